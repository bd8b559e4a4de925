"""docs/cli.md's option tables against the parsers: the tables are what ``tools/cli_tables.py``
generates from them (one help text per option, the defaults, the ranges), and each option's
commands are exactly those whose parser has it (a command that refuses an option is not listed)."""

from __future__ import annotations

import argparse
import importlib.util
import re
import sys
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "cli.md"


def _generator() -> ModuleType:
    """``tools/cli_tables.py``, imported by its path (``tools/`` is not a package)."""
    spec = importlib.util.spec_from_file_location("cli_tables", ROOT / "tools" / "cli_tables.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


cli_tables = _generator()


def test_the_tables_are_generated_from_the_parsers() -> None:
    text = DOC.read_text(encoding="utf-8")
    assert cli_tables.rendered(text, cli_tables.tables()) == text, (
        "docs/cli.md's option tables differ from the parsers': python tools/cli_tables.py --write"
    )


def _table() -> dict[str, set[str]]:
    """``{option: {command, ...}}`` of the table under "## One vocabulary"."""
    text = DOC.read_text(encoding="utf-8").split("## One vocabulary", 1)[1].split("\n\n### ", 1)[0]
    rows = {}
    for line in text.splitlines():
        m = re.match(r"^\| `(--[a-z-]+)[^`]*`(?:, `[^`]*`)* \|.*\| ([a-z, -]+) \|$", line)
        if m:
            rows[m.group(1)] = {c.strip() for c in m.group(2).split(",")}
    return rows


def _options() -> dict[str, set[str]]:
    """``{command: {option, ...}}``: the visible options of every command's parser."""
    return {
        name: {s for a in p._actions if a.help != argparse.SUPPRESS for s in a.option_strings}
        for name, p in cli_tables.command_parsers().items()
    }


def test_the_vocabulary_table_lists_exactly_the_commands_that_take_each_option() -> None:
    table, options = _table(), _options()
    assert {"--grasp", "--mu", "--sweeps", "--quiet"} <= set(table)
    assert set(table) == {o for opts in options.values() for o in opts} - {"-h", "--help", "--no-sweeps"}
    wrong = {}
    for option, listed in table.items():
        actual = {name for name, opts in options.items() if option in opts}
        if listed != actual:
            wrong[option] = (sorted(listed - actual), sorted(actual - listed))
    assert not wrong, f"option: (listed but not taken, taken but not listed): {wrong}"


def _parsers(help_a: str, help_b: str, **kwargs: str | None) -> dict[str, argparse.ArgumentParser]:
    parsers = {}
    for name, help in (("a", help_a), ("b", help_b)):
        p = argparse.ArgumentParser(prog=f"mjtvm {name}")
        p.add_argument("--x", metavar="X", help=help, **kwargs)
        parsers[name] = p
    return parsers


def test_an_option_whose_help_differs_between_commands_is_refused() -> None:
    with pytest.raises(cli_tables.VocabularyError, match=r"--x: its help differs between the commands"):
        cli_tables.options_table(_parsers("one meaning", "another", default="1"))


def test_an_option_without_a_default_must_say_what_its_default_is() -> None:
    with pytest.raises(cli_tables.VocabularyError, match=r"--x \(a\): no default and no computed_default"):
        cli_tables.options_table(_parsers("one meaning", "one meaning", default=None))


def test_defaults_that_differ_are_shown_per_command() -> None:
    parsers = _parsers("one meaning", "one meaning", default="1")
    parsers["b"]._actions[-1].default = "2"
    row = cli_tables.options_table(parsers).splitlines()[-1]
    assert row == "| `--x X` | one meaning | a: `1`; b: `2` | a, b |"


def test_help_texts_become_markdown() -> None:
    assert (
        cli_tables.markdown("25%% (docs/rerun.md#the-grasp; a|b)")
        == "25% ([rerun.md](rerun.md#the-grasp); a\\|b)"
    )
