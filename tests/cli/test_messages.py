"""One format for the lines every command shares: ``wrote PATH`` (mjtvm.cli.output.wrote), the
usage errors' ``(try 'mjtvm CMD --help')`` hint, and the bracket's progress line."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from mjtvm.cli import main
from mjtvm.cli.options import Formatter
from mjtvm.cli.output import bracket_progress, help_hint, wrote
from mjtvm.cli.parser import build_parser
from mjtvm.cli.values import accepted
from mjtvm.cli.verify import verify_parser

ROOT = Path(__file__).resolve().parents[2]


def test_wrote_is_one_line_with_an_optional_note(capsys: pytest.CaptureFixture[str]) -> None:
    wrote(Path("results") / "lift.csv")
    wrote("lift.rrd", "0.52 s")
    wrote("grasp.png", stderr=True)
    out, err = capsys.readouterr()
    assert out == "wrote results/lift.csv\nwrote lift.rrd (0.52 s)\n"
    assert err == "wrote grasp.png\n"


def test_every_command_writes_its_wrote_and_help_lines_through_the_helpers() -> None:
    """No command spells a ``wrote`` line or a ``--help`` hint of its own."""
    for path in sorted((ROOT / "mjtvm").rglob("*.py")):
        if path.name == "output.py" and path.parent.name == "cli":
            continue
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"""["']wrote \{""", text), path  # an f-string's "wrote {path}"
        assert not re.search(r"""f["'][^"'\n]*try '[^"'\n]*--help""", text), path


@pytest.mark.parametrize(
    ("argv", "prog"),
    [
        (["tvms", "--bogus"], "mjtvm tvms"),
        (["verify", "--bogus"], "mjtvm verify"),
        (["sweep", "--mu", "x"], "mjtvm sweep"),
        (["tvms", "case2", "--grasp", "case2"], "mjtvm tvms"),  # refused while it runs
        (["bogus"], "mjtvm"),
    ],
)
def test_every_usage_error_ends_with_the_command_s_help_hint(
    argv: list[str], prog: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.endswith(f" {help_hint(prog)}\n") and err.count("\n") == 1
    assert help_hint(prog) == f"(try '{prog} --help')"


def test_the_bracket_line_has_no_stray_comma(capsys: pytest.CaptureFixture[str]) -> None:
    with bracket_progress(True) as show:
        assert show is not None
        show({"inner": 1.0, "outer": 2.0, "gap": 0.5, "hausdorff": 0.1, "round": 3, "lps": 9, "seconds": 0.5})
    err = capsys.readouterr().err
    assert "bracket: [1, 2] gap 50 %" in err
    assert ": ," not in err


def _options() -> list[tuple[str, argparse.Action]]:
    """``(command, action)`` of every documented option and argument of every command."""
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    parsers = {**commands.choices, "verify": verify_parser()}
    return [
        (name, a)
        for name, p in parsers.items()
        for a in p._actions
        if a.help not in (None, argparse.SUPPRESS) and not isinstance(a, argparse._HelpAction)
    ]


def test_every_option_s_help_states_its_default_once() -> None:
    """The formatter adds ``default: ...``; no help text says it again (`default` in backticks is
    a value, ``--hand default``), and ``--help`` shows one ``default:`` per option."""
    for name, action in _options():
        shown = Formatter("mjtvm")._get_help_string(action)
        assert shown.count("default:") <= 1, (name, shown)
        assert "default" not in re.sub(r"`[^`]*`", "", action.help or "").lower(), (name, action.help)
    assert "(default: the shipped example pinch.json)" in " ".join(
        Formatter("mjtvm")._get_help_string(a) for n, a in _options() if n == "solve" and not a.option_strings
    )


UNITS = {
    "N": "NEWTONS",
    "weights (N)": "NEWTONS",
    "metres": "METRES",
    "mm": "MILLIMETRES",
    "seconds": "SECONDS",
}


def test_an_option_with_a_unit_names_it_as_its_metavar() -> None:
    """docs/cli.md, "One vocabulary": ``--preload NEWTONS``, ``--limit-horizon METRES``, ..."""
    found = set()
    for name, action in _options():
        text = accepted(action.type) or ""
        unit = next((u for u in UNITS if re.match(rf"(comma-separated )?{re.escape(u)} in ", text)), None)
        if unit is not None:
            assert action.metavar == UNITS[unit], (name, action.option_strings, text)
            found.add(action.option_strings[0])
        else:
            assert action.metavar not in UNITS.values(), (name, action.option_strings)
    assert {"--mg", "--preload", "--limit-horizon", "--launch", "--within", "--time-limit", "--hold"} <= found
