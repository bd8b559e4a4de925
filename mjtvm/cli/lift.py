"""The commands along the scripted lift: ``replay`` (Fig. 8 and 9, recording) and ``sweep`` (a grid)."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import TypeVar

from mjtvm.cli.options import Subparsers, command, computed_default
from mjtvm.cli.output import EXIT_OK, emit, warn, wrote
from mjtvm.cli.values import (
    MAX_GRID,
    MAX_STATES,
    integer,
    integers,
)
from mjtvm.cli.vocabulary import (
    contacts_option,
    grasp_option,
    hand_option,
    lift_options,
    limit_horizon_option,
    mg_option,
    mu_option,
    no_plots_option,
    out_options,
    parallel_options,
    quiet_option,
    reading_option,
    resume_option,
    rrd_option,
    states_option,
)
from mjtvm.errors import OptionError, ParamError

__all__ = ["add_replay", "add_sweep"]

_T = TypeVar("_T")


_TEXTS: dict[str, tuple[str, str]] = {
    # command: (help in the list of commands, description of its --help)
    "replay": (
        "TVMMP along a grasp's scripted lift (default: Case 2, Fig. 8), the paper's Fig. 9 sweeps; CSV, JSON, PNG",
        "Move the grasp's object as its [lift] says (Case 2: along +z to the fingers' reach), solve "
        "Problem 2 at every state with the lift's L/S fingers (Case 2: fingers 2 and 4) as L- and "
        "S-points at the grasp's mu and weight, for the paper's grasps (or with --sweeps) sweep mu and "
        "mg (Fig. 9), and write lift.csv, lift.json, lift-sweeps.csv and fig8/fig9a/fig9b.png to --out, "
        "as one set, atomically.",
    ),
    "sweep": (
        "Problem 2 over a grid of lift states and conditions (process pool or Dask)",
        "TVMMP over the product of the given values (every list is comma-separated); rows written "
        "to NAME.json and NAME.csv in --out, atomically, with a checkpoint NAME.partial.json of the "
        "finished rows while it runs (--resume continues from it).",
    ),
}


# ------------------------------------------------------------------ replay
def add_replay(sub: Subparsers) -> None:
    """``mjtvm replay``: the lift's CSV, JSON and plots, optionally a rerun recording."""
    p = command(sub, "replay", *_TEXTS["replay"])
    lift_options(p, contacts="L,S", reading="both")
    limit_horizon_option(p)
    out_options(p, name=None)
    no_plots_option(p)
    sweeps = p.add_argument(
        "--sweeps",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="the paper's Fig. 9 sweeps (mu 0.1-0.5 at mg 2 N, mg 0-3 N at mu 0.3): `lift-sweeps.csv`, "
        "`fig9a.png`, `fig9b.png`",
    )
    computed_default(
        sweeps,
        "for the paper's grasps (`case1`, `case1-s`, `case2` and their `-humanlike` hands) only: "
        "a grasp file of one's own gets its own mu and weight alone",
    )
    quiet_option(p)
    rrd_option(p)
    p.add_argument("--spawn", action="store_true", help="also stream the recording to a new rerun viewer")
    p.add_argument(
        "--tvms-every",
        type=integer(0, MAX_STATES),
        default=5,
        metavar="N",
        help="TVMS (Problem 1) in the recording at every N-th state and the last; 0: never",
    )
    p.set_defaults(func=_cmd_replay)


def check_file_folder(path: str | None, option: str) -> None:
    """Check, before any work, that the folder of an output file (``--rrd``) can be written."""
    if path is not None:
        from mjtvm.formats.files import check_output_dir

        check_output_dir(Path(path).parent if str(Path(path).parent) else ".", option=option)


def _cmd_replay(args: argparse.Namespace) -> int:
    from mjtvm.formats.files import check_output_dir, output_lock
    from mjtvm.jobs.figures import lift_x
    from mjtvm.jobs.replay import (  # MuJoCo and matplotlib: only the coupling commands
        ReplayOutput,
        run_replay,
    )
    from mjtvm.viewer.recording import RecordingJob, start_recording

    outdir = check_output_dir(args.out)
    check_file_folder(args.rrd, "--rrd")
    jobs: list[RecordingJob] = []

    def record(replayed: ReplayOutput) -> None:  # rerun: only in the recording's process
        jobs.append(start_recording(replayed, args.rrd, spawn=args.spawn, tvms_every=args.tvms_every))

    with output_lock(outdir):
        try:
            out = run_replay(
                scenario=args.grasp,
                hand=args.hand,
                mu=args.mu,
                mg=args.mg,
                num_states=args.states,
                stop_margin=args.stop_margin,
                variants=args.contacts,
                readings=args.reading,
                out=outdir,
                plots=not args.no_plots,
                sweeps=args.sweeps,
                progress=not args.quiet,
                on_replay=record if args.rrd is not None or args.spawn else None,
                limit_horizon=args.limit_horizon,
            )
        except BaseException:
            for job in jobs:
                job.cancel()
            raise
        infos = [job.result() for job in jobs]
    lift = out.lift
    x = lift_x(lift)
    values = getattr(lift, x)
    emit(f"lift: {lift.num_states} states, {x} = {values[0]:.4f} .. {values[-1]:.4f} m ({lift.limit})")
    doubtful = [r for r in out.records if r.result.uncertified()]
    if doubtful:
        warn(
            f"{len(doubtful)} of {len(out.records)} states have an alpha that is not certified "
            f"(lift.csv: certified; lift.json: notes), the first: state {doubtful[0].index}"
        )
    for path in out.files.values():
        wrote(path)
    for info in infos:
        if args.rrd is not None:
            wrote(args.rrd, f"{info['seconds']:.2f} s")
    return EXIT_OK


# ------------------------------------------------------------------ sweep
def add_sweep(sub: Subparsers) -> None:
    """``mjtvm sweep``: Problem 2 over a grid, rows to NAME.json and NAME.csv."""
    p = command(sub, "sweep", *_TEXTS["sweep"])
    _sweep_grid(p)
    limit_horizon_option(p)
    parallel_options(p)
    out_options(p, name="sweep")
    resume_option(p)
    quiet_option(p)
    p.set_defaults(func=_cmd_sweep)


def _sweep_grid(p: argparse.ArgumentParser) -> None:
    """The grid's axes: grasps, hands, contacts, readings, mu, mg and the lift's states."""
    grasp_option(p, default="case2", many=True)
    hand_option(p, many=True)
    contacts_option(p, default="L")
    reading_option(p, default="physical")
    mu_option(p, many=True)
    mg_option(p, many=True)
    states_option(p, hint="state indices are --state-indices")
    indices = p.add_argument(
        "--state-indices",
        type=integers(0, MAX_STATES - 1),
        default=None,
        metavar="I,J",
        help="solve only these states of the lift (0 <= I < `--states`)",
    )
    computed_default(indices, "all")


def _tuple(values: Sequence[_T] | None) -> tuple[_T, ...] | None:
    return None if values is None else tuple(values)


def grid_size(args: argparse.Namespace) -> int:
    """Points of the sweep's grid: the product of its lists (``--mu``/``--mg`` count 1 when not
    given: the grasp's own value)."""
    size = len(args.state_indices) if args.state_indices is not None else args.states
    for values in (args.grasp, args.hand, args.contacts, args.reading, args.mu, args.mg):
        size *= 1 if values is None else len(values)
    return int(size)


_SWEEP_OPTIONS = {"mus": "--mu", "mgs": "--mg", "cluster": "--cluster", "states": "--state-indices"}
"""The options of the [`SweepFiles`][mjtvm.jobs.sweep_files.SweepFiles] fields whose values only the run
can judge (the grasps' own mu and mg, a scheduler's answer)."""


def _cmd_sweep(args: argparse.Namespace) -> int:
    from mjtvm.jobs.sweep_files import SweepFiles, run_sweep_files

    size = grid_size(args)
    if size > MAX_GRID:  # the points are built before the first is solved
        raise OptionError(
            "--grasp x --hand x --contacts x --reading x --mu x --mg x --states",
            f"expected a grid of at most {MAX_GRID} points, got {size}",
        )
    bad = [i for i in (args.state_indices or ()) if i >= args.states]
    if bad:
        raise OptionError("--state-indices", f"expected indices below --states = {args.states}, got {bad[0]}")
    run = SweepFiles(
        scenarios=tuple(args.grasp),
        hands=tuple(args.hand),
        variants=tuple(args.contacts),
        readings=tuple(args.reading),
        mus=_tuple(args.mu),
        mgs=_tuple(args.mg),
        num_states=args.states,
        states=_tuple(args.state_indices),
        out=args.out,
        name=args.name,
        jobs=args.jobs,
        cluster=args.cluster,
        resume=args.resume,
        quiet=args.quiet,
        limit_horizon=args.limit_horizon,
    )
    try:
        files = run_sweep_files(run, emit=emit)
    except ParamError as e:
        if e.name not in _SWEEP_OPTIONS:
            raise
        problem = e.problem.replace("give the coefficients and the weights", "give --mu and --mg")
        raise OptionError(_SWEEP_OPTIONS[e.name], problem) from e
    for path in files:
        wrote(path)
    return EXIT_OK
