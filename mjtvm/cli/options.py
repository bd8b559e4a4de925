"""The parser and help formatter, computed defaults, and removed or refused options (one line
with a hint). The options several commands share are in [`vocabulary`][mjtvm.cli.vocabulary]."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any, NoReturn

from mjtvm.cli.output import EXIT_INPUT, help_hint, one_line
from mjtvm.cli.values import (
    accepted,
)

__all__ = [
    "Formatter",
    "Parser",
    "Subparsers",
    "command",
    "computed_default",
    "refused_option",
    "removed_option",
    "shown_default",
]


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``error: --states: expected ... (try 'mjtvm sweep --help')``,
    and help that shows the defaults ([`Formatter`][mjtvm.cli.options.Formatter])."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", Formatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        message = message.removeprefix("argument ")  # "argument --states: ..." names the option
        self.exit(EXIT_INPUT, f"error: {one_line(message)} {help_hint(self.prog)}\n")


if TYPE_CHECKING:
    Subparsers = argparse._SubParsersAction[Parser]
else:
    Subparsers = argparse._SubParsersAction
"""The subcommands of ``mjtvm`` (``parser.add_subparsers()``)."""


def computed_default(action: argparse.Action, text: str) -> argparse.Action:
    """Say what the default of ``action`` is where the parser's is None and the command computes
    it (``"the grasp's"``): ``--help`` and docs/cli.md show ``text`` (backticks: literals)."""
    action.computed_default = text  # type: ignore[attr-defined]
    return action


def shown_default(action: argparse.Action) -> str | None:
    """The default of ``action`` as ``--help`` and docs/cli.md show it: its
    [`computed_default()`][mjtvm.cli.options.computed_default], else the value in backticks; None
    for a flag (off) and an option without a default."""
    text = getattr(action, "computed_default", None)
    if isinstance(text, str):
        return text
    if action.default is None or isinstance(action.default, bool) or action.default is argparse.SUPPRESS:
        return None
    return f"`{action.default}`"


class Formatter(argparse.HelpFormatter):
    """Every option's help followed by what it accepts and its default (``(integer in [0, 16];
    default: 1)``; flags: off, no default shown); backticks, which mark literals for
    docs/cli.md, are left out."""

    def _get_help_string(self, action: argparse.Action) -> str:
        default = shown_default(action)
        extras = [
            text.replace("%", "%%")  # help strings are %-formatted (%(default)s)
            for text in (accepted(action.type), None if default is None else f"default: {default}")
            if text
        ]
        return ((action.help or "") + (f" ({'; '.join(extras)})" if extras else "")).replace("`", "")


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


# ------------------------------------------------------------ the vocabulary
# One help text per option, whichever command has it: docs/cli.md's table is generated from them
# (tools/cli_tables.py), and a command's remark names the command. Backticks mark literals (the
# table keeps them, --help leaves them out); docs/NAME.md becomes a link in the table.
