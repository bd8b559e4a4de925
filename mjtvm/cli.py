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

from .errors import ModelError, SolverError, StateError
from .solvers import SOLVERS
from .state import load_state
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
    from .replay import run_replay  # MuJoCo and matplotlib are imported only by the coupling commands

    readings = ("physical", "literal") if args.reading == "both" else (args.reading,)
    out = run_replay(
        scenario=args.scenario, hand=args.variant, mu=args.mu, mg=args.mg, num_states=args.states,
        variants=tuple(v.strip() for v in args.variants.split(",")), readings=readings, out=args.out,
        plots=not args.no_plots, sweeps=not args.no_sweeps, progress=not args.quiet,
    )  # fmt: skip
    lift = out.lift
    print(f"lift: {lift.num_states} states, z = {lift.z[0]:.4f} .. {lift.z[-1]:.4f} m ({lift.limit})")
    for name, path in out.files.items():
        print(f"wrote {name}: {path}")
    if args.rrd is not None or args.spawn:
        from .viz import record_replay  # rerun is imported only here

        info = record_replay(out, args.rrd, spawn=args.spawn, tvms_every=args.tvms_every)
        if args.rrd is not None:
            print(f"wrote {Path(args.rrd).name}: {args.rrd} ({info['seconds']:.2f} s)")
    return 0


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
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mjtvm`` console script."""
    args = build_parser().parse_args(argv)
    try:
        code: int = args.func(args)
    except (StateError, ModelError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except SolverError as e:
        print(f"solver error: {e}", file=sys.stderr)
        return 3
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
