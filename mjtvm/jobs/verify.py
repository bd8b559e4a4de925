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

[`slide_check()`][mjtvm.jobs.slide_check.slide_check] settles the slide direction of the S variant.
"""

from __future__ import annotations

import math
import multiprocessing
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, replace
from functools import partial
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from mjtvm.errors import MjtvmError, ModelError, StateError
from mjtvm.jobs.figures import lift_x
from mjtvm.jobs.replay import grasp_defaults
from mjtvm.jobs.verify_report import plot_alpha, rows_csv, summarize
from mjtvm.lift.states import lift_state
from mjtvm.lift.trajectory import Lift, scripted_lift
from mjtvm.model.friction import cone_margin
from mjtvm.model.limits import with_limit_horizon
from mjtvm.model.state import GraspState
from mjtvm.physics.bisection import alpha_sim, bisect
from mjtvm.physics.dynamic import dynamic_pair
from mjtvm.physics.hold import hold_row, state_hold
from mjtvm.physics.launch import launch_row
from mjtvm.physics.motors import actuator_model, attach_dcmotors, grasp_source, require_motors, same_model
from mjtvm.physics.simulate import SimSettings, inertial_demand, rollout, sim_model
from mjtvm.physics.verdict import verdict
from mjtvm.physics.witness import witness_drive
from mjtvm.problem2.tvmmp import TvmmpResult, tvmmp

_F64 = NDArray[np.float64]

__all__ = [
    "RUNS",
    "alpha_sim",
    "bisect",
    "cached_lift",
    "checked_lift",
    "motor_model",
    "pair_reason",
    "plot_alpha",
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
_MODELS: dict[int, tuple[Any, mujoco.MjModel]] = {}


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


def _scenario(grasp: str | Path) -> Any:
    loaded = _grasp(grasp)
    if isinstance(loaded, str):
        from mjtvm.paper_hand.scenario import load_scenario

        return load_scenario(loaded)
    return loaded


def _grasp(grasp: str | Path) -> Any:
    """A shipped grasp's name as is (``scripted_lift`` loads it); a path loaded as a grasp file."""
    if isinstance(grasp, Path) or str(grasp).endswith((".toml", ".json")):
        from mjtvm.grasp.resolve.file import load_grasp

        return load_grasp(Path(grasp))
    return str(grasp)


def motor_model(grasp: Any) -> mujoco.MjModel:
    r"""The grasp's model with a ``<dcmotor>`` on every state joint, built once per grasp.

    With a transmission: a ``<dcmotor>`` per actuator instead, on the actuator's own
    transmission ([`actuator_motors()`][mjtvm.physics.motors.actuator_motors],
    [`attach_actuator_dcmotors()`][mjtvm.physics.motors.attach_actuator_dcmotors]).

    The model as is when each state joint already has one (``input="vel ff"``); otherwise
    the grasp's ``MjSpec`` (its MJCF file with the object and supports it adds) with the motors
    of ``grasp.motors`` attached
    ([`attach_dcmotors()`][mjtvm.physics.motors.attach_dcmotors]; [`require_motors()`][mjtvm.physics.motors.require_motors]
    refuses joints without motor data, naming them).

    Parameters
    ----------
    grasp
        A [`Grasp`][mjtvm.grasp.resolve.loaded.Grasp] (``model``, ``model_path``, ``joints``, ``motors``).

    Raises
    ------
    ModelError
        A joint or actuator without motor data.
    """
    if id(grasp) in _MODELS:
        return _MODELS[id(grasp)][1]
    _refuse_floating_base(grasp.model, grasp.joints)
    if getattr(grasp, "transmission", None) is not None:
        model = actuator_model(grasp)
        _MODELS[id(grasp)] = (grasp, model)
        return model
    model = grasp.model
    motors = require_motors(model, grasp.joints, getattr(grasp, "motors", {}))
    if motors:
        model = same_model(grasp, attach_dcmotors(grasp_source(grasp), motors))
    _MODELS[id(grasp)] = (grasp, model)  # the grasp is kept so that its id is not reused
    return model


def _refuse_floating_base(model: mujoco.MjModel, joints: Sequence[str]) -> None:
    """A hand on a free joint or a mocap body is refused: the rollouts rebuild the model from
    its file (a mocap pose is lost) and hold no base (a free base falls), so alpha_sim would
    measure another hand."""
    for name in joints:
        body = int(model.jnt_bodyid[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)])
        while body > 0:
            free = any(
                model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE
                for j in range(model.body_jntadr[body], model.body_jntadr[body] + model.body_jntnum[body])
            )
            if free or model.body_mocapid[body] >= 0:
                what = "on a free joint" if free else "a mocap body"
                label = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body)
                raise ModelError(
                    f"body {label!r}",
                    f"the hand's base is {what}: the physics check is for fixed-base hands "
                    "(export-state, solve, tvms and replay support it)",
                )
            body = int(model.body_parentid[body])


def _types(state: Any) -> dict[str, str]:
    return {c.name.split("#")[0]: c.type for c in state.contacts}


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
) -> list[dict[str, Any]]:
    r"""Rows (one per non-zero RVDS vertex) of state ``index`` for ``run`` (one of [`RUNS`][mjtvm.jobs.verify.RUNS]).

    First the hold test ([`hold_test()`][mjtvm.physics.hold.hold_test], ``hold_time`` s, default a
    rollout's length): a state that does not hold at rest gets its verdict and no rollout.
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
        motor_model(lift.scenario), _types(state), mu=mu, mg=mg, settings=settings, object_body=ob
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
    hold = state_hold(
        model, lift.qpos[index], state, res, settings=settings, object_body=ob, duration=hold_time
    )
    for l in range(len(state.rvds if state.rvds is not None else [])):
        status = res.status[0][l]
        row: dict[str, Any] = {**base, "l": l, "status": status, **lp, "reason": pair_reason(res, l)}
        if status == "optimal" and hold is not None:
            row.update(hold_row(hold), alpha_lp=float(res.alpha[0, l]))
        if status == "optimal" and (hold is None or hold.held):
            a_sim, alpha, b = alpha_sim(
                model,
                lift.qpos[index],
                state,
                0,
                l,
                result=res,
                settings=settings,
                witness=witness,  # type: ignore[arg-type]
                object_body=ob,
            )
            top = min(b.value + 0.01, 2.0)
            # The witness drive of pair (0, l) at a scale of alpha: past the bisection, at the
            # check's scale, and at alpha itself for the inertial demand.
            drive = partial(witness_drive, state, 0, l, alpha, witness=witness, vertex=res.witnesses[0][l])  # type: ignore[arg-type]
            fail = rollout(model, lift.qpos[index], drive(top), settings=settings, object_body=ob)
            chk = rollout(model, lift.qpos[index], drive(check_s), settings=settings, object_body=ob)
            one = drive(1.0)
            demand = inertial_demand(model, lift.qpos[index], one, object_body=ob)
            j = int(np.argmax(demand))
            row.update(
                alpha_lp=alpha,
                alpha_sim=a_sim,
                ratio=a_sim / alpha if alpha > 0 else math.nan,
                verdict=verdict(b, fail, actuators=state.transmission is not None),
                evaluations=b.evaluations,
                fail_reason=fail.reason,
                fail_clamp=fail.clamp_fraction,
                pass_check=chk.passed,
                check_reason=chk.reason,
                inertia_max=float(demand[j]),
                inertia_joint=state.joint_names[j],
                settle_drift=chk.settle_drift,
                limit_margin=chk.limit_margin,
                limit_joint=chk.limit_joint,
                limit_reached=chk.limit_reached,
            )
            if launch_distance is not None:
                row.update(launch_row(model, lift.qpos[index], one, launch_distance, settings, ob))
            if dynamics:
                row.update(
                    _dynamic_row(
                        model, lift.qpos[index], state, l, res, alpha, a_sim, witness, settings, ob, check_s
                    )
                )
        rows.append(row)
    return rows


def verify_lp(
    lift: Lift,
    index: int,
    run: str,
    *,
    mu: float,
    mg: float,
    preload: float = 0.0,
    friction_margin: float | None = None,
    limit_horizon: float | None = None,
) -> tuple[GraspState, TvmmpResult | MjtvmError, dict[str, str]]:
    r"""The state [`verify_state()`][mjtvm.jobs.verify.verify_state] checks at lift state ``index`` for ``run``, its Problem 2
    (``alpha_lp``, without a rollout) and the row's ``lp_state`` and ``lp_note``.

    State 0 is the grasp at its own configuration (the lift starts there): with the grasp's
    friction and weight (``mu``, ``mg`` its own), the file's contact types and no
    ``preload``, the state is the one ``mjtvm solve GRASP`` solves and its alphas are solve's
    (``lp_state`` ``grasp``, ``lp_note`` empty). Otherwise ``lp_note`` says what differs from
    solve's state and why: a state further along the lift (``lp_state`` ``lift``), another
    ``mu`` or ``mg`` (``--mu``, ``--mg``), the L contacts' preload (``--preload``), the
    contacts the run retypes, a ``friction_margin`` (the state's, on the rollouts' cone) other
    than the grasp's, a ``limit_horizon`` (``--limit-horizon``) other than the state's. The LP is solved on the initial configuration, never on the
    settled one of the hold test or a rollout (those move the object by at most
    ``hold_reach``).

    Returns
    -------
    state, result, fields
        The grasp state, its [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp] result (with the diagnosis of
        its infeasible pairs and zero alphas), or the error the LP ended in, and
        ``{"lp_state": ..., "lp_note": ...}``.
    """
    variant, _, reading = run.partition("-")
    sc = lift.scenario
    own_mg = getattr(sc, "weight_mg", None)  # the grasp's own weight: its REFS as they are (solve's)
    state = lift_state(
        lift,
        index,
        variant=variant,  # type: ignore[arg-type]
        reading=reading or "physical",  # type: ignore[arg-type]
        mu=mu,
        mg=None if own_mg is not None and mg == own_mg else mg,
    )
    if preload > 0:
        state = state.with_(
            contacts=tuple(replace(c, preload=preload) if c.type == "L" else c for c in state.contacts)
        )
    own_margin = state.friction_margin
    if friction_margin is not None:
        state = state.with_(friction_margin=friction_margin)
    own_limits = state.joint_limits
    state = with_limit_horizon(state, limit_horizon)
    notes = []
    if index > 0 or float(lift.s[index]) != 0.0:
        notes.append(
            f"the lift's state {index} (s = {float(lift.s[index]):.6g} m), not the grasp's configuration"
        )
    if mu != getattr(sc, "default_mu", None):
        notes.append(f"mu {mu:g} (--mu), not the grasp's")
    if mg != own_mg:
        notes.append(f"mg {mg:g} N (--mg), not the grasp's weight")
    if preload > 0:
        notes.append(f"preload {preload:g} N on the L contacts (--preload)")
    if state.friction_margin != own_margin:
        notes.append(
            f"friction margin {state.friction_margin:g} (--friction-margin on the rollouts' cone), "
            f"not the grasp's {own_margin:g}"
        )
    if (
        own_limits is not None
        and state.joint_limits is not None
        and state.joint_limits.horizon != own_limits.horizon
    ):
        notes.append(
            f"joint-limit horizon {state.joint_limits.horizon:g} m (--limit-horizon), "
            f"not the grasp's {own_limits.horizon:g}"
        )
    own = getattr(sc, "contact_types", {})
    retyped = sorted(
        {c.name.split("#")[0] for c in state.contacts if own.get(c.name.split("#")[0], c.type) != c.type}
    )
    if retyped:
        notes.append(f"run {run} types {', '.join(retyped)} {variant}, the grasp file otherwise")
    fields = {"lp_state": "grasp" if index == 0 else "lift", "lp_note": "; ".join(notes)}
    try:
        return state, tvmmp(state, diagnose=True), fields
    except MjtvmError as e:
        return state, e, fields


def pair_reason(res: TvmmpResult, l: int) -> str:
    """Why pair (0, l) is infeasible or its alpha 0 (the diagnosis ``mjtvm solve`` prints)."""
    for d in res.diagnosis:
        if d.pair[0] == 0 and d.pair[1] in (l, -1):
            return d.message
    return ""


def _dynamic_row(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    l: int,
    res: Any,
    alpha: float,
    a_sim: float,
    witness: str,
    settings: SimSettings | None,
    ob: str,
    check_s: float,
) -> dict[str, Any]:
    """The dynamic alpha of pair (0, l), its limit, alpha_sim / alpha_dyn and the check at
    ``check_s`` alpha_dyn (a rollout of the same drive at speed factor check_s alpha_dyn / alpha_kl)."""
    st = settings or SimSettings()  # the demand along the span the rollout checks
    dyn = dynamic_pair(
        model,
        qpos,
        state,
        0,
        l,
        result=res,
        witness=witness,  # type: ignore[arg-type]
        object_body=ob,
        window=st.startup + st.window,
    )
    a = dyn.alpha
    out: dict[str, Any] = {
        "alpha_dyn": a,
        "ratio_dyn": a_sim / a if a > 0 else math.nan,
        "dyn_joint": _limit_names(state)[dyn.joint] if dyn.joint is not None else "",
        "dyn_term": dyn.term,
        "dyn_demand": float(np.max(np.abs(dyn.demand))),
        "dyn_lps": dyn.lps,
    }
    if a > 0:
        s = check_s * a / alpha
        chk = rollout(
            model,
            qpos,
            witness_drive(
                state,
                0,
                l,
                alpha,
                s,
                witness=witness,  # type: ignore[arg-type]
                vertex=res.witnesses[0][l],
            ),
            settings=settings,
            object_body=ob,
        )
        out.update(pass_check_dyn=chk.passed, check_dyn_reason=chk.reason)
    return out


def _limit_names(state: GraspState) -> tuple[str, ...]:
    """What the operation ranges bound: the actuators with a transmission, else the joints."""
    t = state.transmission
    return state.joint_names if t is None else t.actuator_names


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
        the grasp's motors attached ([`motor_model()`][mjtvm.jobs.verify.motor_model]).
    stride
        Check every ``stride``-th state (the last state is always included).
    runs
        Subset of [`RUNS`][mjtvm.jobs.verify.RUNS].
    dynamics, preload, hold_time, launch_distance, friction_margin, limit_horizon
        As in [`verify_state()`][mjtvm.jobs.verify.verify_state].
    jobs, start_method
        Worker processes (1: in this process) and their start method.
    out, name
        Directory of ``<name>.csv`` and ``<name>.png`` (``None``: write nothing).
    """
    if stride < 1 or jobs < 1 or any(r not in RUNS for r in runs):
        raise StateError("verify", f"expected stride >= 1, jobs >= 1, runs among {RUNS}")
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
            files[outdir / f"{name}.png"] = plot_alpha(rows, f"{grasp}: $\\mu$ = {mu:g}, $mg$ = {mg:g} N")
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
