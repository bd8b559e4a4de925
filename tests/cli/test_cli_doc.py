"""docs/cli.md's vocabulary table against the parsers: each option's commands are exactly
those whose parser has it (a command that refuses an option is not listed)."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from mjtvm.cli import build_parser, verify_parser

DOC = Path(__file__).resolve().parents[2] / "docs" / "cli.md"


def _table() -> dict[str, set[str]]:
    """``{option: {command, ...}}`` of the table under "## One vocabulary"."""
    text = DOC.read_text(encoding="utf-8").split("## One vocabulary", 1)[1].split("\n\n### ", 1)[0]
    rows = {}
    for line in text.splitlines():
        m = re.match(r"^\| `(--[a-z-]+)[^`]*` \|.*\| ([a-z, -]+) \|$", line)
        if m:
            rows[m.group(1)] = {c.strip() for c in m.group(2).split(",")}
    return rows


def _options() -> dict[str, set[str]]:
    """``{command: {option, ...}}``: the visible options of every command's parser."""
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    parsers = {name: p for name, p in sub.choices.items() if name != "verify"}
    parsers["verify"] = verify_parser()
    return {
        name: {s for a in p._actions if a.help != argparse.SUPPRESS for s in a.option_strings}
        for name, p in parsers.items()
    }


def test_the_vocabulary_table_lists_exactly_the_commands_that_take_each_option() -> None:
    table, options = _table(), _options()
    assert len(table) > 10
    wrong = {}
    for option, listed in table.items():
        actual = {name for name, opts in options.items() if option in opts}
        if listed != actual:
            wrong[option] = (sorted(listed - actual), sorted(actual - listed))
    assert not wrong, f"option: (listed but not taken, taken but not listed): {wrong}"
