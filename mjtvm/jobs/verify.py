r"""Physics check of the TVMMP along the lift: alpha_sim (MuJoCo rollouts) against alpha_kl (LP).

[`verify_lift()`][mjtvm.jobs.verify.verify_lift] runs, for every sampled state of the scripted lift
([`scripted_lift()`][mjtvm.lift.trajectory.scripted_lift]), every hand variant / reading and every RVDS vertex
l, the bisection of [`alpha_sim()`][mjtvm.physics.bisection.alpha_sim] (REFS: the weight, k = 0), one rollout
at s = 0.9 and the inertial torque the quasi-static LP leaves out
([`inertial_demand()`][mjtvm.physics.simulate.inertial_demand] at s = 1). With ``dynamics`` it adds the
dynamic alpha ([`dynamic_pair()`][mjtvm.physics.dynamic.dynamic_pair]: eq. 31 with the witness motion's
$M\ddot q + c$ in the torque budget), its limiting joint and term, alpha_sim / alpha_dyn
and one rollout at s = 0.9 alpha_dyn. Rows go to ``verify.csv``, the curves
(TVMMP, the dynamic TVMMP and the simulated minimum along z) to ``verify.png``. States run in parallel with
``jobs`` processes (``ProcessPoolExecutor``, ``forkserver`` or ``spawn`` start).

The rollouts of one pair are [`pair_check()`][mjtvm.physics.check.pair_check] (MuJoCo stays in
the physics room), the state and its LP [`verify_lp()`][mjtvm.jobs.verify_lp.verify_lp], the CSV
and plot [`mjtvm.jobs.verify_report`][mjtvm.jobs.verify_report].
[`slide_check()`][mjtvm.jobs.slide_check.slide_check] settles the slide direction of the S variant.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict
from pathlib import Path
from typing import Any

from tqdm import tqdm

from mjtvm.errors import MjtvmError, StateError
from mjtvm.jobs.figures import lift_x
from mjtvm.jobs.replay import grasp_defaults
from mjtvm.jobs.verify_lp import pair_reason, verify_lp
from mjtvm.jobs.verify_report import plot_alpha, rows_csv, summarize
from mjtvm.lift.trajectory import Lift, scripted_lift
from mjtvm.model.friction import cone_margin
from mjtvm.physics.bisection import alpha_sim, bisect
from mjtvm.physics.check import contact_types, motor_model, pair_check
from mjtvm.physics.hold import hold_row
from mjtvm.physics.hold_drive import HOLD_DRIVES, check_hold
from mjtvm.physics.simulate import SimSettings, sim_model

__all__ = [
    "RUNS",
    "alpha_sim",
    "bisect",
    "cached_lift",
    "checked_lift",
    "motor_model",
    "pair_reason",
    "plot_alpha",
    "plot_title",
    "present_runs",
    "rows_csv",
    "runs_of",
    "state_indices",
    "summarize",
    "verify_lift",
    "verify_lp",
    "verify_state",
]

RUNS = ("L", "S-physical", "S-literal")
"""Hand variants checked: fingers 2 and 4 as L-points, or as S-points of either reading."""
_LIFTS: dict[tuple[str, int], Lift] = {}


def cached_lift(grasp: str | Path, num_states: int) -> Lift:
    """The scripted lift of ``grasp`` (a shipped grasp's name or a grasp file's path) with
    ``num_states`` states, built once per process."""
    key = (str(grasp), num_states)
    if key not in _LIFTS:
        _LIFTS[key] = scripted_lift(_grasp(grasp), num_states=num_states)
    return _LIFTS[key]


def checked_lift(grasp: str | Path, num_states: int) -> Lift:
    """The lift the check runs: [`cached_lift()`][mjtvm.jobs.verify.cached_lift], or the grasp's own state alone when its
    file has no ``[lift]`` (there is no motion to sample)."""
    one = getattr(_scenario(grasp), "lift", ...) is None
    return cached_lift(grasp, 1 if one else num_states)


def present_runs(lift: Lift, runs: Sequence[str]) -> list[str]:
    """The ``runs`` that differ on this lift: without an L/S finger (every finger an F-point)
    the variants are the same grasp, checked once as ``L``; without a ``[lift]`` there is no
    motion to give an S-point's slide direction, so ``L`` only."""
    if "N" not in lift.roles or getattr(lift.scenario, "lift", ...) is None:
        return ["L"]
    return list(runs)


def plot_title(grasp: str | Path, mu: float, mg: float) -> str:
    """The title of ``verify.png``: the grasp's ``name`` (not its file's path), mu and the weight."""
    name = getattr(_scenario(grasp), "name", None) or Path(str(grasp)).stem
    return f"{name}, $\\mu$ = {mu:g}, $mg$ = {mg:g} N"


def _scenario(grasp: str | Path) -> Any:
    loaded = _grasp(grasp)
    if isinstance(loaded, str):
        from mjtvm.grasp import load_grasp

        return load_grasp(loaded)
    return loaded


def _grasp(grasp: str | Path) -> Any:
    """A shipped grasp's name as is (``scripted_lift`` loads it); a path loaded as a grasp file."""
    if isinstance(grasp, Path) or str(grasp).endswith((".toml", ".json")):
        from mjtvm.grasp.resolve.file import load_grasp

        return load_grasp(Path(grasp))
    return str(grasp)


def verify_state(
    lift: Lift,
    index: int,
    run: str,
    *,
    mu: float = 0.3,
    mg: float = 1.0,
    settings: SimSettings | None = None,
    witness: str = "central",
    check_s: float = 0.9,
    dynamics: bool = False,
    preload: float = 0.0,
    hold_time: float | None = None,
    launch_distance: float | None = None,
    friction_margin: float | None = None,
    limit_horizon: float | None = None,
    hold_drive: str = "auto",
) -> list[dict[str, Any]]:
    r"""Rows (one per non-zero RVDS vertex) of state ``index`` for ``run`` (one of [`RUNS`][mjtvm.jobs.verify.RUNS]).

    First the hold test ([`hold_test()`][mjtvm.physics.hold.hold_test], ``hold_time`` s, default a
    rollout's length): a state that does not hold at rest gets its verdict and no rollout.
    ``hold_drive``: ``auto``, ``least`` or ``squeeze`` ([`check_hold()`][mjtvm.physics.hold_drive.check_hold]):
    the drive that holds the state in the hold test and in every rollout (the row's ``hold_drive``).
    ``launch_distance`` (m): also the launch from rest of every pair
    ([`launch()`][mjtvm.physics.launch.launch]).

    ``dynamics``: also the dynamic alpha and its check (module docstring). ``preload`` (N): the
    minimum normal force of every L contact (``mjtvm.state/1``'s contact ``preload``), which the
    witnesses then press on the object. ``friction_margin``: the margin delta of the LPs whose
    witness is driven (default the grasp file's, 0), on the rollouts' cone
    ([`cone_margin()`][mjtvm.model.friction.cone_margin]: pyramidal adds 1/sqrt(2)). ``limit_horizon``:
    the LPs' travel horizon of the joint limits (m; default the grasp file's).
    """
    delta = lift_margin(lift) if friction_margin is None else friction_margin
    margin = cone_margin((settings or SimSettings()).cone, delta)
    state, res, lp = verify_lp(
        lift, index, run, mu=mu, mg=mg, preload=preload, friction_margin=margin, limit_horizon=limit_horizon
    )
    ob = lift.scenario.object_body
    model = sim_model(
        motor_model(lift.scenario), contact_types(state), mu=mu, mg=mg, settings=settings, object_body=ob
    )
    base = {
        "run": run,
        "state": index,
        "z": float(lift.z[index]),
        "s": float(lift.s[index]),
        "x": float(getattr(lift, lift_x(lift))[index]),
        "mu": mu,
        "mg": mg,
        "friction_margin": state.friction_margin,
    }
    if isinstance(res, MjtvmError):
        return [{**base, "l": -1, "status": f"solver: {res}", **lp}]
    rows = []
    hold, used = check_hold(
        model,
        lift.qpos[index],
        state,
        res,
        hold_drive=hold_drive,  # type: ignore[arg-type]
        settings=settings,
        object_body=ob,
        duration=hold_time,
    )
    for l in range(len(state.rvds if state.rvds is not None else [])):
        status = res.status[0][l]
        row: dict[str, Any] = {**base, "l": l, "status": status, **lp, "reason": pair_reason(res, l)}
        if status == "optimal" and hold is not None:
            row.update(hold_row(hold), hold_drive=used, alpha_lp=float(res.alpha[0, l]))
        if status == "optimal" and (hold is None or hold.held):
            row.update(
                pair_check(
                    model,
                    lift.qpos[index],
                    state,
                    res,
                    l,
                    settings=settings,
                    witness=witness,
                    object_body=ob,
                    check_s=check_s,
                    dynamics=dynamics,
                    launch_distance=launch_distance,
                    squeeze=used == "squeeze",
                )
            )
        rows.append(row)
    return rows


def _task(args: tuple[str, int, int, str, dict[str, Any]]) -> list[dict[str, Any]]:
    grasp, num_states, index, run, opts = args
    opts = dict(opts)
    opts["settings"] = SimSettings(**opts["settings"])
    return verify_state(cached_lift(grasp, num_states), index, run, **opts)


def verify_lift(
    grasp: str | Path = "case2",
    *,
    num_states: int = 30,
    stride: int = 1,
    runs: Sequence[str] = RUNS,
    mu: float | None = None,
    mg: float | None = None,
    settings: SimSettings | None = None,
    witness: str = "central",
    dynamics: bool = False,
    preload: float = 0.0,
    hold_time: float | None = None,
    launch_distance: float | None = None,
    friction_margin: float | None = None,
    limit_horizon: float | None = None,
    hold_drive: str = "auto",
    jobs: int = 1,
    start_method: str = "forkserver",
    out: str | Path | None = "results",
    name: str = "verify",
    progress: bool = True,
    plot: bool = True,
) -> list[dict[str, Any]]:
    r"""alpha_sim against alpha_kl along the lift (module docstring); returns the CSV rows.

    Parameters
    ----------
    grasp
        A shipped grasp's name (``case2``, ...) or a grasp file's path (``mjtvm.grasp/1``).
        Its model is simulated as is when every state joint has a ``<dcmotor>``, else with
        the grasp's motors attached ([`motor_model()`][mjtvm.physics.check.motor_model]).
    stride
        Check every ``stride``-th state (the last state is always included).
    runs
        Subset of [`RUNS`][mjtvm.jobs.verify.RUNS].
    dynamics, preload, hold_time, launch_distance, friction_margin, limit_horizon, hold_drive
        As in [`verify_state()`][mjtvm.jobs.verify.verify_state].
    jobs, start_method
        Worker processes (1: in this process) and their start method.
    out, name
        Directory of ``<name>.csv`` and ``<name>.png`` (``None``: write nothing).
    """
    if stride < 1 or jobs < 1 or any(r not in RUNS for r in runs):
        raise StateError("verify", f"expected stride >= 1, jobs >= 1, runs among {RUNS}")
    if hold_drive not in HOLD_DRIVES:
        raise StateError("hold_drive", f"expected one of {HOLD_DRIVES}, got {hold_drive!r}")
    if start_method not in ("forkserver", "spawn"):
        raise StateError("start_method", f"expected 'forkserver' or 'spawn', got {start_method!r}")
    if out is not None:  # before any work
        from mjtvm.formats.files import check_output_dir

        check_output_dir(out, option="out")
    st = settings or SimSettings()
    lift = checked_lift(grasp, num_states)
    num_states, runs = lift.num_states, present_runs(lift, runs)
    indices = state_indices(num_states, stride)
    mu, mg = grasp_defaults(lift.scenario, mu, mg)
    opts = {
        "mu": mu,
        "mg": mg,
        "settings": asdict(st),
        "witness": witness,
        "dynamics": dynamics,
        "preload": preload,
        "hold_time": hold_time,
        "launch_distance": launch_distance,
        "friction_margin": friction_margin,
        "limit_horizon": limit_horizon,
        "hold_drive": hold_drive,
    }
    if jobs > 1:  # refuse a grasp without motor data here, not in every worker
        motor_model(lift.scenario)
    tasks = [(str(grasp), num_states, i, r, opts) for r in runs for i in indices]
    rows: list[dict[str, Any]] = []
    bar = tqdm(
        total=len(tasks), desc=f"verify ({jobs} job{'s' * (jobs > 1)})", unit="state", disable=not progress
    )
    if jobs == 1:
        for t in tasks:
            rows += _task(t)
            bar.update()
    else:
        from mjtvm.jobs.pool import init_worker, stop  # Ctrl-C: the parent alone reports it

        ctx = multiprocessing.get_context(start_method)
        pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=init_worker)
        try:
            for fut in as_completed([pool.submit(_task, t) for t in tasks]):
                rows += fut.result()
                bar.update()
        except BaseException:
            stop(pool)
            raise
        pool.shutdown()
    bar.close()
    rows.sort(key=lambda r: (RUNS.index(r["run"]), r["state"], r["l"]))
    if out is not None:
        from mjtvm.formats.files import check_output_dir, write_files

        outdir = check_output_dir(out, option="out")
        files: dict[Path, bytes | str] = {outdir / f"{name}.csv": rows_csv(rows)}
        if plot:
            files[outdir / f"{name}.png"] = plot_alpha(rows, plot_title(grasp, mu, mg))
        write_files(files, option="out")
    return rows


def lift_margin(lift: Lift) -> float:
    """The grasp file's ``friction_margin`` delta (before its ``cone``; 0 without one)."""
    document = getattr(lift.scenario, "document", None) or {}
    return float(document.get("friction_margin", 0.0))


def state_indices(num_states: int, stride: int) -> list[int]:
    """Every ``stride``-th state of the lift, and the last."""
    return sorted({*range(0, num_states, stride), num_states - 1})


# --------------------------------------------------------------- slide check
def runs_of(contacts: Sequence[str], readings: Sequence[str]) -> list[str]:
    """The [`RUNS`][mjtvm.jobs.verify.RUNS] of contact types (``L``, ``S``) and readings: L once, S once per reading."""
    return [r for r in RUNS if r.split("-")[0] in contacts and (r == "L" or r.split("-")[1] in readings)]
