r"""Physics check of the TVMMP along the lift: alpha_sim (MuJoCo rollouts) against alpha_kl (LP).

:func:`verify_lift` runs, for every sampled state of the scripted lift
(:func:`~mjtvm.sim.trajectory.scripted_lift`), every hand variant / reading and every RVDS vertex
l, the bisection of :func:`~mjtvm.physics.verify.alpha_sim` (REFS: the weight, k = 0), one rollout
at s = 0.9 and the inertial torque the quasi-static LP leaves out
(:func:`~mjtvm.physics.simulate.inertial_demand` at s = 1). Rows go to ``verify.csv``, the curves
(TVMMP and the simulated minimum along z) to ``verify.png``. States run in parallel with
``jobs`` processes (``ProcessPoolExecutor``, ``forkserver`` or ``spawn`` start).

:func:`slide_check` settles the slide-direction ambiguity of the S variant: fingers 2 and 4,
frictional (mu), are driven with the paper's minimum-norm lift motion (their slip is then the
one that motion produces), or made to out-run the object (the slip of the literal reading),
or left frictionless (control); it reports the direction of MuJoCo's friction force.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import multiprocessing
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ..core.state import GraspState
from ..core.tvmmp import tvmmp
from ..errors import MjtvmError, StateError
from ..sim.trajectory import Lift, lift_state, scripted_lift
from .simulate import SimSettings, inertial_demand, rollout, sim_model
from .witness import WitnessKind, witness_drive

_F64 = NDArray[np.float64]

__all__ = ["RUNS", "add_arguments", "run", "slide_check", "summarize", "verify_lift", "verify_state"]

RUNS = ("L", "S-physical", "S-literal")
"""Hand variants checked: fingers 2 and 4 as L-points, or as S-points of either reading."""
_LIFTS: dict[tuple[str, int], Lift] = {}


def _lift(scenario: str, num_states: int) -> Lift:
    key = (scenario, num_states)
    if key not in _LIFTS:
        _LIFTS[key] = scripted_lift(scenario, num_states=num_states)
    return _LIFTS[key]


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
) -> list[dict[str, Any]]:
    r"""Rows (one per non-zero RVDS vertex) of state ``index`` for ``run`` (one of :data:`RUNS`)."""
    variant, _, reading = run.partition("-")
    state = lift_state(lift, index, variant=variant, reading=reading or "physical", mu=mu, mg=mg)  # type: ignore[arg-type]
    model = sim_model(lift.scenario.model, _types(state), mu=mu, mg=mg, settings=settings)
    base = {"run": run, "state": index, "z": float(lift.z[index]), "mu": mu, "mg": mg}
    try:
        res = tvmmp(state)
    except MjtvmError as e:
        return [{**base, "l": -1, "status": f"solver: {e}"}]
    rows = []
    for l in range(len(state.rvds if state.rvds is not None else [])):
        status = res.status[0][l]
        row: dict[str, Any] = {**base, "l": l, "status": status}
        if status == "optimal":
            a_sim, alpha, b = alpha_sim(model, lift.qpos[index], state, 0, l, result=res, settings=settings,
                                        witness=witness)  # type: ignore[arg-type]  # fmt: skip
            top = min(b.value + 0.01, 2.0)
            fail = rollout(model, lift.qpos[index], witness_drive(state, 0, l, alpha, top, witness=witness,  # type: ignore[arg-type]
                           vertex=res.witnesses[0][l]), settings=settings)  # fmt: skip
            chk = rollout(model, lift.qpos[index], witness_drive(state, 0, l, alpha, check_s, witness=witness,  # type: ignore[arg-type]
                          vertex=res.witnesses[0][l]), settings=settings)  # fmt: skip
            one = witness_drive(state, 0, l, alpha, 1.0, witness=witness, vertex=res.witnesses[0][l])  # type: ignore[arg-type]
            demand = inertial_demand(model, lift.qpos[index], one)
            j = int(np.argmax(demand))
            row.update(alpha_lp=alpha, alpha_sim=a_sim, ratio=a_sim / alpha if alpha > 0 else math.nan,
                       censored=b.above_bracket or b.below_bracket, evaluations=b.evaluations,
                       fail_reason=fail.reason, fail_clamp=fail.clamp_fraction, pass_check=chk.passed,
                       check_reason=chk.reason, inertia_max=float(demand[j]), inertia_joint=state.joint_names[j],
                       settle_drift=chk.settle_drift)  # fmt: skip
        rows.append(row)
    return rows


def _task(args: tuple[str, int, int, str, dict[str, Any]]) -> list[dict[str, Any]]:
    scenario, num_states, index, run, opts = args
    opts = dict(opts)
    opts["settings"] = SimSettings(**opts["settings"])
    return verify_state(_lift(scenario, num_states), index, run, **opts)


def verify_lift(
    scenario: str = "case2",
    *,
    num_states: int = 30,
    stride: int = 1,
    runs: Sequence[str] = RUNS,
    mu: float = 0.3,
    mg: float = 1.0,
    settings: SimSettings | None = None,
    witness: str = "central",
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
    stride
        Check every ``stride``-th state (the last state is always included).
    runs
        Subset of :data:`RUNS`.
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
        from ..core.files import check_output_dir

        check_output_dir(out, option="out")
    st = settings or SimSettings()
    indices = sorted({*range(0, num_states, stride), num_states - 1})
    opts = {"mu": mu, "mg": mg, "settings": asdict(st), "witness": witness}
    tasks = [(scenario, num_states, i, r, opts) for r in runs for i in indices]
    rows: list[dict[str, Any]] = []
    bar = tqdm(
        total=len(tasks), desc=f"verify ({jobs} job{'s' * (jobs > 1)})", unit="state", disable=not progress
    )
    if jobs == 1:
        for t in tasks:
            rows += _task(t)
            bar.update()
    else:
        from ..apps.sweep import _ignore_sigint, _stop  # Ctrl-C: the parent alone reports it

        ctx = multiprocessing.get_context(start_method)
        pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_ignore_sigint)
        try:
            for fut in as_completed([pool.submit(_task, t) for t in tasks]):
                rows += fut.result()
                bar.update()
        except BaseException:
            _stop(pool)
            raise
        pool.shutdown()
    bar.close()
    rows.sort(key=lambda r: (RUNS.index(r["run"]), r["state"], r["l"]))
    if out is not None:
        from ..core.files import check_output_dir, write_files

        outdir = check_output_dir(out, option="out")
        files: dict[Path, bytes | str] = {outdir / f"{name}.csv": _csv(rows)}
        if plot:
            files[outdir / f"{name}.png"] = _plot(rows, f"{scenario}: $\\mu$ = {mu:g}, $mg$ = {mg:g} N")
        write_files(files, option="out")
    return rows


def _csv(rows: Sequence[dict[str, Any]]) -> str:
    cols = list(dict.fromkeys(k for r in rows for k in r))
    buf = io.StringIO(newline="")
    w = csv.DictWriter(buf, fieldnames=cols)
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    return buf.getvalue()


def _minima(rows: Sequence[dict[str, Any]], run: str, key: str) -> tuple[np.ndarray, np.ndarray]:
    by: dict[float, list[float]] = {}
    for r in rows:
        if r["run"] == run:
            by.setdefault(r["z"], []).append(r.get(key, math.nan) if r["status"] == "optimal" else math.nan)
    z = np.array(sorted(by))
    return z, np.array([min(by[k]) if not any(math.isnan(v) for v in by[k]) else math.nan for k in z])


def _plot(rows: Sequence[dict[str, Any]], title: str) -> bytes:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.5, 4.2), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for run in dict.fromkeys(r["run"] for r in rows):
        z, lp = _minima(rows, run, "alpha_lp")
        (line,) = ax.plot(z, lp, "-", label=f"TVMMP (LP), {run}")
        z, sim = _minima(rows, run, "alpha_sim")
        ax.plot(
            z, sim, "o--", color=line.get_color(), ms=4, label=f"min $\\alpha_{{\\mathrm{{sim}}}}$, {run}"
        )
    ax.set_xlabel("object height $z$ (m)")
    ax.set_ylabel(r"$\alpha$ (m/s per unit of RVDS vertex $\hat r_l$)", fontsize=8)
    ax.set_title(title, fontsize=9)
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120)
    return buf.getvalue()


def summarize(rows: Sequence[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    r"""Per run: count, median and quartiles of alpha_sim / alpha_kl, the 3 worst pairs, s = 0.9 failures."""
    out: dict[str, dict[str, Any]] = {}
    for run in dict.fromkeys(r["run"] for r in rows):
        ok = [r for r in rows if r["run"] == run and r["status"] == "optimal"]
        if not ok:
            out[run] = {"pairs": 0}
            continue
        ratios = sorted(r["ratio"] for r in ok)
        q = statistics.quantiles(ratios, n=4) if len(ratios) > 1 else [ratios[0]] * 3
        worst = sorted(ok, key=lambda r: r["ratio"])[:3]
        out[run] = {"pairs": len(ok), "states": len({r["state"] for r in ok}), "median": statistics.median(ratios),
                    "q1": q[0], "q3": q[2], "min": ratios[0], "max": ratios[-1],
                    "worst": [(r["state"], r["l"], round(r["ratio"], 3), r["fail_reason"]) for r in worst],
                    "fail_at_check": sum(not r["pass_check"] for r in ok),
                    "censored": sum(bool(r["censored"]) for r in ok)}  # fmt: skip
    return out


# --------------------------------------------------------------- slide check
def slide_check(
    lift: Lift,
    indices: Sequence[int],
    *,
    speed: float = 0.2,
    mu: float = 0.3,
    mg: float = 1.0,
    settings: SimSettings | None = None,
) -> list[dict[str, Any]]:
    r"""Friction direction at fingers 2 and 4 while they slide during the lift (module docstring).

    The object is lifted along +z at ``speed`` (m/s; at most half the LP's alpha along +z);
    fingers 1 and 3 stick (F, mu). Modes: ``physical`` (fingers 2 and 4 frictional, the
    paper's minimum-norm motion, so they slip as that motion makes them), ``literal``
    (frictional, driven to slip against that direction at the same slip speed: they out-run
    the object) and ``frictionless`` (L-points, control). Feedforward: the central solution
    (:func:`~mjtvm.physics.witness.central_witness`) of the mode's LP (S-points of that reading;
    L-points for the control) for the twist ``speed e_z``, or of the L-point LP where the
    reading's LP has none (``ff`` column). Per S geom: ``cos`` of MuJoCo's mean tangential
    friction force on the object and of the measured slip with the physical slide direction
    :math:`\hat p` (eq. 13), the friction force's z component (N) and the twist errors.
    """
    ez = np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0]])
    rows = []
    for i in indices:
        states = {m: lift_state(lift, i, variant=v, reading=r, mu=mu, mg=mg).with_(rvds=ez)  # type: ignore[arg-type]
                  for m, v, r in (("physical", "S", "physical"), ("literal", "S", "literal"),
                                  ("frictionless", "L", "physical"))}  # fmt: skip
        hats = {c.name.split("#")[0]: np.asarray(c.slide_direction) for c in states["physical"].contacts
                if c.type == "S"}  # fmt: skip
        alpha_l = float(tvmmp(states["frictionless"], witnesses=False).alpha[0, 0])
        v = min(speed, 0.5 * alpha_l)
        slip = {g: float(np.linalg.norm(s)) * v for g, s in zip(lift.geoms, lift.slips[i]) if g in hats}
        for mode, state in states.items():
            res_lp = tvmmp(state, witnesses=False)
            ok = res_lp.status[0][0] == "optimal" and float(res_lp.alpha[0, 0]) >= v
            drive = witness_drive(state if ok else states["frictionless"], 0, 0, v, 1.0)
            kinds = {g: ("S" if mode == "literal" else "L") for g in hats}
            drive = replace(drive, contacts=tuple((g, kinds.get(g, k)) for g, k in drive.contacts),
                            slips={g: (slip[g] if mode == "literal" else 0.0, -h if mode == "literal" else h)
                                   for g, h in hats.items()})  # fmt: skip
            model = sim_model(lift.scenario.model, _types(state), mu=mu, mg=mg, settings=settings)
            res = rollout(model, lift.qpos[i], drive, settings=settings)
            for g, hat in hats.items():
                force, sl = res.friction[g]
                rows.append({"state": i, "z": float(lift.z[i]), "mode": mode, "ff": mode if ok else "L",
                             "geom": g, "speed": v, "slip_speed": slip[g], "friction_cos_phys": _cos(force, hat),
                             "friction_z": float(force[2]), "friction_t": float(np.linalg.norm(force)),
                             "slip_cos_phys": _cos(sl, hat), "slip_measured": float(np.linalg.norm(sl)),
                             "speed_error": res.speed_error, "angle_error": res.angle_error,
                             "passed": res.passed, "reason": res.reason})  # fmt: skip
    return rows


def _cos(a: np.ndarray, b: np.ndarray) -> float:
    na = float(np.linalg.norm(a))
    return float(a @ b) / na if na > 1e-9 else math.nan


# ------------------------------------------------------------------- command
def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``mjtvm verify`` (also ``scripts/verify.py``); the vocabulary of ``docs/cli.md``."""
    from ..cli import READINGS as readings
    from ..cli import choices, deprecated_alias, folder, integer, number, stem

    p.add_argument("--scenario", default="case2", help="scenario name or path of a scenario JSON file")
    p.add_argument(
        "--states", type=integer(2), default=30, metavar="N", help="number of states along the lift"
    )
    p.add_argument(
        "--stride", type=integer(1), default=1, metavar="N", help="check every N-th state (and the last)"
    )
    p.add_argument("--contacts", type=choices(("L", "S")), default="L,S", metavar="L,S",
                   help="contact types of fingers 2 and 4 to check")  # fmt: skip
    p.add_argument("--reading", type=choices(readings, every="both"), default="both", metavar="READING",
                   help="slide directions of the S-points: physical, literal or both")  # fmt: skip
    p.add_argument("--runs", action=_RunsAlias, type=_runs, help=argparse.SUPPRESS, default=argparse.SUPPRESS)
    p.add_argument("--mu", type=number(0.0), default=0.3, help="friction coefficient")
    p.add_argument("--mg", type=number(0.0), default=1.0, help="object weight (N)")
    p.add_argument("--jobs", type=integer(1), default=1, help="worker processes")
    p.add_argument("--start-method", default="forkserver", choices=("forkserver", "spawn"),
                   help="how worker processes start")  # fmt: skip
    p.add_argument("--witness", default="central", choices=("central", "vertex"),
                   help="drive the central solution of the LP or the simplex vertex")  # fmt: skip
    p.add_argument("--armature-scale", type=number(0.0, strict=True), default=1.0,
                   help="ablation: scale the rotor inertia (armature)")  # fmt: skip
    p.add_argument("--window", type=number(0.0, strict=True), default=SimSettings.window,
                   help="measurement window of a rollout (s)")  # fmt: skip
    p.add_argument("--startup", type=number(0.0), default=SimSettings.startup,
                   help="settling time before the window (s)")  # fmt: skip
    p.add_argument("--cone", default="elliptic", choices=("elliptic", "pyramidal"),
                   help="MuJoCo friction cone")  # fmt: skip
    p.add_argument("--no-track", action="store_true", help="constant joint-speed setpoints (no tracking)")
    p.add_argument("--slide-check", action="store_true", help="also run the slide-direction check")
    p.add_argument("--out", type=folder, default="results", metavar="DIR",
                   help="output folder (created if missing; locked while the run writes)")  # fmt: skip
    p.add_argument("--name", type=stem, default="verify", help="file stem of the CSV and PNG in --out")
    new = p.add_argument("--no-plots", action="store_true", help="do not write the PNG plot")
    deprecated_alias(p, "--no-plot", new)
    p.add_argument("--rrd", default=None, metavar="FILE", help="also write a rerun recording of the results")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def _runs(text: str) -> tuple[str, ...]:
    runs = tuple(r.strip() for r in text.split(","))
    if not text.strip() or len(set(runs)) != len(runs) or any(r not in RUNS for r in runs):
        raise argparse.ArgumentTypeError(f"expected distinct values among {','.join(RUNS)}, got {text!r}")
    return runs


class _RunsAlias(argparse.Action):
    """The old ``--runs L,S-literal``: deprecated, the same as ``--contacts L,S --reading literal``."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:  # fmt: skip
        print(f"mjtvm: {option_string} is deprecated, use --contacts and --reading", file=sys.stderr)
        namespace.contacts = tuple(dict.fromkeys(r.split("-")[0] for r in values))
        readings = tuple(r.split("-")[1] for r in values if "-" in r)
        namespace.reading = readings or namespace.reading


def runs_of(contacts: Sequence[str], readings: Sequence[str]) -> list[str]:
    """The :data:`RUNS` of ``--contacts`` and ``--reading``: L once, S once per reading."""
    return [r for r in RUNS if r.split("-")[0] in contacts and (r == "L" or r.split("-")[1] in readings)]


def run(args: argparse.Namespace) -> int:
    """Run ``mjtvm verify`` with parsed :func:`add_arguments` options; print the summary.

    The output folder is checked and locked before any work; the CSV, PNG and the slide
    check's CSV are written together, atomically, at the end (:mod:`mjtvm.core.files`).
    """
    from ..core.files import check_output_dir, output_lock, write_files

    settings = SimSettings(armature_scale=args.armature_scale, window=args.window, startup=args.startup,
                           cone=args.cone, track=not args.no_track)  # fmt: skip
    outdir = check_output_dir(args.out)
    if args.rrd is not None:
        check_output_dir(Path(args.rrd).parent, option="--rrd")
    with output_lock(outdir):
        t0 = time.perf_counter()
        rows = verify_lift(
            args.scenario, num_states=args.states, stride=args.stride, runs=runs_of(args.contacts, args.reading),
            mu=args.mu, mg=args.mg, settings=settings, witness=args.witness, jobs=args.jobs,
            start_method=args.start_method, out=None, progress=not args.quiet,
        )  # fmt: skip
        wall = time.perf_counter() - t0
        files: dict[Path, bytes | str] = {outdir / f"{args.name}.csv": _csv(rows)}
        if not args.no_plots:
            files[outdir / f"{args.name}.png"] = _plot(
                rows, f"{args.scenario}: $\\mu$ = {args.mu:g}, $mg$ = {args.mg:g} N"
            )
        srows: list[dict[str, Any]] = []
        if args.slide_check:
            lift = _lift(args.scenario, args.states)
            idx = sorted({*range(0, args.states, args.stride), args.states - 1})
            srows = slide_check(lift, idx, mu=args.mu, mg=args.mg, settings=settings)
            files[outdir / "slide-check.csv"] = _csv(srows)
        write_files(files)
    for run_name, s in summarize(rows).items():
        print(
            f"{run_name}: "
            + ", ".join(f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}" for k, v in s.items())
        )
    print(f"wall time {wall:.1f} s ({args.jobs} job(s)); rows in {outdir / (args.name + '.csv')}")
    if args.slide_check:
        for mode in ("physical", "literal", "frictionless"):
            sel = [r for r in srows if r["mode"] == mode]
            fc = [r["friction_cos_phys"] for r in sel if not math.isnan(r["friction_cos_phys"])]
            print(f"slide check {mode}: friction cos with physical slide direction: median "
                  f"{statistics.median(fc) if fc else math.nan:.3f}; passed {sum(r['passed'] for r in sel) // 2}"
                  f"/{len(sel) // 2} states")  # fmt: skip
    if args.rrd is not None:
        from ..viewer.viz import record_verify  # rerun is imported only here

        record_verify(rows, args.rrd)
        print(f"wrote {args.rrd}")
    return 0


# ----------------------------------------------------------------- bisection
@dataclass(frozen=True)
class Bisection:
    """Largest passing value found, and whether it sits at a bracket end (censored)."""

    value: float
    below_bracket: bool
    above_bracket: bool
    evaluations: int


def bisect(
    passes: Callable[[float], bool], lo: float = 0.0, hi: float = 2.0, *, tol: float = 0.01
) -> Bisection:
    r"""Largest ``x`` in ``[lo, hi]`` with ``passes(x)``, assuming pass below / fail above a threshold.

    Returns ``lo`` (``below_bracket``) if ``passes(lo)`` is False and ``hi``
    (``above_bracket``) if ``passes(hi)`` is True; otherwise the last passing midpoint,
    within ``tol`` of the threshold.
    """
    if not (lo < hi and tol > 0):
        raise StateError("bracket", f"expected lo < hi and tol > 0, got {lo}, {hi}, {tol}")
    if passes(hi):
        return Bisection(hi, False, True, 1)
    if not passes(lo):
        return Bisection(lo, True, False, 2)
    count = 2
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        count += 1
        lo, hi = (mid, hi) if passes(mid) else (lo, mid)
    return Bisection(lo, False, False, count)


def alpha_sim(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    k: int,
    l: int,
    *,
    result: Any = None,
    settings: SimSettings | None = None,
    witness: WitnessKind = "central",
    bracket: tuple[float, float] = (0.0, 2.0),
    tol: float = 0.01,
) -> tuple[float, float, Bisection]:
    r"""alpha_sim of pair (k, l): :math:`s^* \alpha_{kl}`, s* by :func:`bisect` on rollouts.

    ``model`` from :func:`sim_model`; ``result``: the state's
    :class:`~mjtvm.core.tvmmp.TvmmpResult` (solved here when omitted). Returns
    ``(alpha_sim, alpha_kl, bisection)``.

    Raises
    ------
    StateError
        The pair is not optimal in the LP (no witness).
    """
    res = tvmmp(state) if result is None else result
    if res.status[k][l] != "optimal":
        raise StateError("pair", f"pair ({k}, {l}) is {res.status[k][l]}: no witness to simulate")
    alpha, vertex = float(res.alpha[k, l]), res.witnesses[k][l]

    def passes(s: float) -> bool:
        drive = witness_drive(state, k, l, alpha, s, witness=witness, vertex=vertex)
        return rollout(model, qpos, drive, settings=settings).passed

    b = bisect(passes, *bracket, tol=tol)
    return b.value * alpha, alpha, b
