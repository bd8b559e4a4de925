r"""The ``mjtvm`` command line: thin wrappers over the library (the options: ``docs/cli.md``).

Exit codes
----------
0
    Success (also ``--help`` and ``--version``).
1
    Another failure the package reports (e.g. a rerun recording that fails).
2
    Bad input, printed as one line ``error: <what>: <expected>`` on stderr: a malformed or
    out-of-range option (argparse's errors too, followed by ``(try 'mjtvm CMD --help')``), an
    invalid state file (:class:`~mjtvm.errors.StateError`) or scenario
    (:class:`~mjtvm.errors.ModelError`), an output folder that cannot be written or is in use
    by another run (:class:`~mjtvm.errors.OutputError`, checked before any work), an
    unreachable ``--cluster``.
3
    Solver trouble (:class:`~mjtvm.errors.SolverError`): ``solver error: ...``.
130
    Interrupted (Ctrl-C, SIGINT): one line ``mjtvm: interrupted``, no traceback; output
    files are either untouched or complete (``sweep`` keeps a checkpoint of its finished rows).
141
    Standard output closed early (``mjtvm solve | head -c 10``): nothing more is printed.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import re
import sys
from collections.abc import Callable, Iterator, Sequence
from importlib import metadata, resources
from pathlib import Path
from typing import Any, NoReturn

from .core.solvers import SOLVERS
from .core.state import GraspState, load_state
from .core.tvmmp import tvmmp
from .errors import MjtvmError, ModelError, OutputError, SolverError, StateError

__all__ = ["main"]

EXIT_OK, EXIT_FAILURE, EXIT_INPUT, EXIT_SOLVER, EXIT_INTERRUPTED, EXIT_PIPE = 0, 1, 2, 3, 130, 141
CONTACTS = ("L", "S")
READINGS = ("physical", "literal")


def example_path(name: str = "pinch.json") -> str:
    """Path of a state shipped in ``mjtvm/data/examples``."""
    return str(resources.files("mjtvm.data").joinpath("examples").joinpath(name))


# ------------------------------------------------------------------ the parser
class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``error: --states: expected ... (try 'mjtvm sweep --help')``."""

    def error(self, message: str) -> NoReturn:
        message = message.removeprefix("argument ")  # "argument --states: ..." names the option
        self.exit(EXIT_INPUT, f"error: {message} (try '{self.prog} --help')\n")


class _Formatter(argparse.ArgumentDefaultsHelpFormatter):
    """Show every option's default, except for flags (off) and options without one."""

    def _get_help_string(self, action: argparse.Action) -> str:
        if action.default is None or isinstance(action.default, bool) or action.default is argparse.SUPPRESS:
            return action.help or ""
        return super()._get_help_string(action) or ""


class _Deprecated(argparse.Action):
    """A hidden old spelling: stores into the new option's destination, with a notice on stderr."""

    def __init__(self, option_strings: list[str], dest: str, *, new: str, **kwargs: Any) -> None:
        self.new = new
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:  # fmt: skip
        print(f"mjtvm: {option_string} is deprecated, use {self.new}", file=sys.stderr)
        setattr(namespace, self.dest, self.const if self.nargs == 0 else values)


def deprecated_alias(parser: argparse.ArgumentParser, old: str, new: argparse.Action) -> None:
    """Accept ``old`` as a hidden alias of the option ``new`` (same type), with a notice."""
    kwargs: dict[str, Any] = {"nargs": 0, "const": new.const} if new.nargs == 0 else {"type": new.type}
    parser.add_argument(old, dest=new.dest, action=_Deprecated, new=new.option_strings[0],
                        help=argparse.SUPPRESS, default=argparse.SUPPRESS, **kwargs)  # fmt: skip


class _Removed(argparse.Action):
    """A dropped spelling: a one-line error saying what replaced it."""

    def __init__(self, option_strings: list[str], dest: str, *, hint: str, **kwargs: Any) -> None:
        self.hint = hint
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:  # fmt: skip
        parser.error(f"{option_string}: no longer an option: {self.hint}")


def removed_option(parser: argparse.ArgumentParser, old: str, hint: str) -> None:
    """Refuse ``old`` (one value) with a hint, instead of argparse's bare "unrecognized"."""
    parser.add_argument(old, action=_Removed, hint=hint, help=argparse.SUPPRESS, default=argparse.SUPPRESS)


# -------------------------------------------------------- value types (argparse)
def integer(low: int, *, hint: str = "") -> Callable[[str], int]:
    """An argparse type: an integer >= ``low`` (``1.5``, ``nan`` and ``0,3`` are errors)."""

    def parse(text: str) -> int:
        try:
            value = int(text.strip(), 10)
        except ValueError:
            value = None
        if value is None or value < low:
            extra = f" ({hint})" if hint and "," in text else ""
            raise argparse.ArgumentTypeError(f"expected an integer >= {low}, got {text!r}{extra}")
        return value

    return parse


def _float(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def number(low: float | None = None, *, strict: bool = False) -> Callable[[str], float]:
    """An argparse type: a finite number, ``> low`` (``strict``) or ``>= low``."""
    bound = "" if low is None else f" {'>' if strict else '>='} {low:g}"

    def parse(text: str) -> float:
        value = _float(text)
        if value is None or (low is not None and (value <= low if strict else value < low)):
            raise argparse.ArgumentTypeError(f"expected a finite number{bound}, got {text!r}")
        return value

    return parse


def numbers(low: float | None = None) -> Callable[[str], tuple[float, ...]]:
    """An argparse type: comma-separated finite numbers ``>= low``."""
    one = number(low)

    def parse(text: str) -> tuple[float, ...]:
        try:
            return tuple(one(v) for v in text.split(","))
        except argparse.ArgumentTypeError:
            bound = "" if low is None else f" >= {low:g}"
            raise argparse.ArgumentTypeError(
                f"expected comma-separated finite numbers{bound}, got {text!r}"
            ) from None

    return parse


def integers(low: int) -> Callable[[str], tuple[int, ...]]:
    """An argparse type: comma-separated integers ``>= low``."""
    one = integer(low)

    def parse(text: str) -> tuple[int, ...]:
        try:
            return tuple(one(v) for v in text.split(","))
        except argparse.ArgumentTypeError:
            raise argparse.ArgumentTypeError(
                f"expected comma-separated integers >= {low}, got {text!r}"
            ) from None

    return parse


def choices(allowed: Sequence[str], *, every: str | None = None) -> Callable[[str], tuple[str, ...]]:
    """An argparse type: distinct comma-separated values of ``allowed`` (``every``: all of them)."""
    expected = ",".join(allowed) + (f" or {every}" if every else "")

    def parse(text: str) -> tuple[str, ...]:
        if every is not None and text.strip() == every:
            return tuple(allowed)
        values = tuple(v.strip() for v in text.split(","))
        if not text.strip() or len(set(values)) != len(values) or any(v not in allowed for v in values):
            raise argparse.ArgumentTypeError(f"expected distinct values among {expected}, got {text!r}")
        return values

    return parse


def names(text: str) -> tuple[str, ...]:
    """An argparse type: non-empty comma-separated names."""
    values = tuple(v.strip() for v in text.split(","))
    if not all(values):
        raise argparse.ArgumentTypeError(f"expected comma-separated names, got {text!r}")
    return values


_STEM = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")


def stem(text: str) -> str:
    """An argparse type: a file stem (letters, digits, ``_ . -``; no folder, no leading dot)."""
    if not _STEM.fullmatch(text):
        raise argparse.ArgumentTypeError(
            f"expected a file stem of letters, digits, '_', '.', '-' (no '/'), got {text!r}"
        )
    return text


def folder(text: str) -> str:
    """An argparse type: an output folder (a ``.json``/``.csv`` path is the old file form)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a folder, got ''")
    if Path(text).suffix in (".json", ".csv", ".md") and not Path(text).is_dir():
        raise argparse.ArgumentTypeError(
            f"expected a folder (the output files are written inside it), got the file name {text!r}"
        )
    return text


_CLUSTER = re.compile(r"(?:(tcp|tls|ucx|ws|wss)://)?\[?[A-Za-z0-9_.:-]+\]?:\d{1,5}")


def cluster_address(text: str) -> str:
    """An argparse type: a Dask scheduler address ``[tcp://]HOST:PORT``."""
    if not _CLUSTER.fullmatch(text.strip()) or not 0 < int(text.rsplit(":", 1)[1]) < 65536:
        raise argparse.ArgumentTypeError(f"expected a scheduler address tcp://HOST:PORT, got {text!r}")
    return text.strip()


# ------------------------------------------------------------------ output
def _stdout_to_devnull() -> None:
    """Point file descriptor 1 at /dev/null so that the interpreter's final flush is silent
    (the recipe of Python's signal documentation for SIGPIPE)."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # captured in-process: nothing to redirect
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def emit(text: str) -> None:
    """Print a line to stdout and flush, so that a full or closed stdout is reported here."""
    try:
        sys.stdout.write(text + "\n")
        sys.stdout.flush()
    except BrokenPipeError:
        raise
    except OSError as e:
        _stdout_to_devnull()
        raise OutputError("standard output", getattr(sys.stdout, "name", "<stdout>"),
                          f"cannot write ({e.strerror or e})") from e  # fmt: skip


@contextlib.contextmanager
def _lp_progress(enabled: bool, desc: str) -> Iterator[None]:
    """A spinner on stderr counting the HiGHS solves (Problem 1 does not know their number
    in advance: the projection adds facets until the polytope closes)."""
    if not enabled:
        yield
        return
    import highspy
    from tqdm import tqdm

    bar = tqdm(desc=desc, unit=" LP", file=sys.stderr, mininterval=0.25, leave=False)
    original = highspy.Highs.run

    def run(self: Any) -> Any:
        try:
            return original(self)
        finally:
            bar.update()

    highspy.Highs.run = run  # type: ignore[method-assign]
    try:
        yield
    finally:
        highspy.Highs.run = original  # type: ignore[method-assign]
        bar.close()


# ------------------------------------------------------------------ commands
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


def _cmd_export_state(args: argparse.Namespace) -> int:
    from .sim.scenario import export_state  # MuJoCo is imported only by the coupling commands

    options = {"variant": args.hand}
    if args.mg is not None:
        options["mg"] = args.mg
    emit(json.dumps(export_state(args.scenario, **options), indent=args.indent))
    return EXIT_OK


def _check_file_folder(path: str | None, option: str) -> None:
    if path is not None:
        from .core.files import check_output_dir

        check_output_dir(Path(path).parent if str(Path(path).parent) else ".", option=option)


def _cmd_replay(args: argparse.Namespace) -> int:
    from .apps.replay import ReplayOutput, run_replay  # MuJoCo and matplotlib: only the coupling commands
    from .core.files import check_output_dir, output_lock
    from .viewer.recording import RecordingJob, start_recording

    outdir = check_output_dir(args.out)
    _check_file_folder(args.rrd, "--rrd")
    jobs: list[RecordingJob] = []

    def record(replayed: ReplayOutput) -> None:  # rerun: only in the recording's process
        jobs.append(start_recording(replayed, args.rrd, spawn=args.spawn, tvms_every=args.tvms_every))

    with output_lock(outdir):
        try:
            out = run_replay(
                scenario=args.scenario, hand=args.hand, mu=args.mu, mg=args.mg, num_states=args.states,
                variants=args.contacts, readings=args.reading, out=outdir,
                plots=not args.no_plots, sweeps=not args.no_sweeps, progress=not args.quiet,
                on_replay=record if args.rrd is not None or args.spawn else None,
            )  # fmt: skip
        except BaseException:
            for job in jobs:
                job.cancel()
            raise
        infos = [job.result() for job in jobs]
    lift = out.lift
    emit(f"lift: {lift.num_states} states, z = {lift.z[0]:.4f} .. {lift.z[-1]:.4f} m ({lift.limit})")
    for name, path in out.files.items():
        emit(f"wrote {name}: {path}")
    for info in infos:
        if args.rrd is not None:
            emit(f"wrote {Path(args.rrd).name}: {args.rrd} ({info['seconds']:.2f} s)")
    return EXIT_OK


def _load_state_or_scenario(args: argparse.Namespace) -> GraspState:
    if args.scenario is not None:
        from .sim.scenario import load_scenario  # MuJoCo only for scenario shortcuts

        return load_scenario(args.scenario, variant=args.hand).state()
    if args.state is None:
        raise StateError("state", "give a mjtvm.state/1 file (or -) or --scenario NAME")
    source = sys.stdin.read() if args.state == "-" else args.state
    return load_state(source)


def _cmd_tvms(args: argparse.Namespace) -> int:
    from .polytopes.tvms import tvms  # Problem 1 needs scipy's Qhull and (for cdd) pycddlib

    state = _load_state_or_scenario(args)
    if args.no_rvds:
        state = state.with_(rvds=None)
    with _lp_progress(not args.quiet and args.method == "lp", "tvms"):
        result = tvms(state, method=args.method, time_limit=args.time_limit)
    emit(json.dumps(result.to_dict(), indent=args.indent))
    return EXIT_OK


def _cmd_verify(args: argparse.Namespace) -> int:
    from .physics.verify import run  # MuJoCo rollouts: imported only when used

    return run(args)


def _cmd_sweep(args: argparse.Namespace) -> int:
    from .apps.sweep import run_sweep_files

    files = run_sweep_files(args, emit=emit)
    for path in files:
        emit(f"wrote {path}")
    return EXIT_OK


def _cmd_bench(args: argparse.Namespace) -> int:
    from .bench.report import run_from_args  # cvxpy, MuJoCo and the pool: imported only when used

    return run_from_args(args, emit=emit)


def _version() -> str:
    try:
        return metadata.version("mjtvm")
    except metadata.PackageNotFoundError:  # pragma: no cover - run from a source tree
        return "unknown"


def _common_out(p: argparse.ArgumentParser, *, name: str | None) -> None:
    p.add_argument("--out", type=folder, default="results", metavar="DIR",
                   help="output folder (created if missing; locked while the run writes)")  # fmt: skip
    if name is not None:
        p.add_argument("--name", type=stem, default=name, help="file stem of the outputs in --out")


def _lift_options(p: argparse.ArgumentParser, *, contacts: str, reading: str) -> None:
    p.add_argument("--scenario", default="case2", help="scenario name or path of a scenario JSON file")
    new = p.add_argument("--hand", default="default", help="hand model: default or humanlike")
    deprecated_alias(p, "--variant", new)
    p.add_argument("--mu", type=number(0.0), default=0.3, help="friction coefficient")
    p.add_argument("--mg", type=number(0.0), default=1.0, help="object weight (N)")
    p.add_argument(
        "--states", type=integer(2), default=30, metavar="N", help="number of states along the lift"
    )
    new = p.add_argument(
        "--contacts", type=choices(CONTACTS), default=contacts, metavar="L,S",
        help="contact types of fingers 2 and 4 (L: line/rolling, S: sliding), comma-separated",
    )  # fmt: skip
    deprecated_alias(p, "--variants", new)
    p.add_argument(
        "--reading", type=choices(READINGS, every="both"), default=reading, metavar="READING",
        help="slide direction of S-points: physical (the slip of the min-norm motion), literal "
        "(the paper's printed vector), a comma list, or both",
    )  # fmt: skip


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``mjtvm`` (``verify``'s options: :func:`mjtvm.physics.verify.add_arguments`)."""
    parser = _Parser(
        prog="mjtvm", formatter_class=_Formatter,
        description="Joint torque-velocity pair based manipulability (Watanabe) of robot hands. "
        "Exit codes: 0 ok, 2 bad input, 3 solver trouble, 130 interrupted (docs/cli.md).",
    )  # fmt: skip
    parser.add_argument("--version", action="version", version=f"mjtvm {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name: str, help: str, description: str) -> argparse.ArgumentParser:
        return sub.add_parser(name, help=help, description=description, formatter_class=_Formatter)

    solve = command(
        "solve", "Problem 2: TVMMP of one mjtvm.state/1 grasp state (prints mjtvm.result/1)",
        "Solve Problem 2 (eq. 31-35) for STATE and print the mjtvm.result/1 JSON.",
    )  # fmt: skip
    solve.add_argument(
        "state", nargs="?", default=None,
        help="mjtvm.state/1 JSON file, or - for standard input (default: the shipped example pinch.json)",
    )  # fmt: skip
    solve.add_argument("--solver", choices=SOLVERS, default="highs", help="LP backend")
    solve.add_argument(
        "--box", choices=("eliminated", "literal"), default="eliminated",
        help="operation-range form: exact reduction or the paper's literal eq. 2 box",
    )  # fmt: skip
    solve.add_argument("--no-witnesses", action="store_true", help="omit forces, torques, speeds and boxes")
    solve.add_argument("--indent", type=integer(0), default=1, help="JSON indentation")
    solve.set_defaults(func=_cmd_solve)

    export = command(
        "export-state", "print the mjtvm.state/1 grasp state of a scenario, computed by MuJoCo",
        "Build a scenario's grasp state from the MuJoCo model (mj_forward) and print it.",
    )  # fmt: skip
    export.add_argument(
        "--scenario",
        required=True,
        help="scenario name (case1, case1-s, case2) or path of a scenario JSON file",
    )
    new = export.add_argument("--hand", default="default", help="hand model: default or humanlike")
    deprecated_alias(export, "--variant", new)
    export.add_argument(
        "--mg", type=number(0.0), default=None, help="object weight (N); default: the scenario's"
    )
    export.add_argument("--indent", type=integer(0), default=1, help="JSON indentation")
    export.set_defaults(func=_cmd_export_state)

    replay = command(
        "replay", "TVMMP along the scripted lift of Case 2 (Fig. 8) and the Fig. 9 sweeps; CSV, JSON, PNG",
        "Lift the object along +z to the fingers' reach, solve Problem 2 at every state with fingers 2 "
        "and 4 as L- and S-points, sweep mu and mg (Fig. 9), and write lift.csv, lift.json, "
        "lift-sweeps.csv and fig8/fig9a/fig9b.png to --out, as one set, atomically.",
    )  # fmt: skip
    _lift_options(replay, contacts="L,S", reading="physical")
    _common_out(replay, name=None)
    replay.add_argument("--no-plots", action="store_true", help="do not write the PNG plots")
    replay.add_argument("--no-sweeps", action="store_true", help="skip the Fig. 9 mu and mg sweeps")
    replay.add_argument("--quiet", action="store_true", help="no progress bars")
    replay.add_argument(
        "--rrd", metavar="FILE", default=None,
        help="also write a rerun recording of the lift (scene, contacts, velocity polytopes, TVMMP, "
        "joint operation points); open it with `rerun FILE`",
    )  # fmt: skip
    replay.add_argument(
        "--spawn", action="store_true", help="also stream the recording to a new rerun viewer"
    )
    replay.add_argument(
        "--tvms-every", type=integer(0), default=5, metavar="N",
        help="TVMS (Problem 1) in the recording at every N-th state and the last; 0: never",
    )  # fmt: skip
    replay.set_defaults(func=_cmd_replay)

    tv = command(
        "tvms", "Problem 1: the exact TVMS polytope and its volume (prints mjtvm.tvms/1)",
        "Solve Problem 1 (eq. 26-29, 34) for STATE or a scenario and print mjtvm.tvms/1.",
    )  # fmt: skip
    tv.add_argument("state", nargs="?", default=None, help="mjtvm.state/1 JSON file, or - for standard input")
    tv.add_argument("--scenario", default=None, help="a scenario instead of a file: case1, case1-s, case2")
    new = tv.add_argument("--hand", default="default", help="hand model of --scenario: default or humanlike")
    deprecated_alias(tv, "--variant", new)
    tv.add_argument("--no-rvds", action="store_true", help="ignore the state's RVDS (no cone restriction)")
    tv.add_argument("--method", choices=("lp", "cdd"), default="lp", help="LP projection or cdd enumeration")
    tv.add_argument(
        "--time-limit",
        type=number(0.0, strict=True),
        default=120.0,
        metavar="S",
        help="cap of the cdd method (s)",
    )
    tv.add_argument("--indent", type=integer(0), default=1, help="JSON indentation")
    tv.add_argument("--quiet", action="store_true", help="no progress spinner (LPs solved) on stderr")
    tv.set_defaults(func=_cmd_tvms)

    sub.add_parser(
        "verify", add_help=False,  # its options come from mjtvm.physics.verify (MuJoCo), parsed in main()
        help="check TVMMP along the lift against MuJoCo rollouts with the dcmotor actuators",
    )  # fmt: skip

    sweep = command(
        "sweep", "Problem 2 over a grid of lift states and conditions (process pool or Dask)",
        "TVMMP over the product of the given values (every list is comma-separated); rows written "
        "to NAME.json and NAME.csv in --out, atomically, with a checkpoint NAME.partial.json of the "
        "finished rows while it runs (--resume continues from it).",
    )  # fmt: skip
    sweep.add_argument("--scenario", type=names, default="case2", help="scenarios")
    new = sweep.add_argument("--hand", type=names, default="default", help="hand models: default, humanlike")
    sweep.add_argument("--contacts", type=choices(CONTACTS), default="L", metavar="L,S",
                       help="contact types of fingers 2 and 4")  # fmt: skip
    deprecated_alias(sweep, "--variants", sweep._option_string_actions["--contacts"])
    new = sweep.add_argument("--reading", type=choices(READINGS, every="both"), default="physical",
                             metavar="READING", help="slide directions of S-points: physical, literal or both")  # fmt: skip
    deprecated_alias(sweep, "--readings", new)
    sweep.add_argument("--mu", type=numbers(0.0), default="0.3", help="friction coefficients")
    sweep.add_argument("--mg", type=numbers(0.0), default="1.0", help="object weights (N)")
    new = sweep.add_argument("--states", type=integer(2, hint="state indices are --state-indices"),
                             default=30, metavar="N", help="number of states along the lift")  # fmt: skip
    deprecated_alias(sweep, "--num-states", new)
    sweep.add_argument("--state-indices", type=integers(0), default=None, metavar="I,J",
                       help="solve only these states of the lift (default: all)")  # fmt: skip
    sweep.add_argument("--jobs", type=integer(1), default=1, help="local worker processes")
    sweep.add_argument("--cluster", type=cluster_address, default=None, metavar="tcp://HOST:PORT",
                       help="Dask scheduler address (overrides --jobs; connection timeout 10 s)")  # fmt: skip
    _common_out(sweep, name="sweep")
    sweep.add_argument("--resume", action="store_true",
                       help="keep the finished rows of NAME.partial.json / NAME.json that belong to this grid")  # fmt: skip
    sweep.add_argument("--quiet", action="store_true", help="no progress bar")
    sweep.set_defaults(func=_cmd_sweep)

    from .bench.report import add_arguments as bench_arguments  # numpy only at import

    bench = command(
        "bench", "the benchmark run: paper cases vs cvxpy/cdd, the lift, the sweeps on 1 and 2 processes, scaling",
        "Time the paper's cases (Problem 1 and 2) against the cvxpy and cdd baselines, the full lift, "
        "the Fig. 9 sweeps on 1 and 2 processes and synthetic hands of 2-16 fingers; write NAME.json "
        "and NAME.md to --out.",
    )  # fmt: skip
    bench_arguments(bench)
    bench.set_defaults(func=_cmd_bench)
    return parser


def verify_parser() -> argparse.ArgumentParser:
    """The parser of ``mjtvm verify`` (imports MuJoCo: built only when that command runs)."""
    from .physics.verify import add_arguments

    parser = _Parser(
        prog="mjtvm verify", formatter_class=_Formatter,
        description="alpha_sim (MuJoCo rollouts, bisection on the speed factor) against alpha_kl along "
        "the lift; writes NAME.csv and NAME.png (and slide-check.csv) to --out, atomically.",
    )  # fmt: skip
    add_arguments(parser)
    parser.set_defaults(func=_cmd_verify)
    return parser


def _parse(words: list[str]) -> argparse.Namespace:
    if words[:1] == ["verify"]:
        return verify_parser().parse_args(words[1:])
    return build_parser().parse_args(words)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mjtvm`` console script; returns the exit code (module docstring)."""
    words = list(sys.argv[1:] if argv is None else argv)
    try:
        try:
            args = _parse(words)
        except SystemExit as e:  # --help, --version and argparse's (one-line) errors
            return e.code if isinstance(e.code, int) else EXIT_INPUT
        code: int = args.func(args)
        sys.stdout.flush()  # a closed or full stdout is reported here, not at interpreter exit
        return code
    except KeyboardInterrupt:
        print("mjtvm: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        _stdout_to_devnull()
        return EXIT_PIPE
    except (StateError, ModelError, OutputError) as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_INPUT
    except SolverError as e:
        print(f"solver error: {e}", file=sys.stderr)
        return EXIT_SOLVER
    except MjtvmError as e:  # e.g. a RecordingError
        print(f"error: {e}", file=sys.stderr)
        return EXIT_FAILURE


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
