r"""Figures along the lift: alpha (TVMMP, alpha_sim) against the object's height (a lift straight
up) or the travel along the lift, as PNG bytes.

Shared by the replay's Fig. 8 / 9 and the physics check's plot, so that both draw the same
axes in the same units. matplotlib is imported only when a figure is drawn.
"""

from __future__ import annotations

import io
from typing import Any

__all__ = ["ALPHA_UNIT", "lift_axes", "lift_png", "lift_x"]

ALPHA_UNIT = r"(m/s per unit of RVDS vertex $\hat r_l$)"
"""The unit of an alpha axis: alpha multiplies the RVDS vertex r_l (eq. 30: object velocity in
m/s, angular velocity in rad/s), so alpha = 1 is the vertex itself; the scenarios' vertices have
linear components of +-1 m/s, so alpha reads as m/s per unit of the vertex."""


X_LABELS = {"z": "object height $z$ (m)", "s": "travel along the lift $s$ (m)"}


def lift_x(lift: Any) -> str:
    """The x axis of a lift's figures: ``"z"`` (the object's height) for a lift straight up, as
    the paper's Fig. 8 draws it, else ``"s"`` (the lift's path parameter: m travelled)."""
    twists = getattr(lift, "twists", None)
    if twists is None:
        return "z"
    import numpy as np

    return "z" if np.allclose(twists, [0.0, 0.0, 1.0, 0.0, 0.0, 0.0], rtol=0.0, atol=1e-12) else "s"


def lift_axes(width: float, height: float) -> tuple[Any, Any]:
    """A new off-screen figure (inches) and its axes."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


def lift_png(fig: Any, ax: Any, *, ylabel: str, title: str, legend_fontsize: float, x: str = "z") -> bytes:
    """Label ``ax`` (x: [`X_LABELS`][mjtvm.jobs.figures.X_LABELS] of ``x``, y: ``ylabel`` from 0) and render ``fig``."""
    ax.set_xlabel(X_LABELS[x])
    ax.set_ylabel(ylabel, fontsize=8)
    ax.set_title(title, fontsize=9)
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=legend_fontsize)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120)
    return buf.getvalue()
