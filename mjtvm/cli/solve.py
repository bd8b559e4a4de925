"""The commands on one grasp state: ``solve`` (Problem 2), ``export-state`` and ``tvms`` (Problem 1)."""

from __future__ import annotations

import argparse
import json
import sys
from importlib import resources

from ..core.solvers import SOLVERS
from ..core.state import GraspState, load_state
from ..core.tvmmp import tvmmp
from ..errors import StateError
from .options import Subparsers, command, hand_option
from .output import EXIT_OK, emit, lp_progress
from .values import integer, number

__all__ = ["add_export_state", "add_solve", "add_tvms", "example_path"]


_TEXTS: dict[str, tuple[str, str]] = {
    # command: (help in the list of commands, description of its --help)
    "solve": (
        "Problem 2: TVMMP of one mjtvm.state/1 grasp state (prints mjtvm.result/1)",
        "Solve Problem 2 (eq. 31-35) for STATE and print the mjtvm.result/1 JSON.",
    ),
    "export-state": (
        "print the mjtvm.state/1 grasp state of a scenario, computed by MuJoCo",
        "Build a scenario's grasp state from the MuJoCo model (mj_forward) and print it.",
    ),
    "tvms": (
        "Problem 1: the exact TVMS polytope and its volume (prints mjtvm.tvms/1)",
        "Solve Problem 1 (eq. 26-29, 34) for STATE or a scenario and print mjtvm.tvms/1.",
    ),
}


def example_path(name: str = "pinch.json") -> str:
    """Path of a state shipped in ``mjtvm/data/examples``."""
    return str(resources.files("mjtvm.data").joinpath("examples").joinpath(name))


def _indent_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--indent", type=integer(0), default=1, help="JSON indentation")


# ------------------------------------------------------------------ solve
def add_solve(sub: Subparsers) -> None:
    """``mjtvm solve [STATE|-]``: prints mjtvm.result/1."""
    p = command(sub, "solve", *_TEXTS["solve"])
    p.add_argument(
        "state", nargs="?", default=None,
        help="mjtvm.state/1 JSON file, or - for standard input (default: the shipped example pinch.json)",
    )  # fmt: skip
    p.add_argument("--solver", choices=SOLVERS, default="highs", help="LP backend")
    p.add_argument(
        "--box", choices=("eliminated", "literal"), default="eliminated",
        help="operation-range form: exact reduction or the paper's literal eq. 2 box",
    )  # fmt: skip
    p.add_argument("--no-witnesses", action="store_true", help="omit forces, torques, speeds and boxes")
    _indent_option(p)
    p.set_defaults(func=_cmd_solve)


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
    emit(json.dumps(result.to_dict(witnesses=not args.no_witnesses), indent=args.indent))
    return EXIT_OK


# ------------------------------------------------------------------ export-state
def add_export_state(sub: Subparsers) -> None:
    """``mjtvm export-state --scenario NAME``: prints the scenario's mjtvm.state/1."""
    p = command(sub, "export-state", *_TEXTS["export-state"])
    p.add_argument(
        "--scenario",
        required=True,
        help="scenario name (case1, case1-s, case2) or path of a scenario JSON file",
    )
    hand_option(p)
    p.add_argument("--mg", type=number(0.0), default=None, help="object weight (N); default: the scenario's")
    _indent_option(p)
    p.set_defaults(func=_cmd_export_state)


def _cmd_export_state(args: argparse.Namespace) -> int:
    from ..sim.scenario import export_state  # MuJoCo is imported only by the coupling commands

    options = {"variant": args.hand}
    if args.mg is not None:
        options["mg"] = args.mg
    emit(json.dumps(export_state(args.scenario, **options), indent=args.indent))
    return EXIT_OK


# ------------------------------------------------------------------ tvms
def add_tvms(sub: Subparsers) -> None:
    """``mjtvm tvms [STATE|-|--scenario NAME]``: prints mjtvm.tvms/1."""
    p = command(sub, "tvms", *_TEXTS["tvms"])
    p.add_argument("state", nargs="?", default=None, help="mjtvm.state/1 JSON file, or - for standard input")
    p.add_argument("--scenario", default=None, help="a scenario instead of a file: case1, case1-s, case2")
    hand_option(p, help="hand model of --scenario: default or humanlike")
    p.add_argument("--no-rvds", action="store_true", help="ignore the state's RVDS (no cone restriction)")
    p.add_argument("--method", choices=("lp", "cdd"), default="lp", help="LP projection or cdd enumeration")
    p.add_argument(
        "--time-limit",
        type=number(0.0, strict=True),
        default=120.0,
        metavar="S",
        help="cap of the cdd method (s)",
    )
    _indent_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress spinner (LPs solved) on stderr")
    p.set_defaults(func=_cmd_tvms)


def _load_state_or_scenario(args: argparse.Namespace) -> GraspState:
    if args.scenario is not None:
        from ..sim.scenario import load_scenario  # MuJoCo only for scenario shortcuts

        return load_scenario(args.scenario, variant=args.hand).state()
    if args.state is None:
        raise StateError("state", "give a mjtvm.state/1 file (or -) or --scenario NAME")
    source = sys.stdin.read() if args.state == "-" else args.state
    return load_state(source)


def _cmd_tvms(args: argparse.Namespace) -> int:
    from ..polytopes.tvms import tvms  # Problem 1 needs scipy's Qhull and (for cdd) pycddlib

    state = _load_state_or_scenario(args)
    if args.no_rvds:
        state = state.with_(rvds=None)
    with lp_progress(not args.quiet and args.method == "lp", "tvms"):
        result = tvms(state, method=args.method, time_limit=args.time_limit)
    emit(json.dumps(result.to_dict(), indent=args.indent))
    return EXIT_OK
