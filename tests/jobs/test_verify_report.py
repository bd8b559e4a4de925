"""verify.png: a single state drawn per RVDS vertex, states that do not hold marked and named (a note in the key),
never drawn as alpha_sim = 0."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from mjtvm.jobs import verify_report


def _row(
    state: int, l: int, z: float, *, run: str = "L", held: bool = True, status: str = "optimal"
) -> dict[str, Any]:
    lp = 1.0 + 0.1 * l + 0.01 * state
    return {
        "run": run, "state": state, "l": l, "z": z, "status": status, "held": held,
        "alpha_lp": lp, "alpha_sim": 0.9 * lp if held else 0.0, "ratio": 0.9 if held else math.nan,
    }  # fmt: skip


@pytest.fixture
def drawn(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    seen: dict[str, Any] = {}

    def capture(fig: Any, ax: Any, **kw: Any) -> bytes:
        seen.update(ax=ax, **kw)
        return b""

    monkeypatch.setattr(verify_report, "lift_png", capture)
    return seen


def test_one_state_is_bars_per_rvds_vertex(drawn: dict[str, Any]) -> None:
    rows = [_row(7, l, 0.1) for l in range(4)] + [
        _row(7, l, 0.1, run="S-physical", status="infeasible") for l in range(4)
    ]
    verify_report.plot_alpha(rows, "case2")
    ax = drawn["ax"]
    heights = sorted(p.get_height() for p in ax.patches)
    expected = sorted([1.07 + 0.1 * l for l in range(4)] + [0.9 * (1.07 + 0.1 * l) for l in range(4)])
    np.testing.assert_allclose(heights, expected)  # LP and sim per vertex, the infeasible run has none
    assert drawn["x"] == "l" and drawn["title"] == "case2, state 7"
    assert list(drawn["notes"]) == ["no solution: S-physical"]  # in the key below the axes


def test_states_not_held_are_named_and_not_drawn_at_zero(drawn: dict[str, Any]) -> None:
    rows = [_row(s, l, 0.1 + 0.01 * s, held=s != 1) for s in range(3) for l in range(2)]
    verify_report.plot_alpha(rows, "g")
    ax = drawn["ax"]
    sim = next(line for line in ax.lines if "sim" in line.get_label())
    assert math.isnan(sim.get_ydata()[1]) and sim.get_ydata()[0] == pytest.approx(0.9 * 1.0)
    marks = next(line for line in ax.lines if line.get_label().startswith("not held"))
    np.testing.assert_allclose(marks.get_xdata(), [0.11])
    assert "not held at rest: state 1" in drawn["notes"]
