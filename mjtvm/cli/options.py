"""The parser and help formatter, removed options (refused with a hint), and option groups
that several commands share (the vocabulary of ``docs/cli.md``)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any, NoReturn

from mjtvm.cli.output import EXIT_INPUT, one_line
from mjtvm.cli.values import (
    CONTACTS,
    MAX_FORCE,
    MAX_JOBS,
    MAX_MU,
    MAX_STATES,
    READINGS,
    choices,
    cluster_address,
    folder,
    fraction,
    integer,
    number,
    source,
    stem,
)
from mjtvm.errors import OptionError
from mjtvm.model.limits import with_limit_horizon  # the commands' --limit-horizon, one meaning

__all__ = [
    "Formatter",
    "Parser",
    "Subparsers",
    "command",
    "friction_margin_option",
    "hand_option",
    "lift_options",
    "limit_horizon_option",
    "mg_option",
    "mu_option",
    "one_grasp",
    "out_options",
    "parallel_options",
    "refused_option",
    "removed_option",
    "with_limit_horizon",
]


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``error: --states: expected ... (try 'mjtvm sweep --help')``,
    and help that shows the defaults ([`Formatter`][mjtvm.cli.options.Formatter])."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", Formatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        message = message.removeprefix("argument ")  # "argument --states: ..." names the option
        self.exit(EXIT_INPUT, f"error: {one_line(message)} (try '{self.prog} --help')\n")


if TYPE_CHECKING:
    Subparsers = argparse._SubParsersAction[Parser]
else:
    Subparsers = argparse._SubParsersAction
"""The subcommands of ``mjtvm`` (``parser.add_subparsers()``)."""


class Formatter(argparse.ArgumentDefaultsHelpFormatter):
    """Show every option's default, except for flags (off) and options without one."""

    def _get_help_string(self, action: argparse.Action) -> str:
        if action.default is None or isinstance(action.default, bool) or action.default is argparse.SUPPRESS:
            return action.help or ""
        return super()._get_help_string(action) or ""


class _Removed(argparse.Action):
    """A hidden option that is no longer one (or not one of this command): a one-line error
    ``OPTION: WHAT: HINT``."""

    def __init__(
        self,
        option_strings: list[str],
        dest: str,
        *,
        hint: str,
        what: str = "no longer an option",
        **kwargs: Any,
    ) -> None:
        self.hint, self.what = hint, what
        super().__init__(option_strings, dest, **kwargs)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        parser.error(f"{option_string}: {self.what}: {self.hint}")


def removed_option(parser: argparse.ArgumentParser, old: str, hint: str) -> None:
    """Refuse ``old`` (one value) with a hint, instead of argparse's bare "unrecognized"."""
    parser.add_argument(old, action=_Removed, hint=hint, help=argparse.SUPPRESS, default=argparse.SUPPRESS)


def refused_option(parser: argparse.ArgumentParser, option: str, why: str) -> None:
    """Refuse ``option`` (one value), which other commands have, saying ``why`` this one has
    not (argparse would answer "unrecognized arguments", with the next word)."""
    parser.add_argument(
        option,
        action=_Removed,
        hint=why,
        what=f"not an option of {parser.prog.split()[-1]}",
        help=argparse.SUPPRESS,
        default=argparse.SUPPRESS,
    )


def command(sub: Subparsers, name: str, help: str, description: str) -> argparse.ArgumentParser:
    """A subcommand's parser (a [`Parser`][mjtvm.cli.options.Parser], like its parent)."""
    return sub.add_parser(name, help=help, description=description)  # a Parser, with the Formatter


# ------------------------------------------------------------ shared option groups
_OUT_HELP = "output folder (created if missing; locked while the run writes)"


def out_options(
    p: argparse.ArgumentParser,
    *,
    name: str | None,
    out_help: str = _OUT_HELP,
    name_help: str = "file stem of the outputs in --out",
) -> None:
    """``--out DIR`` and (unless ``name`` is None) ``--name STEM`` with the default ``name``."""
    p.add_argument("--out", type=folder, default="results", metavar="DIR", help=out_help)
    if name is not None:
        p.add_argument("--name", type=stem, default=name, help=name_help)


def parallel_options(p: argparse.ArgumentParser) -> None:
    """``--jobs N`` local worker processes and ``--cluster tcp://HOST:PORT`` (a Dask scheduler)."""
    p.add_argument("--jobs", type=integer(1, MAX_JOBS), default=1, help="local worker processes")
    p.add_argument(
        "--cluster",
        type=cluster_address,
        default=None,
        metavar="tcp://HOST:PORT",
        help="Dask scheduler address (overrides --jobs; connection timeout 10 s)",
    )


GRASP_HELP = (
    "grasp: a mjtvm.grasp/1 file (.toml or .json), or a shipped grasp: the paper's case1, case1-s, "
    "case2 (with --hand), or any name in models/*/ (installed as mjtvm.models)"
)


def grasp_option(
    p: argparse.ArgumentParser, *, default: str | None, type: Any = None, help: str = GRASP_HELP
) -> None:
    """``--grasp NAME|FILE``."""
    p.add_argument("--grasp", default=default, type=type or source, metavar="GRASP", help=help)


def one_grasp(positional: str | None, option: str | None, *, name: str = "GRASP") -> str:
    """The grasp of a command that takes it as ``name`` or as ``--grasp``: one of them.

    Raises
    ------
    OptionError
        Both given (which one was meant is not for the command to guess), or neither.
    """
    if positional is not None and option is not None:
        raise OptionError("--grasp", f"give {name} or --grasp, not both")
    source = positional if positional is not None else option
    if source is None:
        raise OptionError(name, "give a grasp file or a shipped grasp name (e.g. case2)")
    return source


def friction_margin_option(p: argparse.ArgumentParser) -> None:
    """``--friction-margin D``: the LPs use (1 - D) mu for every F contact (docs/state-format.md)."""
    p.add_argument(
        "--friction-margin",
        type=fraction,
        default=None,
        metavar="D",
        help="friction margin in [0, 1): the LPs use (1 - D) mu for every F contact's cone; replaces the "
        "state's friction_margin or the grasp file's (combined with its cone: pyramidal x 1/sqrt(2)) "
        "(default: the state's or grasp's, 0)",
    )


def hand_option(
    p: argparse.ArgumentParser, help: str = "hand model of the paper's cases: default or humanlike"
) -> None:
    """``--hand``."""
    p.add_argument("--hand", default="default", help=help)


def mu_option(p: argparse.ArgumentParser) -> None:
    """``--mu X``: one friction coefficient for every contact instead of the grasp's
    ([`with_options()`][mjtvm.grasp.resolve.loaded.Grasp.with_options]; ``replay``, ``solve``)."""
    p.add_argument(
        "--mu",
        type=number(0.0, MAX_MU),
        default=None,
        help="friction coefficient (default: the grasp's, 0.3 for case2)",
    )


def mg_option(p: argparse.ArgumentParser) -> None:
    """``--mg X``: the object's weight (N) instead of the grasp's (its REFS scaled to it;
    [`with_options()`][mjtvm.grasp.resolve.loaded.Grasp.with_options]; ``replay``, ``solve``)."""
    p.add_argument(
        "--mg",
        type=number(0.0, MAX_FORCE),
        default=None,
        help="object weight (N) (default: the grasp's, 1 for case2)",
    )


def states_option(p: argparse.ArgumentParser, *, hint: str = "", minimum: int = 2) -> None:
    """``--states N``: the number of states along the lift (``hint``: added to its error;
    ``minimum``: 1 where one state, the grasp's own, is a check of its own)."""
    p.add_argument(
        "--states",
        type=integer(minimum, MAX_STATES, hint=hint),
        default=30,
        metavar="N",
        help="number of states along the lift"
        + (" (1: the grasp's own state, no lift)" if minimum == 1 else ""),
    )


def lift_options(p: argparse.ArgumentParser, *, contacts: str, reading: str) -> None:
    """The scripted lift of ``replay``: grasp, hand, friction, weight, states, contacts, reading."""
    grasp_option(p, default="case2")
    hand_option(p)
    mu_option(p)
    mg_option(p)
    states_option(p)
    p.add_argument(
        "--stop-margin",
        type=fraction,
        default=None,
        metavar="F",
        help="end the lift where a finger's contact Jacobian keeps this fraction of its smallest singular "
        "value at the start (default: the grasp's, 0.25; 0: to the reach limit)",
    )
    p.add_argument(
        "--contacts",
        type=choices(CONTACTS),
        default=contacts,
        metavar="L,S",
        help="contact types of the lift's L/S fingers (Case 2: fingers 2 and 4; L: line/rolling, "
        "S: sliding), comma-separated",
    )
    p.add_argument(
        "--reading",
        type=choices(READINGS, every="both"),
        default=reading,
        metavar="READING",
        help="slide direction of S-points: physical (the slip of the min-norm motion: friction "
        "resists the lift, what the physics check supports), literal (the paper's printed vector: "
        "reproduces its Fig. 8), a comma list, or both",
    )


def limit_horizon_option(p: argparse.ArgumentParser) -> None:
    """``--limit-horizon M``: Problem 2's travel horizon of the joint limits (m of object travel;
    ``docs/joint-limits.md``), replacing the state's."""
    p.add_argument(
        "--limit-horizon",
        type=number(0.0, 1e3),
        default=None,
        metavar="M",
        help="metres of object travel within which no joint may reach its position limit "
        "(Problem 2; 0: only joints on a limit are held; default: the state's, or the grasp "
        "file's joint_limits.horizon, 0.001)",
    )
