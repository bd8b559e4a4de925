"""The ``mjtvm`` parser (one builder per command group) and [`main()`][mjtvm.cli.parser.main]: errors to exit codes."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from typing import Any

from mjtvm.cli.lift import add_replay, add_sweep
from mjtvm.cli.options import Parser
from mjtvm.cli.output import (
    EXIT_FAILURE,
    EXIT_INPUT,
    EXIT_INTERRUPTED,
    EXIT_PIPE,
    EXIT_SOLVER,
    help_hint,
    one_line,
    stdout_to_devnull,
)
from mjtvm.cli.rank import add_rank
from mjtvm.cli.show import add_show
from mjtvm.cli.solve import add_export_state, add_solve, add_tvms
from mjtvm.cli.verify import verify_parser
from mjtvm.errors import MjtvmError, ModelError, OptionError, OutputError, ParamError, SolverError, StateError

__all__ = ["build_parser", "guarded", "main"]


def _version() -> str:
    from importlib import metadata  # with the email parser it reads: ~15 ms every command would pay

    try:
        return metadata.version("mjtvm")
    except metadata.PackageNotFoundError:  # pragma: no cover - run from a source tree
        return "unknown"


class _VersionAction(argparse.Action):
    """``--version``: argparse's version action, the version read only when asked for."""

    def __init__(self, option_strings: Sequence[str], dest: str = argparse.SUPPRESS, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, *_: Any) -> None:
        print(f"mjtvm {_version()}")
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``mjtvm`` (``verify``'s options: [`mjtvm.cli.verify.add_arguments()`][mjtvm.cli.verify.add_arguments])."""
    parser = Parser(
        prog="mjtvm",
        description="Joint torque-velocity pair based manipulability (Watanabe) of robot hands. "
        "Exit codes: 0 ok, 2 bad input, 3 solver trouble, 130 interrupted (docs/cli.md).",
    )
    parser.add_argument("--version", action=_VersionAction, help="show the version and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    add_solve(sub)
    add_export_state(sub)
    add_replay(sub)
    add_tvms(sub)
    add_show(sub)
    sub.add_parser(
        "verify",
        add_help=False,  # its options import MuJoCo: parsed by verify_parser() in main()
        help="check TVMMP along the lift against MuJoCo rollouts with the dcmotor actuators",
    )
    add_sweep(sub)
    add_rank(sub)
    return parser


def _parse(words: list[str]) -> argparse.Namespace:
    if words[:1] == ["--version"] and len(words) > 1:  # argparse would print it and drop the rest
        build_parser().error(f"--version: takes no other arguments, got {words[1]!r}")
    if words[:1] == ["verify"]:
        return verify_parser().parse_args(words[1:])
    parser = build_parser()
    args, extra = parser.parse_known_args(words)
    if extra:  # argparse's top level would name itself: the hint is the command's
        commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        commands.choices[args.command].error(f"unrecognized arguments: {' '.join(extra)}")
    return args


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mjtvm`` console script; returns the exit code ([`mjtvm.cli`][mjtvm.cli])."""
    words = list(sys.argv[1:] if argv is None else argv)
    prog = f"mjtvm {words[0]}" if words[:1] and not words[0].startswith("-") else "mjtvm"
    return guarded(lambda: _parse(words), lambda args: int(args.func(args)), prog=prog)


def guarded(
    parse: Callable[[], argparse.Namespace],
    run: Callable[[argparse.Namespace], int],
    *,
    prog: str | None = None,
) -> int:
    """Parse and run a command, mapping the error family to exit codes (``docs/cli.md``).

    Parameters
    ----------
    parse
        Returns the parsed options (argparse's ``SystemExit`` is its exit code).
    run
        Runs the command on them; returns its exit code.
    prog
        The command (``mjtvm sweep``): an option refused while it runs
        ([`OptionError`][mjtvm.errors.OptionError]) ends with the hint argparse's errors end
        with, ``(try 'mjtvm sweep --help')``; None: no hint.

    Returns
    -------
    int
        0 ok, 1 another failure, 2 bad input, 3 solver trouble, 130 interrupted, 141 a closed
        standard output; each error printed as one line on stderr, never a traceback.
    """
    try:
        try:
            args = parse()
        except SystemExit as e:  # --help, --version and argparse's (one-line) errors
            return e.code if isinstance(e.code, int) else EXIT_INPUT
        code = run(args)
        sys.stdout.flush()  # a closed or full stdout is reported here, not at interpreter exit
        return code
    except KeyboardInterrupt:
        print("mjtvm: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        stdout_to_devnull()
        return EXIT_PIPE
    except OptionError as e:
        hint = "" if prog is None else f" {help_hint(prog)}"
        print(f"error: {one_line(str(e))}{hint}", file=sys.stderr)
        return EXIT_INPUT
    except (StateError, ModelError, OutputError, ParamError) as e:
        print(f"error: {one_line(str(e))}", file=sys.stderr)
        return EXIT_INPUT
    except SolverError as e:
        print(f"solver error: {one_line(str(e))}", file=sys.stderr)
        return EXIT_SOLVER
    except MjtvmError as e:  # e.g. a RecordingError
        print(f"error: {one_line(str(e))}", file=sys.stderr)
        return EXIT_FAILURE
