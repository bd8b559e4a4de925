r"""The ``mjtvm`` command line: thin wrappers over the library.

Exit codes: 0 success, 2 invalid input (a :class:`~mjtvm.errors.StateError` or
:class:`~mjtvm.errors.ModelError`, printed as ``error: <field>: <problem>``), 3 solver
failure.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from importlib import resources
from pathlib import Path

from .errors import MjtvmError, ModelError, SolverError, StateError
from .solvers import SOLVERS
from .state import GraspState, load_state
from .tvmmp import tvmmp

__all__ = ["main"]


def example_path(name: str = "pinch.json") -> str:
    """Path of a state shipped in ``mjtvm/data/examples``."""
    return str(resources.files("mjtvm.data").joinpath("examples").joinpath(name))


def _cmd_solve(args: argparse.Namespace) -> int:
    source = args.state
    if source == "-":
        source = sys.stdin.read()
        if not source.lstrip().startswith("{"):
            raise StateError("", "standard input does not hold a JSON object")
    elif source is None:
        source = example_path()
    state = load_state(source)
    result = tvmmp(state, solver=args.solver, box=args.box, witnesses=not args.no_witnesses)
    print(json.dumps(result.to_dict(witnesses=not args.no_witnesses), indent=args.indent))
    return 0


def _cmd_export_state(args: argparse.Namespace) -> int:
    from .scenario import export_state  # MuJoCo is imported only by the coupling commands

    options = {"variant": args.variant}
    if args.mg is not None:
        options["mg"] = args.mg
    print(json.dumps(export_state(args.scenario, **options), indent=args.indent))
    return 0


def _cmd_replay(args: argparse.Namespace) -> int:
    from .recording import RecordingJob, start_recording
    from .replay import ReplayOutput, run_replay  # MuJoCo and matplotlib: only the coupling commands

    readings = ("physical", "literal") if args.reading == "both" else (args.reading,)
    jobs: list[RecordingJob] = []

    def record(replayed: ReplayOutput) -> None:  # rerun: only in the recording's process
        jobs.append(start_recording(replayed, args.rrd, spawn=args.spawn, tvms_every=args.tvms_every))

    try:
        out = run_replay(
            scenario=args.scenario, hand=args.variant, mu=args.mu, mg=args.mg, num_states=args.states,
            variants=tuple(v.strip() for v in args.variants.split(",")), readings=readings, out=args.out,
            plots=not args.no_plots, sweeps=not args.no_sweeps, progress=not args.quiet,
            on_replay=record if args.rrd is not None or args.spawn else None,
        )  # fmt: skip
    except BaseException:
        for job in jobs:
            job.cancel()
        raise
    lift = out.lift
    print(f"lift: {lift.num_states} states, z = {lift.z[0]:.4f} .. {lift.z[-1]:.4f} m ({lift.limit})")
    for name, path in out.files.items():
        print(f"wrote {name}: {path}")
    for job in jobs:
        info = job.result()
        if args.rrd is not None:
            print(f"wrote {Path(args.rrd).name}: {args.rrd} ({info['seconds']:.2f} s)")
    return 0


def _load_state_or_scenario(args: argparse.Namespace) -> GraspState:
    if args.scenario is not None:
        from .scenario import load_scenario  # MuJoCo only for scenario shortcuts

        return load_scenario(args.scenario, variant=args.variant).state()
    if args.state is None:
        raise StateError("state", "give a mjtvm.state/1 file (or -) or --scenario NAME")
    source = sys.stdin.read() if args.state == "-" else args.state
    return load_state(source)


def _cmd_tvms(args: argparse.Namespace) -> int:
    from .tvms import tvms  # Problem 1 needs scipy's Qhull and (for cdd) pycddlib

    state = _load_state_or_scenario(args)
    if args.no_rvds:
        state = state.with_(rvds=None)
    result = tvms(state, method=args.method, time_limit=args.time_limit)
    print(json.dumps(result.to_dict(), indent=args.indent))
    return 0


def _cmd_verify(args: argparse.Namespace) -> int:
    from .verify import add_arguments, run  # MuJoCo rollouts: imported only when used

    parser = argparse.ArgumentParser(
        prog="mjtvm verify",
        description="alpha_sim (MuJoCo rollouts, bisection on the speed factor) against alpha_kl.",
    )
    add_arguments(parser)
    return run(parser.parse_args(args.options))


def _cmd_sweep(args: argparse.Namespace) -> int:
    from .sweep import grid, run_sweep

    def floats(text: str, name: str) -> tuple[float, ...]:
        try:
            return tuple(float(v) for v in text.split(","))
        except ValueError as e:
            raise StateError(name, f"expected comma-separated numbers, got {text!r}") from e

    states = (
        None if args.state_indices is None else tuple(int(v) for v in floats(args.state_indices, "states"))
    )
    points = grid(
        scenarios=tuple(args.scenario.split(",")),
        hands=tuple(args.hand.split(",")),
        variants=tuple(args.variants.split(",")),
        readings=tuple(args.readings.split(",")),
        mus=floats(args.mu, "mu"),
        mgs=floats(args.mg, "mg"),
        states=states,
        num_states=args.num_states,
    )
    rows = run_sweep(points, jobs=args.jobs, cluster=args.cluster, progress=not args.quiet)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rows, indent=1))
    print(f"wrote {len(rows)} rows: {out}")
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    from .bench_report import run_from_args  # cvxpy, MuJoCo and the pool: imported only when used

    return run_from_args(args)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``mjtvm``."""
    parser = argparse.ArgumentParser(
        prog="mjtvm",
        description="Joint torque-velocity pair based manipulability (Watanabe) of robot hands.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    solve = sub.add_parser(
        "solve",
        help="Problem 2: TVMMP of one mjtvm.state/1 grasp state (prints mjtvm.result/1)",
        description="Solve Problem 2 (eq. 31-35) for STATE and print the mjtvm.result/1 JSON.",
    )
    solve.add_argument(
        "state", nargs="?", default=None,
        help="mjtvm.state/1 JSON file, or - for standard input (default: the shipped example pinch.json)",
    )  # fmt: skip
    solve.add_argument("--solver", choices=SOLVERS, default="highs", help="LP backend (default: highs)")
    solve.add_argument(
        "--box", choices=("eliminated", "literal"), default="eliminated",
        help="operation-range form: exact reduction (default) or the paper's literal eq. 2 box",
    )  # fmt: skip
    solve.add_argument("--no-witnesses", action="store_true", help="omit forces, torques, speeds and boxes")
    solve.add_argument("--indent", type=int, default=1, help="JSON indentation (default 1)")
    solve.set_defaults(func=_cmd_solve)

    export = sub.add_parser(
        "export-state",
        help="print the mjtvm.state/1 grasp state of a scenario, computed by MuJoCo",
        description="Build a scenario's grasp state from the MuJoCo model (mj_forward) and print it.",
    )
    export.add_argument(
        "--scenario", required=True,
        help="scenario name (case1, case1-s, case2) or path of a scenario JSON file",
    )  # fmt: skip
    export.add_argument(
        "--variant", default="default", help="hand variant: default or humanlike (default: default)"
    )
    export.add_argument("--mg", type=float, default=None, help="object weight (N); default: the scenario's")
    export.add_argument("--indent", type=int, default=1, help="JSON indentation (default 1)")
    export.set_defaults(func=_cmd_export_state)

    replay = sub.add_parser(
        "replay",
        help="TVMMP along the scripted lift of Case 2 (Fig. 8) and the Fig. 9 sweeps; CSV, JSON, PNG",
        description="Lift the object along +z to the fingers' reach, solve Problem 2 at every state with "
        "fingers 2 and 4 as L- and S-points, sweep mu and mg (Fig. 9), write lift.csv, lift.json, "
        "lift-sweeps.csv and fig8/fig9a/fig9b.png to --out.",
    )
    replay.add_argument("--scenario", default="case2", help="scenario name or JSON path (default: case2)")
    replay.add_argument(
        "--variant", default="default", help="hand variant: default or humanlike (default: default)"
    )
    replay.add_argument("--mu", type=float, default=0.3, help="friction coefficient (default 0.3)")
    replay.add_argument("--mg", type=float, default=1.0, help="object weight in N (default 1.0)")
    replay.add_argument("--states", type=int, default=30, help="number of states along the lift (default 30)")
    replay.add_argument(
        "--variants", default="L,S", help="contact types of fingers 2 and 4, comma-separated (default: L,S)"
    )
    replay.add_argument(
        "--reading", choices=("physical", "literal", "both"), default="physical",
        help="S-point slide direction: the slip of the min-norm motion (physical, default) or the "
        "paper's printed vector, its reverse (literal); both runs both",
    )  # fmt: skip
    replay.add_argument("--out", default="results", help="output directory (default: results)")
    replay.add_argument("--no-plots", action="store_true", help="do not write the PNG plots")
    replay.add_argument("--no-sweeps", action="store_true", help="skip the Fig. 9 mu and mg sweeps")
    replay.add_argument("--quiet", action="store_true", help="no progress bars")
    replay.add_argument(
        "--rrd", metavar="FILE", default=None,
        help="also write a rerun recording of the lift (scene, contacts, velocity polytopes, TVMMP, "
        "joint operation points); open it with `rerun FILE`",
    )  # fmt: skip
    replay.add_argument(
        "--spawn", action="store_true", help="also stream the recording to a newly spawned rerun viewer"
    )
    replay.add_argument(
        "--tvms-every", type=int, default=5, metavar="N",
        help="TVMS (Problem 1) in the recording at every N-th state and the last; 0: never (default 5)",
    )  # fmt: skip
    replay.set_defaults(func=_cmd_replay)

    tv = sub.add_parser(
        "tvms",
        help="Problem 1: the exact TVMS polytope and its volume (prints mjtvm.tvms/1)",
        description="Solve Problem 1 (eq. 26-29, 34) for STATE or a scenario and print mjtvm.tvms/1.",
    )
    tv.add_argument("state", nargs="?", default=None, help="mjtvm.state/1 JSON file, or - for standard input")
    tv.add_argument("--scenario", default=None, help="a scenario instead of a file: case1, case1-s, case2")
    tv.add_argument("--variant", default="default", help="hand variant of --scenario (default or humanlike)")
    tv.add_argument("--no-rvds", action="store_true", help="ignore the state's RVDS (no cone restriction)")
    tv.add_argument("--method", choices=("lp", "cdd"), default="lp", help="LP projection (default) or cdd")
    tv.add_argument("--time-limit", type=float, default=120.0, help="cap of the cdd baseline (s)")
    tv.add_argument("--indent", type=int, default=1, help="JSON indentation (default 1)")
    tv.set_defaults(func=_cmd_tvms)

    verify = sub.add_parser(
        "verify",
        help="check TVMMP along the lift against MuJoCo rollouts with the dcmotor actuators",
        add_help=False,  # its options (and --help) are parsed by mjtvm.verify's own parser
    )
    verify.set_defaults(func=_cmd_verify)  # main() hands its words to mjtvm.verify's parser

    sweep = sub.add_parser(
        "sweep",
        help="Problem 2 over a grid of lift states and conditions (process pool or Dask)",
        description="TVMMP over the product of the given values; rows written as JSON.",
    )
    sweep.add_argument("--scenario", default="case2", help="comma-separated scenarios (default case2)")
    sweep.add_argument("--hand", default="default", help="comma-separated hands: default, humanlike")
    sweep.add_argument("--variants", default="L", help="comma-separated: L, S (default L)")
    sweep.add_argument("--readings", default="physical", help="comma-separated: physical, literal")
    sweep.add_argument("--mu", default="0.3", help="comma-separated friction coefficients")
    sweep.add_argument("--mg", default="1.0", help="comma-separated weights (N)")
    sweep.add_argument("--states", dest="state_indices", default=None, help="comma-separated state indices")
    sweep.add_argument("--num-states", type=int, default=30, help="states of the lift (default 30)")
    sweep.add_argument("--jobs", type=int, default=1, help="local worker processes (default 1)")
    sweep.add_argument("--cluster", default=None, help="Dask scheduler address (tcp://host:8786)")
    sweep.add_argument("--out", default="results/sweep.json", help="output JSON (default results/sweep.json)")
    sweep.add_argument("--quiet", action="store_true", help="no progress bar")
    sweep.set_defaults(func=_cmd_sweep)

    from .bench_report import add_arguments as bench_arguments  # numpy only at import

    bench = sub.add_parser(
        "bench",
        help="the benchmark run: paper cases vs cvxpy/cdd, the lift, the sweeps on 1 and 2 processes, scaling",
        description="Time the paper's cases (Problem 1 and 2) against the cvxpy and cdd baselines, the full "
        "lift, the Fig. 9 sweeps on 1 and 2 processes and synthetic hands of 2-16 fingers; write "
        "results/bench.json and results/bench.md.",
    )
    bench_arguments(bench)
    bench.set_defaults(func=_cmd_bench)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mjtvm`` console script."""
    words = list(sys.argv[1:] if argv is None else argv)
    if words[:1] == ["verify"]:  # its own parser (imports MuJoCo only when used)
        args = argparse.Namespace(func=_cmd_verify, options=words[1:])
    else:
        args = build_parser().parse_args(words)
    try:
        code: int = args.func(args)
    except (StateError, ModelError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except SolverError as e:
        print(f"solver error: {e}", file=sys.stderr)
        return 3
    except MjtvmError as e:  # e.g. a RecordingError
        print(f"error: {e}", file=sys.stderr)
        return 1
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
