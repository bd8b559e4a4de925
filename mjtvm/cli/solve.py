"""The commands on one grasp state: ``solve`` (Problem 2), ``export-state`` and ``tvms`` (Problem 1)."""

from __future__ import annotations

import argparse
import json
import sys
from importlib import resources
from pathlib import Path

from mjtvm.cli.options import Subparsers, command, computed_default, refused_option
from mjtvm.cli.output import (
    EXIT_OK,
    bracket_progress,
    emit,
    grouped,
    lp_progress,
    one_line,
    warn,
    warn_uncertified,
    wrote,
)
from mjtvm.cli.show import warn_contacts
from mjtvm.cli.values import fraction, memory_size, source
from mjtvm.cli.vocabulary import (
    GRASP_HELP,
    friction_margin_option,
    grasp_option,
    hand_option,
    indent_option,
    limit_horizon_option,
    mg_option,
    mu_option,
    one_grasp,
    png_option,
    quiet_option,
    time_limit_option,
    with_limit_horizon,
)
from mjtvm.errors import OptionError, StateError
from mjtvm.formats.state_file import load_state
from mjtvm.lp.solvers import SOLVERS
from mjtvm.model.bounds import MAX_FILE_BYTES
from mjtvm.model.state import GraspState
from mjtvm.polytopes.budget import DEFAULT_CONFIDENCE
from mjtvm.problem2.tvmmp import tvmmp

__all__ = ["add_export_state", "add_solve", "add_tvms", "example_path", "is_grasp_source", "load_source"]


_TEXTS: dict[str, tuple[str, str]] = {
    # command: (help in the list of commands, description of its --help)
    "solve": (
        "Problem 2: TVMMP of one grasp state or grasp file (prints mjtvm.result/1)",
        "Solve Problem 2 (eq. 31-35) for a mjtvm.state/1 STATE or a mjtvm.grasp/1 grasp and print "
        "the mjtvm.result/1 JSON.",
    ),
    "export-state": (
        "print the mjtvm.state/1 grasp state of a grasp file, computed by MuJoCo",
        "Build a grasp's state from its MuJoCo model (mj_forward) and print it; the contacts found "
        "against those the grasp file expects go to stderr.",
    ),
    "tvms": (
        "Problem 1: the exact TVMS polytope and its volume (prints mjtvm.tvms/1)",
        "Solve Problem 1 (eq. 26-29, 34) for STATE or a grasp and print mjtvm.tvms/1.",
    ),
}


def example_path(name: str = "pinch.json") -> str:
    """Path of a state shipped in ``mjtvm/data/examples``."""
    return str(resources.files("mjtvm.data").joinpath("examples").joinpath(name))


# ------------------------------------------------------------------ solve
_SOURCE_HELP = (
    "a mjtvm.state/1 JSON file, - for standard input, or a mjtvm.grasp/1 file (.toml, or .json "
    "with that schema) or shipped grasp name"
)


def add_solve(sub: Subparsers) -> None:
    """``mjtvm solve [STATE|GRASP|-]``: prints mjtvm.result/1."""
    p = command(sub, "solve", *_TEXTS["solve"])
    state = p.add_argument(
        "state", nargs="?", default=None, type=source, metavar="STATE|GRASP", help=_SOURCE_HELP
    )
    computed_default(state, "the shipped example `pinch.json`")
    hand_option(p)
    mu_option(p)
    mg_option(p)
    friction_margin_option(p)
    p.add_argument("--solver", choices=SOLVERS, default="highs", help="LP backend")
    p.add_argument(
        "--box",
        choices=("eliminated", "literal"),
        default="eliminated",
        help="operation-range form: exact reduction or the paper's literal eq. 2 box",
    )
    p.add_argument("--no-witnesses", action="store_true", help="omit forces, torques, speeds and boxes")
    limit_horizon_option(p)
    indent_option(p)
    quiet_option(p)
    png_option(p)
    p.set_defaults(func=_cmd_solve)


def is_grasp_source(source: str) -> bool:
    """A grasp (file or shipped name) rather than a state file: ``.toml``, a JSON document of
    schema ``mjtvm.grasp/1``, or a name without a suffix that is not a file."""
    path = Path(source)
    if path.suffix.lower() == ".toml":
        return True
    if path.suffix.lower() == ".json":
        try:
            with path.open("rb") as f:
                head = f.read(4096)
        except OSError:
            return False
        return b'"mjtvm.grasp/1"' in head
    return not path.suffix and "/" not in source and not path.exists()


def _read_stdin() -> bytes:
    """Standard input, read up to one byte more than a state may have (``< /dev/zero`` is
    refused as too large, not read forever)."""
    buffer = getattr(sys.stdin, "buffer", None)
    if buffer is not None:
        raw: bytes = buffer.read(MAX_FILE_BYTES + 1)
    else:  # a text stream (a test's StringIO)
        raw = sys.stdin.read(MAX_FILE_BYTES + 1).encode("utf-8", "surrogateescape")
    if len(raw) > MAX_FILE_BYTES:
        raise StateError(
            "-", f"expected a state of at most {MAX_FILE_BYTES} bytes on standard input, got more"
        )
    if not raw.lstrip(b"\xef\xbb\xbf \t\r\n").startswith(b"{"):
        raise StateError("", "standard input does not hold a JSON object")
    return raw


def load_source(
    source: str | None,
    *,
    hand: str = "default",
    default: str | None = None,
    warnings: bool = True,
    friction_margin: float | None = None,
    mu: float | None = None,
    mg: float | None = None,
) -> GraspState:
    """The state of ``source``: a state file, ``-`` (standard input), or a grasp (MuJoCo; its
    contact warnings on stderr unless ``warnings`` is false). ``friction_margin``: the margin
    instead of the state's ``friction_margin`` or the grasp file's (on its ``cone``); ``mu``,
    ``mg``: the grasp's friction coefficient and object weight (N) instead of its own, as
    ``replay`` takes them (a grasp only: a state file's are refused).

    Raises
    ------
    OptionError
        ``mu`` or ``mg`` (``--mu``, ``--mg``) or a ``hand`` other than the default for a state file.
    """
    if source == "-":
        _refuse_for_state(mu, mg)
        return _with_margin(load_state(_read_stdin()), friction_margin)
    if source is None:
        if default is None:
            raise OptionError(
                "STATE", "give a mjtvm.state/1 file (or -) or a grasp (--grasp or a .toml file)"
            )
        source = default
    if is_grasp_source(source):
        from mjtvm.grasp import load_grasp  # MuJoCo only for grasps

        grasp = load_grasp(source, hand=hand).with_options(mu=mu, mg=mg, friction_margin=friction_margin)
        state = grasp.state()
        if warnings:
            warn_contacts(grasp)
        return state
    if hand != "default":
        raise OptionError("--hand", "applies to the paper's shipped grasps, not to a state file")
    _refuse_for_state(mu, mg)
    return _with_margin(load_state(source), friction_margin)


def _refuse_for_state(mu: float | None, mg: float | None) -> None:
    """A state file has its contacts' friction and its REFS written out: ``--mu``/``--mg``
    (a grasp's coefficient, its weight) have nothing to replace there."""
    if mu is not None:
        raise OptionError("--mu", "applies to a grasp (its contacts' friction), not to a state file")
    if mg is not None:
        raise OptionError("--mg", "applies to a grasp (the weight in its REFS), not to a state file")


def _with_margin(state: GraspState, friction_margin: float | None) -> GraspState:
    """A state file's state with the ``--friction-margin`` (a state has no cone: as given)."""
    return state if friction_margin is None else state.with_(friction_margin=friction_margin)


def _check_png(path: str | None) -> None:
    """Check, before any work, that ``--png``'s folder can be written."""
    if path is not None:
        from mjtvm.formats.files import check_output_dir

        check_output_dir(Path(path).parent, option="--png")


def _write_png(path: str, data: bytes) -> None:
    """Write ``--png``'s picture; the ``wrote`` line on stderr (stdout: the JSON document)."""
    from mjtvm.formats import atomic_write

    atomic_write(path, data, option="--png")
    wrote(path, stderr=True)


def _source_name(source: str | None, default: str) -> str:
    """The name of a state or grasp in a picture's title: a file's stem or a shipped name."""
    return "standard input" if source == "-" else Path(source or default).stem


def _cmd_solve(args: argparse.Namespace) -> int:
    _check_png(args.png)
    state = with_limit_horizon(
        load_source(
            args.state,
            hand=args.hand,
            default=example_path(),
            warnings=not args.quiet,
            friction_margin=args.friction_margin,
            mu=args.mu,
            mg=args.mg,
        ),
        args.limit_horizon,
    )
    result = tvmmp(state, solver=args.solver, box=args.box, witnesses=not args.no_witnesses, diagnose=True)
    document = result.to_dict(witnesses=not args.no_witnesses)
    emit(json.dumps(document, indent=args.indent))
    if args.png is not None:
        from mjtvm.jobs.result_figures import solve_png  # matplotlib: only with --png

        title = f"{_source_name(args.state, example_path())}: Problem 2"
        figure = solve_png(document, state.operation_ranges, title, actuators=state.transmission is not None)
        _write_png(args.png, figure)
    if args.quiet:
        return EXIT_OK
    warn_uncertified(result)
    zeros = [(f"alpha[{d.pair[0]}][{d.pair[1]}]", d.message) for d in result.diagnosis if d.pair[1] >= 0]
    for d in result.diagnosis:
        if d.pair[1] < 0:
            warn(d.message)
    for subjects, message, _ in grouped(zeros):  # one line per cause, counting its pairs
        warn(f"{subjects} = 0: {message}")
    return EXIT_OK


# ------------------------------------------------------------------ export-state
def add_export_state(sub: Subparsers) -> None:
    """``mjtvm export-state GRASP``: prints the grasp's mjtvm.state/1."""
    p = command(sub, "export-state", *_TEXTS["export-state"])
    p.add_argument("grasp_file", nargs="?", default=None, type=source, metavar="GRASP", help=GRASP_HELP)
    grasp_option(p, default=None)
    hand_option(p)
    mg_option(p)
    mu_option(p)
    friction_margin_option(p)
    limit_horizon_option(p)
    indent_option(p)
    quiet_option(p)
    p.set_defaults(func=_cmd_export_state)


def _cmd_export_state(args: argparse.Namespace) -> int:
    from mjtvm.formats.state_file import state_to_dict
    from mjtvm.grasp import load_grasp  # MuJoCo is imported only by the coupling commands

    source = one_grasp(args.grasp_file, args.grasp)
    grasp = load_grasp(source, hand=args.hand).with_options(
        mg=args.mg, mu=args.mu, friction_margin=args.friction_margin
    )
    state = with_limit_horizon(grasp.state(), args.limit_horizon)
    if not args.quiet:
        warn_contacts(grasp)
        report = ", ".join(
            f"{row['selection']} {row['type']}: " + (", ".join(row["found"]) or "not found")
            for row in grasp.contact_report()
        )
        print(
            one_line(f"contacts (expected: found within {1e3 * grasp.contact_tolerance:g} mm): {report}"),
            file=sys.stderr,
        )
    emit(json.dumps(state_to_dict(state), indent=args.indent))
    return EXIT_OK


# ------------------------------------------------------------------ tvms
def add_tvms(sub: Subparsers) -> None:
    """``mjtvm tvms [STATE|GRASP|-] [--grasp NAME]``: prints mjtvm.tvms/1."""
    p = command(sub, "tvms", *_TEXTS["tvms"])
    p.add_argument("state", nargs="?", default=None, type=source, metavar="STATE|GRASP", help=_SOURCE_HELP)
    grasp_option(p, default=None)
    hand_option(p)
    p.add_argument("--no-rvds", action="store_true", help="ignore the state's RVDS (no cone restriction)")
    p.add_argument(
        "--method",
        choices=("auto", "lp", "cdd", "zonotope"),
        default="auto",
        help="auto: the joint-speed box's image when no force binds, else lp; lp: LP projection; "
        "cdd: vertex enumeration; zonotope: the box's image or exit 2",
    )
    time_limit_option(p)
    p.add_argument(
        "--tolerance",
        type=fraction,
        default=0.0,
        metavar="REL",
        help="`tvms --method lp`: stop once the volume bracket's relative gap `(outer - inner) / outer` "
        "is at most REL (`0`: exact within floating point)",
    )
    memory = p.add_argument(
        "--memory",
        type=memory_size,
        default=None,
        metavar="SIZE",
        help="`tvms --method lp`: memory the projection may add to the process (`512M`, `2G`, `1.5GiB`, "
        'bytes, or `25%%` of the available memory); reaching it stops with `status: "approximate"`, '
        "or exit 3 naming the budget when not even a bracket fits",
    )
    computed_default(memory, "`25%` of the available memory")
    p.add_argument(
        "--confidence",
        type=fraction,
        default=DEFAULT_CONFIDENCE,
        metavar="P",
        help="`tvms --method lp` with `--tolerance`: when the certified bracket stays wider than REL, "
        "estimate the volume by random points and LPs until an interval (`volume_estimate`) that "
        "holds it with probability P is that narrow (`0`: none); the cutting planes then stop at "
        "half of `--time-limit`",
    )
    indent_option(p)
    quiet_option(p)
    png_option(p)
    refused_option(
        p,
        "--limit-horizon",
        "Problem 1 has no travel horizon, only the on-limit rows (its twist has no alpha: docs/joint-limits.md)",
    )
    p.set_defaults(func=_cmd_tvms)


def _cmd_tvms(args: argparse.Namespace) -> int:
    from mjtvm.polytopes.tvms import tvms  # Problem 1 needs scipy's Qhull and (for cdd) pycddlib

    if args.grasp is not None and args.state is not None:
        raise OptionError("--grasp", "give STATE or --grasp, not both")
    _check_png(args.png)
    state = load_source(args.grasp or args.state, hand=args.hand, warnings=not args.quiet)
    if args.no_rvds:
        state = state.with_(rvds=None)
    show = not args.quiet and args.method in ("auto", "lp")
    with lp_progress(show, "tvms"), bracket_progress(show) as progress:
        result = tvms(
            state,
            method=args.method,
            time_limit=args.time_limit,
            tolerance=args.tolerance,
            memory=args.memory,
            progress=progress,
            confidence=args.confidence,
        )
    document = result.to_dict()
    emit(json.dumps(document, indent=args.indent))
    if args.png is not None:
        from mjtvm.jobs.result_figures import tvms_png  # matplotlib: only with --png

        title = _source_name(args.grasp or args.state, "STATE")
        _write_png(args.png, tvms_png(document, title))
    return EXIT_OK
