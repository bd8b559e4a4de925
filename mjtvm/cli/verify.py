"""``mjtvm verify``: the physics check of [`mjtvm.jobs.verify`][mjtvm.jobs.verify] on the command line.

Its parser is built only when the command runs (the options' defaults come from
[`SimSettings`][mjtvm.physics.simulate.SimSettings], which imports MuJoCo).
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mjtvm.cli.options import Parser, computed_default
from mjtvm.cli.output import EXIT_OK, emit, wrote
from mjtvm.cli.values import (
    MAX_FORCE,
    MAX_GEAR,
    MAX_LAUNCH,
    MAX_SCALE,
    MAX_SIM_SECONDS,
    MAX_STATES,
    MIN_GEAR,
    integer,
    number,
    numbers,
)
from mjtvm.cli.vocabulary import (
    contacts_option,
    friction_margin_option,
    grasp_option,
    hand_option,
    jobs_option,
    limit_horizon_option,
    mg_option,
    mu_option,
    no_plots_option,
    out_options,
    quiet_option,
    reading_option,
    rrd_option,
    states_option,
)

__all__ = ["add_arguments", "verify_parser"]

_DESCRIPTION = (
    "alpha_sim (MuJoCo rollouts, bisection on the speed factor) against alpha_kl along "
    "the lift; writes NAME.csv and NAME.png (and slide-check.csv) to --out, atomically."
)


def verify_parser() -> argparse.ArgumentParser:
    """The parser of ``mjtvm verify`` (imports MuJoCo: built only when that command runs)."""
    parser = Parser(prog="mjtvm verify", description=_DESCRIPTION)
    add_arguments(parser)
    parser.set_defaults(func=_cmd_verify)
    return parser


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``mjtvm verify``; the vocabulary of ``docs/cli.md``."""
    grasp_option(p, default="case2")
    hand_option(p)
    states_option(p, minimum=1)
    p.add_argument(
        "--stride",
        type=integer(1, MAX_STATES),
        default=1,
        metavar="N",
        help="check every N-th state (and the last)",
    )
    contacts_option(p, default="L,S")
    reading_option(p, default="both")
    mu_option(p)
    mg_option(p, positive=True)
    friction_margin_option(p)
    limit_horizon_option(p)
    jobs_option(p)
    p.add_argument(
        "--start-method",
        default="forkserver",
        choices=("forkserver", "spawn"),
        help="how worker processes start",
    )
    p.add_argument(
        "--witness",
        default="central",
        choices=("central", "vertex"),
        help="drive the central solution of the LP or the simplex vertex",
    )
    p.add_argument(
        "--dynamics",
        action="store_true",
        help="also the dynamic alpha (eq. 31 with M qdd + c of the witness motion, docs/dynamics.md), "
        "alpha_sim / alpha_dyn and a rollout at 0.9 alpha_dyn",
    )
    p.add_argument(
        "--preload",
        type=number(0.0, MAX_FORCE, unit="N"),
        default=0.0,
        metavar="NEWTONS",
        help="minimum normal force (N) of every L contact (the state's contact preload)",
    )
    hold = p.add_argument(
        "--hold",
        type=number(0.0, MAX_SIM_SECONDS, strict=True, unit="seconds"),
        default=None,
        metavar="SECONDS",
        help="length of the hold test at rest that comes first (a state that does not hold is not "
        "checked further; docs/physics-check.md#the-hold-test)",
    )
    computed_default(hold, "a rollout's length, settle + startup + window (37 ms)")
    p.add_argument(
        "--hold-drive",
        default="auto",
        choices=("auto", "least", "squeeze"),
        help="what holds each state in the hold test and the rollouts: the witness's least forces, "
        "the squeeze with a position loop in the settle, or `auto`: the squeeze only where the least "
        "forces do not hold (docs/physics-check.md#the-squeeze-hold)",
    )
    launch = p.add_argument(
        "--launch",
        type=number(0.0, MAX_LAUNCH, strict=True, unit="metres"),
        default=None,
        metavar="METRES",
        help="also launch every pair from rest and report the speed reached within that many metres "
        "(e.g. `0.01`; docs/physics-check.md#from-rest)",
    )
    computed_default(launch, "none")
    gears = p.add_argument(
        "--gears",
        type=numbers(MIN_GEAR, MAX_GEAR, unit="reductions"),
        default=None,
        metavar="N,N,...",
        help="instead of the rollouts: the gear-ratio sweep of the TVMMP and the dynamic TVMMP at the "
        "states of `--states`/`--stride` (e.g. `10,20,30,40,60,100`; writes `gears.csv` and `gears.png`)",
    )
    computed_default(gears, "none: the rollouts")
    _simulation_options(p)
    p.add_argument("--slide-check", action="store_true", help="also run the slide-direction check")
    out_options(p, name="verify")
    no_plots_option(p)
    rrd_option(p)
    quiet_option(p)


def _simulation_options(p: argparse.ArgumentParser) -> None:
    """The rollouts' [`SimSettings`][mjtvm.physics.simulate.SimSettings] (ablations)."""
    from mjtvm.physics.simulate import SimSettings  # MuJoCo

    p.add_argument(
        "--armature-scale",
        type=number(0.0, MAX_SCALE, strict=True),
        default=1.0,
        metavar="X",
        help="ablation: scale the rotor inertia (armature)",
    )
    p.add_argument(
        "--window",
        type=number(0.0, MAX_SIM_SECONDS, strict=True, unit="seconds"),
        default=SimSettings.window,
        metavar="SECONDS",
        help="measurement window of a rollout (s)",
    )
    p.add_argument(
        "--startup",
        type=number(0.0, MAX_SIM_SECONDS, unit="seconds"),
        default=SimSettings.startup,
        metavar="SECONDS",
        help="settling time before the window (s)",
    )
    p.add_argument(
        "--cone",
        default="elliptic",
        choices=("elliptic", "pyramidal"),
        help="the rollouts' MuJoCo friction cone (pyramidal also drives the witnesses of the LPs at "
        "mu / sqrt(2), times 1 - `--friction-margin`)",
    )
    p.add_argument("--no-track", action="store_true", help="constant joint-speed setpoints (no tracking)")


_ROLLOUT_ONLY = {
    "--launch": lambda a: a.launch is not None,
    "--hold": lambda a: a.hold is not None,
    "--hold-drive": lambda a: a.hold_drive != "auto",
    "--dynamics": lambda a: a.dynamics,
    "--slide-check": lambda a: a.slide_check,
    "--preload": lambda a: a.preload != 0.0,
    "--rrd": lambda a: a.rrd is not None,
}
"""The options of the rollouts and their checks, given (not at their defaults): ``--gears``
runs none of them, so each would be ignored without a word."""


def _refuse_with_gears(args: argparse.Namespace) -> None:
    """``--gears`` replaces the rollouts: refuse an option that only they use."""
    from mjtvm.errors import OptionError

    given = [name for name, is_given in _ROLLOUT_ONLY.items() if is_given(args)]
    if given:
        raise OptionError(
            "--gears", f"replaces the rollouts, which {given[0]} is an option of: give one of them, not both"
        )


def _cmd_gears(args: argparse.Namespace) -> int:
    """``mjtvm verify --gears``: [`gear_sweep()`][mjtvm.jobs.gears.gear_sweep] to gears.csv and gears.png."""
    from mjtvm.formats.files import check_output_dir, output_lock, write_files
    from mjtvm.jobs import verify
    from mjtvm.jobs.gears import gear_sweep, plot_gears
    from mjtvm.jobs.replay import grasp_defaults

    outdir = check_output_dir(args.out)
    with output_lock(outdir):
        scenario = verify.cached_lift(args.grasp, args.states).scenario
        mu, mg = grasp_defaults(scenario, args.mu, args.mg)
        states = verify.state_indices(args.states, args.stride)
        rows = gear_sweep(
            args.grasp,
            args.gears,
            num_states=args.states,
            states=states,
            mu=mu,
            mg=mg,
            limit_horizon=args.limit_horizon,
        )
        files: dict[Path, bytes | str] = {outdir / "gears.csv": verify.rows_csv(rows)}
        if not args.no_plots:
            files[outdir / "gears.png"] = plot_gears(
                rows, f"{scenario.name}, L-points: $\\mu$ = {mu:g}, $mg$ = {mg:g} N"
            )
        write_files(files)
    for n in args.gears:
        sel = [r for r in rows if r["ratio"] == n]
        qs = [r["tvmmp"] for r in sel if r["tvmmp"] is not None]
        dy = [r["tvmmp_dyn"] for r in sel if "tvmmp_dyn" in r]
        emit(
            f"gear {n:g}: TVMMP mean {statistics.fmean(qs) if qs else math.nan:.3f}, dynamic "
            f"{statistics.fmean(dy) if dy else math.nan:.3f} ({len(qs)}/{len(sel)} states feasible)"
        )
    for path in files:
        wrote(path)
    return EXIT_OK


def _cmd_verify(args: argparse.Namespace) -> int:
    """Run ``mjtvm verify`` with parsed [`add_arguments()`][mjtvm.cli.verify.add_arguments] options; print the summary.

    The output folder is checked and locked before any work; the CSV, PNG and the slide
    check's CSV are written together, atomically, at the end ([`mjtvm.formats.files`][mjtvm.formats.files]).
    """
    from mjtvm.formats.files import check_output_dir, output_lock, write_files
    from mjtvm.grasp.resolve.variants import with_hand
    from mjtvm.jobs import verify
    from mjtvm.jobs.slide_check import slide_check
    from mjtvm.physics.simulate import SimSettings

    args.grasp = str(with_hand(args.grasp, args.hand))  # replay's --hand: case2 + humanlike
    if args.gears is not None:
        _refuse_with_gears(args)
        return _cmd_gears(args)
    settings = SimSettings(
        armature_scale=args.armature_scale,
        window=args.window,
        startup=args.startup,
        cone=args.cone,
        track=not args.no_track,
    )
    outdir = check_output_dir(args.out)
    if args.rrd is not None:
        check_output_dir(Path(args.rrd).parent, option="--rrd")
    with output_lock(outdir):
        from mjtvm.jobs.replay import grasp_defaults

        mu, mg = grasp_defaults(verify.checked_lift(args.grasp, args.states).scenario, args.mu, args.mg)
        t0 = time.perf_counter()
        rows = verify.verify_lift(
            args.grasp,
            num_states=args.states,
            stride=args.stride,
            runs=verify.runs_of(args.contacts, args.reading),
            mu=mu,
            mg=mg,
            settings=settings,
            witness=args.witness,
            dynamics=args.dynamics,
            preload=args.preload,
            hold_time=args.hold,
            launch_distance=args.launch,
            friction_margin=args.friction_margin,
            limit_horizon=args.limit_horizon,
            hold_drive=args.hold_drive,
            jobs=args.jobs,
            start_method=args.start_method,
            out=None,
            progress=not args.quiet,
        )
        wall = time.perf_counter() - t0
        files: dict[Path, bytes | str] = {outdir / f"{args.name}.csv": verify.rows_csv(rows)}
        if not args.no_plots:
            title = verify.plot_title(args.grasp, mu, mg)
            files[outdir / f"{args.name}.png"] = verify.plot_alpha(rows, title)
        srows: list[dict[str, Any]] = []
        if args.slide_check:
            lift = verify.cached_lift(args.grasp, args.states)
            indices = verify.state_indices(args.states, args.stride)
            srows = slide_check(lift, indices, mu=mu, mg=mg, settings=settings)
            files[outdir / "slide-check.csv"] = verify.rows_csv(srows)
        write_files(files)
    _print_holds(rows, args.grasp)
    _print_summary(verify.summarize(rows), wall, args.jobs)
    if args.slide_check:
        _print_slide_check(srows)
    for path in files:
        wrote(path)
    if args.rrd is not None:
        from mjtvm.viewer.viz import record_verify  # rerun is imported only here

        record_verify(rows, args.rrd)
        wrote(args.rrd)
    return EXIT_OK


def _print_holds(rows: Sequence[dict[str, Any]], grasp: str) -> None:
    """One line on stderr per (run, state) that does not hold at rest: its check stopped there."""
    seen: set[tuple[str, int]] = set()
    for r in rows:
        key = (r["run"], r["state"])
        if r.get("held") is False and key not in seen:
            seen.add(key)
            print(f"mjtvm verify: {grasp} state {r['state']} ({r['run']}) {r['verdict']}", file=sys.stderr)


def _print_summary(summary: dict[str, dict[str, Any]], wall: float, jobs: int) -> None:
    for run_name, s in summary.items():
        verdicts = s.pop("verdicts", {})
        causes = s.pop("causes", {})
        emit(
            f"{run_name}: "
            + ", ".join(f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}" for k, v in s.items())
        )
        if verdicts:
            emit(f"{run_name} verdicts: " + "; ".join(f"{v} x{n}" for v, n in verdicts.items()))
        if causes:
            emit(
                f"{run_name} causes of ratios outside [0.9, 1.05]: "
                + "; ".join(f"{c} x{n}" for c, n in causes.items())
            )
    emit(f"wall time {wall:.1f} s ({jobs} job(s))")


def _print_slide_check(srows: Sequence[dict[str, Any]]) -> None:
    for mode in ("physical", "literal", "frictionless"):
        sel = [r for r in srows if r["mode"] == mode]
        fc = [r["friction_cos_phys"] for r in sel if not math.isnan(r["friction_cos_phys"])]
        emit(
            f"slide check {mode}: friction cos with physical slide direction: median "
            f"{statistics.median(fc) if fc else math.nan:.3f}; passed {sum(r['passed'] for r in sel) // 2}"
            f"/{len(sel) // 2} states"
        )
