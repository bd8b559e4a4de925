"""Warnings on stderr (mjtvm.cli.output): one line per cause, naming and counting its subjects."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from mjtvm.cli.output import LISTED, grouped, warn_uncertified


def test_grouped_names_the_first_and_counts() -> None:
    items = [(f"alpha[{k}][{l}]", "ill-conditioned") for k in range(6) for l in range(6)]
    items.insert(3, ("alpha[9][9]", "other"))
    assert grouped(items) == [
        (
            "alpha[0][0], alpha[0][1], alpha[0][2], alpha[0][3], alpha[0][4] and 31 more (36 pairs)",
            "ill-conditioned",
            36,
        ),
        ("alpha[9][9]", "other", 1),
    ]
    assert LISTED == 5 and grouped([]) == []


def test_uncertified_pairs_are_one_line_per_note(capsys: pytest.CaptureFixture[str]) -> None:
    pairs = [(k, l) for k in range(6) for l in range(6)]
    notes = {p: "scaled LP only" if p != (5, 5) else "restarted" for p in pairs}
    result = SimpleNamespace(uncertified=lambda: pairs, note=notes.get)
    warn_uncertified(result)
    lines = capsys.readouterr().err.splitlines()
    assert lines == [
        "mjtvm: warning: alpha[0][0], alpha[0][1], alpha[0][2], alpha[0][3], alpha[0][4] and 30 more "
        "(35 pairs) are not certified: scaled LP only",
        "mjtvm: warning: alpha[5][5] is not certified: restarted",
    ]
