r"""The one plotting style of every figure mjtvm draws (``show --png``, the replay's Fig. 8 / 9,
``verify.png``, ``gears.png``, the rank plots, ``solve --png`` and ``tvms --png``).

The rules, checked for every figure by ``tests/jobs/test_figures.py``:

* every axis has a label with its unit in parentheses; a unitless axis says so with
  [`UNITLESS`][mjtvm.jobs.style.UNITLESS] ``(-)`` or [`COUNT`][mjtvm.jobs.style.COUNT] ``(count)``;
* the legend and the notes (what is not drawn, and why) sit below the axes, outside the data
  ([`finish()`][mjtvm.jobs.style.finish]);
* markers of values that have none ("no solution") sit on the zero line, unclipped
  ([`no_value()`][mjtvm.jobs.style.no_value]);
* constrained layout keeps every text inside the canvas; [`png()`][mjtvm.jobs.style.png] saves
  at a fixed size and dpi, so a figure's pixels depend only on its data.

matplotlib is imported only when a figure is drawn (off-screen, Agg: no pyplot state).
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from typing import Any

__all__ = ["COUNT", "DPI", "FONT", "UNITLESS", "figure", "finish", "no_value", "png"]

UNITLESS = "(-)"
"""The unit of a unitless axis (an index, a ratio)."""
COUNT = "(count)"
"""The unit of an axis that counts (grasps, states)."""
DPI = 120
"""The resolution of every PNG (pixels per inch)."""
FONT = {"suptitle": 10.0, "title": 9.0, "label": 8.0, "tick": 7.5, "legend": 7.5, "note": 7.5}
"""Font sizes (points) of each kind of text."""


def figure(width: float, height: float, grid: tuple[int, int] | None = None) -> tuple[Any, Any]:
    """A new off-screen figure (``width`` x ``height`` inches, constrained layout) and its axes:
    one ``Axes``, or with ``grid`` = (rows, columns) a 2-D array of them."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained", dpi=DPI)
    FigureCanvasAgg(fig)
    axes: Any = fig.add_subplot() if grid is None else fig.subplots(*grid, squeeze=False)
    for ax in [axes] if grid is None else list(axes.flat):
        ax.tick_params(labelsize=FONT["tick"])
    return fig, axes


def no_value(ax: Any, x: Sequence[float], *, color: Any, label: str) -> None:
    """Mark the abscissae ``x`` that have no value (no solution, infeasible) as crosses on the
    zero line, drawn over the frame (never clipped), never as a value of 0."""
    if len(x):
        ax.plot(x, [0.0] * len(x), "x", color=color, ms=6, mew=1.5, clip_on=False, zorder=5, label=label)


def finish(
    fig: Any,
    ax: Any,
    *,
    xlabel: str,
    ylabel: str,
    title: str,
    notes: Sequence[str] = (),
    grid: bool = True,
    key: bool = True,
    also: Sequence[Any] = (),
) -> None:
    """Label ``ax`` (``xlabel``, ``ylabel`` with their units, ``title``: the grasp's name first)
    and put its legend and the ``notes`` in one key below the axes, outside the data (a note
    is a line of the key without a symbol). A figure of several axes has one key: ``also``,
    the other axes whose legend entries it holds; ``key`` false: none (only the labels)."""
    from matplotlib.lines import Line2D

    ax.set_xlabel(xlabel, fontsize=FONT["label"])
    ax.set_ylabel(ylabel, fontsize=FONT["label"])
    ax.set_title(title, fontsize=FONT["title"])
    if grid:
        ax.grid(alpha=0.3)
    if not key:
        return
    handles, labels = [], []
    for each in (ax, *also):
        h, lab = each.get_legend_handles_labels()
        handles += h
        labels += lab
    handles += [Line2D([], [], linestyle="none") for _ in notes]
    labels += list(notes)
    if handles:
        width = fig.get_figwidth() * 72.0
        longest = max(len(s) for s in labels) * 0.5 * FONT["legend"] + 30.0  # points
        ncol = max(1, min(len(labels), int(width // longest)))
        fig.legend(
            handles,
            labels,
            loc="outside lower center",
            ncol=ncol,
            fontsize=FONT["legend"],
            frameon=False,
            handlelength=2.0,
        )


def png(fig: Any) -> bytes:
    """``fig`` as PNG bytes at [`DPI`][mjtvm.jobs.style.DPI], its size as created."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    return buf.getvalue()
