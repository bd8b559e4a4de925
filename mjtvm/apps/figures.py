r"""Figures along the lift: alpha (TVMMP, alpha_sim) against the object's height, as PNG bytes.

Shared by the replay's Fig. 8 / 9 and the physics check's plot, so that both draw the same
axes in the same units. matplotlib is imported only when a figure is drawn.
"""

from __future__ import annotations

import io
from typing import Any

__all__ = ["ALPHA_UNIT", "lift_axes", "lift_png"]

ALPHA_UNIT = r"(m/s per unit of RVDS vertex $\hat r_l$)"
"""The unit of an alpha axis: alpha multiplies the RVDS vertex r_l (eq. 30: object velocity in
m/s, angular velocity in rad/s), so alpha = 1 is the vertex itself; the scenarios' vertices have
linear components of +-1 m/s, so alpha reads as m/s per unit of the vertex."""


def lift_axes(width: float, height: float) -> tuple[Any, Any]:
    """A new off-screen figure (inches) and its axes."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


def lift_png(fig: Any, ax: Any, *, ylabel: str, title: str, legend_fontsize: float) -> bytes:
    """Label ``ax`` (x: the object's height z in m, y: ``ylabel`` from 0) and render ``fig``."""
    ax.set_xlabel("object height $z$ (m)")
    ax.set_ylabel(ylabel, fontsize=8)
    ax.set_title(title, fontsize=9)
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=legend_fontsize)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120)
    return buf.getvalue()
