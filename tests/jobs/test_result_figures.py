"""``mjtvm solve --png`` and ``mjtvm tvms --png``'s pictures (mjtvm.jobs.result_figures): what
each draws, and the note a state with no solution or an empty TVMS gets instead of an empty
axis (their legibility: tests/jobs/test_figures.py)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from matplotlib.text import Text

from mjtvm import load_state, tvmmp
from mjtvm.cli import example_path
from mjtvm.jobs.result_figures import solve_figure, tvms_figure
from mjtvm.model.operation_range import OperationRange
from tests.jobs.test_figures import problems

EMPTY_TVMS = {"schema": "mjtvm.tvms/1", "status": "empty", "feasible": False, "dimension": -1,
              "vertices": [], "scale": [10.0, 10.0, 10.0, 1.0, 1.0, 1.0]}  # fmt: skip
"""A ``mjtvm.tvms/1`` document of a state whose REFS cannot be balanced: no vertices."""


def _texts(fig: Any) -> list[str]:
    fig.canvas.draw()
    return [t.get_text() for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()]


def test_solve_figure_marks_the_limiting_pair_and_the_binding_joints() -> None:
    state = load_state(example_path())
    doc = tvmmp(state).to_dict()
    fig = solve_figure(doc, state.operation_ranges, "pinch")
    bars, witness = fig.axes[:2]
    heights = sorted(p.get_height() for p in bars.patches)
    assert heights == pytest.approx(sorted(a for row in doc["alpha"] for a in row))
    assert "TVMMP = " in bars.get_title()
    points = [line for line in witness.lines if line.get_marker() == "o"]
    drawn = sum(len(line.get_xdata()) for line in points)
    assert drawn == len(state.operation_ranges)  # one point per joint
    for line in points:
        for tau, qd in zip(line.get_xdata(), line.get_ydata(), strict=True):
            assert any(r.contains(tau, qd, tol=1e-6) for r in state.operation_ranges)
    texts = _texts(fig)
    assert any(t.startswith("witness: joint on its range's boundary") for t in texts)
    assert not problems(fig)


def test_solve_figure_without_a_solution_has_a_note_and_the_ranges() -> None:
    doc = {"alpha": [[None, None]], "status": [["infeasible", "infeasible"]], "limiting": None,
           "tvmmp": None, "witnesses": [[None, None]]}  # fmt: skip
    fig = solve_figure(doc, [OperationRange.box(1.0, 2.0)], "nothing")
    bars, witness = fig.axes[:2]
    assert not bars.patches  # no bar of height 0
    crosses = [line for line in bars.lines if line.get_marker() == "x"]
    assert sum(len(line.get_xdata()) for line in crosses) == 2
    assert witness.lines  # the operation range is drawn
    assert any(t.startswith("no solution at any pair (infeasible)") for t in _texts(fig))
    assert not problems(fig)


def test_solve_figure_without_witnesses_says_so() -> None:
    state = load_state(example_path())
    doc = tvmmp(state, witnesses=False).to_dict(witnesses=False)
    fig = solve_figure(doc, state.operation_ranges, "pinch")
    assert "no witness drawn: solved with --no-witnesses" in _texts(fig)


def test_tvms_figure_draws_every_vertex_projected() -> None:
    cube = np.array([[x, y, z, 0.0, 0.0, 0.0] for x in (-1, 1) for y in (-2, 2) for z in (0, 3)], dtype=float)
    doc = {"status": "bounded", "dimension": 3, "vertices": cube.tolist(), "scale": [1.0] * 6}
    fig = tvms_figure(doc, "cube")
    for ax, (a, b) in zip(fig.axes, ((0, 1), (0, 2), (1, 2)), strict=True):
        (dots,) = [line for line in ax.lines if line.get_marker() == "o"]
        assert np.allclose(dots.get_xydata(), cube[:, [a, b]])
        assert len(ax.patches) == 1  # the hull
        assert "(m/s)" in ax.get_xlabel() and "(m/s)" in ax.get_ylabel()
    assert not problems(fig)


def test_tvms_figure_of_an_empty_tvms_has_a_note() -> None:
    fig = tvms_figure(EMPTY_TVMS, "empty")
    texts = _texts(fig)
    assert any(t.startswith("no vertices to draw: the TVMS is empty") for t in texts)
    assert all(not ax.patches for ax in fig.axes)
    assert not problems(fig)
