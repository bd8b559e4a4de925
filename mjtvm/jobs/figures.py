r"""Figures as PNG bytes: alpha (TVMMP, alpha_sim) against the object's height (a lift straight
up) or the travel along the lift, and the rendered views of a grasp.

Shared by the replay's Fig. 8 / 9, the physics check's plot and ``mjtvm show --png``, so that
all draw in one style and the same units. matplotlib is imported only when a figure is drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["ALPHA_UNIT", "grasp_figure", "grasp_png", "lift_axes", "lift_png", "lift_x"]

ALPHA_UNIT = r"(m/s per unit of RVDS vertex $\hat r_l$)"
"""The unit of an alpha axis: alpha multiplies the RVDS vertex r_l (eq. 30: object velocity in
m/s, angular velocity in rad/s), so alpha = 1 is the vertex itself; the scenarios' vertices have
linear components of +-1 m/s, so alpha reads as m/s per unit of the vertex."""


X_LABELS = {
    "z": "object height $z$ (m)",
    "s": "travel along the lift $s$ (m)",
    "l": r"RVDS vertex $l$ (index, -)",
}


def lift_x(lift: Any) -> str:
    """The x axis of a lift's figures: ``"z"`` (the object's height) for a lift straight up, as
    the paper's Fig. 8 draws it, else ``"s"`` (the lift's path parameter: m travelled)."""
    twists = getattr(lift, "twists", None)
    if twists is None:
        return "z"
    import numpy as np

    return "z" if np.allclose(twists, [0.0, 0.0, 1.0, 0.0, 0.0, 0.0], rtol=0.0, atol=1e-12) else "s"


def lift_axes(width: float, height: float) -> tuple[Any, Any]:
    """A new off-screen figure (inches) and its axes, in the one style ([`mjtvm.jobs.style`][mjtvm.jobs.style])."""
    from mjtvm.jobs.style import figure

    return figure(width, height)  # type: ignore[no-any-return]


def lift_png(fig: Any, ax: Any, *, ylabel: str, title: str, x: str = "z", notes: Sequence[str] = ()) -> bytes:
    """Label ``ax`` (x: [`X_LABELS`][mjtvm.jobs.figures.X_LABELS] of ``x``, y: ``ylabel`` from 0),
    the key and the ``notes`` below the axes ([`finish()`][mjtvm.jobs.style.finish]), and render ``fig``."""
    from mjtvm.jobs.style import finish, png

    ax.set_ylim(bottom=0.0)
    finish(fig, ax, xlabel=X_LABELS[x], ylabel=ylabel, title=title, notes=notes)
    return png(fig)  # type: ignore[no-any-return]


_OBJECT, _CONE, _SELF = "#d91a1a", "#1a992e", "#2659e6"  # object contacts, cones, self-contacts


def _nice_length(target: float) -> float:
    """The largest 1, 2 or 5 x 10^k metres not above ``target`` (m > 0)."""
    import math

    exp = math.floor(math.log10(target))
    for m in (5.0, 2.0, 1.0):
        if m * 10.0**exp <= target:
            return m * 10.0**exp
    return 10.0**exp


def grasp_png(picture: Any, title: str) -> bytes:
    """[`grasp_figure()`][mjtvm.jobs.figures.grasp_figure] as PNG bytes (120 dpi: 1296 x 540 pixels for three views)."""
    from mjtvm.jobs.style import png

    return png(grasp_figure(picture, title))  # type: ignore[no-any-return]


def grasp_figure(picture: Any, title: str) -> Any:
    """The panels of a [`Picture`][mjtvm.grasp.contacts.picture.Picture] side by side, each with its view's name and a scale
    bar (mm, at the object's centre), the grasp's ``title`` above, the contact key below: a
    matplotlib ``Figure``."""
    from matplotlib.lines import Line2D

    from mjtvm.jobs.style import FONT, figure

    n = len(picture.panels)
    height, width = picture.panels[0].shape[:2]
    fig, axes = figure(3.6 * n, 3.6 * height / width + 0.9, (1, n))
    axes = axes[0]
    panels = zip(picture.panels, picture.labels, picture.metres_per_pixel, picture.marks, strict=True)
    for ax, (img, label, mpp, marks) in zip(axes, panels, strict=True):
        ax.imshow(img)
        for seg in marks.cone_segments:
            ax.plot(seg[:, 0], seg[:, 1], color=_CONE, linewidth=0.8)
        for a, b, hid in zip(marks.points, marks.normal_ends, marks.hidden, strict=True):
            style = {"arrowstyle": "-|>", "color": _OBJECT, "lw": 1.5, "alpha": 0.35 if hid else 1.0}
            ax.annotate("", xy=b, xytext=a, arrowprops=style)
            ax.plot(*a, "o", color=_OBJECT, markersize=5, alpha=0.35 if hid else 1.0)
        if len(marks.self_points):
            ax.plot(marks.self_points[:, 0], marks.self_points[:, 1], "s", color=_SELF, markersize=5)
        ax.set_xlim(0, width)
        ax.set_ylim(height, 0)
        ax.set_title(label, fontsize=FONT["title"])
        ax.set_xticks([])
        ax.set_yticks([])
        bar = _nice_length(0.25 * width * mpp)
        px, x0, y0 = bar / mpp, 0.06 * width, 0.93 * height
        ax.plot([x0, x0 + px], [y0, y0], color="black", linewidth=3, solid_capstyle="butt")
        ax.text(
            x0 + px / 2,
            y0 - 0.02 * height,
            f"{1e3 * bar:g} mm",
            ha="center",
            va="bottom",
            fontsize=8,
            bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.8, "pad": 1.5},
        )
    fig.suptitle(title, fontsize=FONT["suptitle"])
    n_obj, n_self = picture.object_contacts, picture.self_contacts
    key = [
        Line2D(
            [], [], marker="o", color=_OBJECT, label=f"object contact, normal out ({n_obj}; faint: hidden)"
        ),
        Line2D([], [], color=_CONE, label="friction cone (mu)"),
        Line2D([], [], marker="s", linestyle="", color=_SELF, label=f"hand self-contact ({n_self})"),
    ]
    fig.legend(handles=key, loc="outside lower center", ncol=3, fontsize=FONT["legend"], frameon=False)
    return fig
