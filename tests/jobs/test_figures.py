"""Every figure the package makes, drawn on small shipped inputs (and on the rows of the cases
that crowd a plot: no solution, one state, states not held, many objects), is legible: each
axis labelled with a unit, no text outside the canvas, legends over no data, annotations and
tick labels apart. The figures are caught where they are saved (``Figure.savefig``)."""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text
from matplotlib.transforms import Bbox

from mjtvm.cli import main
from mjtvm.jobs import verify_report
from mjtvm.jobs.gears import plot_gears
from mjtvm.jobs.rank_auc import auc_plot, auc_table
from mjtvm.jobs.rank_files import rank_plots

ROOT = Path(__file__).resolve().parents[2]
UNIT = re.compile(r"\(.+\)|\[.+\]")
"""A unit in parentheses or brackets; unitless axes say so: ``(-)``, ``(count)``, ``(index, -)``."""


@pytest.fixture
def saved(monkeypatch: pytest.MonkeyPatch) -> list[Figure]:
    figures: list[Figure] = []
    original = Figure.savefig

    def capture(self: Figure, *args: Any, **kw: Any) -> None:
        figures.append(self)
        original(self, *args, **kw)

    monkeypatch.setattr(Figure, "savefig", capture)
    return figures


def _unseen_ticks(fig: Figure) -> set[int]:
    """The tick labels matplotlib holds outside the view limits (not drawn)."""
    out = set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            lo, hi = sorted(axis.get_view_interval())
            for ticks in (axis.get_major_ticks(), axis.get_minor_ticks()):
                for tick in ticks:
                    if not lo - 1e-9 * (hi - lo) <= tick.get_loc() <= hi + 1e-9 * (hi - lo):
                        out.update((id(tick.label1), id(tick.label2)))
    return out


def _texts(fig: Figure) -> Iterator[Text]:
    unseen = _unseen_ticks(fig)
    for t in fig.findobj(Text):
        if t.get_visible() and t.get_text().strip() and id(t) not in unseen:
            yield t


def _inside(inner: Bbox, outer: Bbox, tol: float = 1.0) -> bool:
    return (
        inner.x0 >= outer.x0 - tol
        and inner.y0 >= outer.y0 - tol
        and inner.x1 <= outer.x1 + tol
        and inner.y1 <= outer.y1 + tol
    )


def _overlap(a: Bbox, b: Bbox, tol: float = 1.0) -> bool:
    return a.x0 < b.x1 - tol and b.x0 < a.x1 - tol and a.y0 < b.y1 - tol and b.y0 < a.y1 - tol


def _data_points(ax: Any) -> np.ndarray:
    """The display positions of the plotted data: the lines' vertices (a marker: its four
    extreme points) and their segments sampled (20 points each), the bars' corners and
    centres; those inside the axes (a marker on the frame counts)."""
    pts = []
    for line in ax.lines:
        if not line.get_visible():
            continue
        xy = line.get_transform().transform(np.asarray(line.get_xydata(), dtype=float))
        xy = xy[np.isfinite(xy).all(axis=1)]
        pts.append(xy)
        if line.get_marker() not in ("None", "", " ", None):
            r = 0.5 * line.get_markersize() * ax.figure.dpi / 72.0
            pts += [xy + d for d in ([r, 0], [-r, 0], [0, r], [0, -r])]
        if line.get_linestyle() not in ("None", "", " ") and len(xy) > 1:
            t = np.linspace(0.0, 1.0, 20)[:, None, None]
            pts.append((xy[:-1] + t * (xy[1:] - xy[:-1])).reshape(-1, 2))
    for patch in ax.patches:
        b = patch.get_window_extent()
        if np.isfinite(b.bounds).all() and b.width > 0 and b.height > 0:
            pts.append(np.array([[b.x0, b.y1], [b.x1, b.y1], [(b.x0 + b.x1) / 2, b.y1], [b.x0, b.y0]]))
    if not pts:
        return np.zeros((0, 2))
    return np.concatenate(pts)


def _picture(ax: Any) -> bool:
    """A rendered view (an image, no ticks): its scale is the scale bar, not an axis."""
    return bool(ax.images) and not len(ax.get_xticks()) and not len(ax.get_yticks())


def problems(fig: Figure) -> list[str]:
    """What makes ``fig`` illegible, one line each; empty when it is legible."""
    if not hasattr(fig.canvas, "get_renderer"):  # closed by pyplot
        FigureCanvasAgg(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    out = []
    for ax in fig.axes:
        if _picture(ax):
            continue
        for which, label in (("x", ax.get_xlabel()), ("y", ax.get_ylabel())):
            if not UNIT.search(label):
                out.append(f"{ax.get_title()!r}: {which} label {label!r} has no unit")
    if not _inside(fig.get_tightbbox(renderer), fig.bbox_inches, tol=0.01):
        out.append(f"tight bbox {fig.get_tightbbox(renderer).bounds} outside {fig.bbox_inches.bounds}")
    for t in _texts(fig):
        if hasattr(t, "xyann") and not t._check_xy(renderer):  # an annotation's point out of view
            out.append(f"text {t.get_text()!r} not drawn: its point is outside the axes")
        elif not _inside(t.get_window_extent(renderer), fig.bbox):
            out.append(f"text {t.get_text()!r} outside the canvas")
    legends = [lg for lg in fig.legends]
    legends += [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    for lg in legends:
        box = lg.get_window_extent(renderer).padded(3.0)  # touching counts
        for ax in fig.axes:
            xy = _data_points(ax)
            hit = (xy[:, 0] > box.x0) & (xy[:, 0] < box.x1) & (xy[:, 1] > box.y0) & (xy[:, 1] < box.y1)
            if hit.any():
                out.append(f"{ax.get_title()!r}: the legend covers {int(hit.sum())} data points")
            for t in ax.texts:
                if t.get_visible() and t.get_text().strip() and _overlap(t.get_window_extent(renderer), box):
                    out.append(f"{ax.get_title()!r}: the legend covers the text {t.get_text()!r}")
    for ax in fig.axes:
        for line in ax.lines:
            if line.get_clip_on() and line.get_marker() not in ("None", "", " ", None) and line.get_visible():
                r = 0.5 * line.get_markersize() * fig.dpi / 72.0
                xy = line.get_transform().transform(np.asarray(line.get_xydata(), dtype=float))
                xy = xy[np.isfinite(xy).all(axis=1)]
                b = ax.bbox
                cut = (
                    (np.abs(xy[:, 0] - b.x0) < r) | (np.abs(xy[:, 0] - b.x1) < r)
                    | (np.abs(xy[:, 1] - b.y0) < r) | (np.abs(xy[:, 1] - b.y1) < r)
                )  # fmt: skip
                if cut.any():
                    out.append(
                        f"{ax.get_title()!r}: {int(cut.sum())} markers of {line.get_label()!r} cut by the frame"
                    )
    texts = [t for t in _texts(fig) if not any(t in lg.get_texts() for lg in legends)]
    boxes = [t.get_window_extent(renderer) for t in texts]
    for i in range(len(texts)):
        for j in range(i):
            if _overlap(boxes[i], boxes[j]):
                out.append(f"text {texts[i].get_text()!r} on {texts[j].get_text()!r}")
    return out


def _rank_rows() -> list[dict[str, Any]]:
    rng = np.random.default_rng(0)
    objects = [  # DexGraspNet's object codes
        "core-bottle-1a7ba1f4c892e2da30711cdbdbc73924", "ddg-gd_banana_poisson_001", "sem-Bowl-8e199e8e09",
        "mujoco-Ecoforms_Plant_Container", "core-mug-10f6e09036350e92b3f21f1137c3c347",
    ]  # fmt: skip
    rows = []
    for i in range(60):
        kind = int(rng.integers(0, 6))
        failed, feasible = kind == 5, kind < 4
        rows.append(
            {
                "id": f"g{i}", "object": objects[i % len(objects)], "rank": None,
                "failure": "no contact" if failed else None, "feasible": feasible and not failed,
                "tvmmp": float(rng.uniform(0.0, 0.06)) if feasible else None,
                "epsilon_l1": None if failed else float(rng.uniform(0.05, 0.3)),
                "reason": None, "certified": True, "limiting": None, "alpha": None, "status": None,
            }
        )  # fmt: skip
    return rows


GEARS = """\
ratio,state,z,tvmmp,tvmmp_dyn
1,0,0.1,,
10,0,0.1,,
40,0,0.1,1.21505,0.809179
100,0,0.1,0.499995,0.508784
400,0,0.1,0.126745,0.12724
1,1,0.137982,,
10,1,0.137982,,
40,1,0.137982,1.47388,1.08134
100,1,0.137982,0.599987,0.583581
400,1,0.137982,0.149999,0.15
1,2,0.175964,,
10,2,0.175964,4.67385,0.5
40,2,0.175964,1.16846,0.8
100,2,0.175964,0.467385,0.46
400,2,0.175964,0.116846,0.116
1,3,0.213945,,
10,3,0.213945,1.71718,0.3
40,3,0.213945,0.435208,0.43
100,3,0.213945,0.174556,0.17
400,3,0.213945,0.0436982,0.043
"""
"""``mjtvm verify --states 4 --gears 1,10,40,100,400`` on case2 (gears.csv; the dynamic column
rounded): every state infeasible at 1:1, two at 10:1."""


def _gear_rows() -> list[dict[str, Any]]:
    rows = []
    for line in GEARS.splitlines()[1:]:
        n, s, z, q, d = line.split(",")
        row: dict[str, Any] = {
            "ratio": float(n),
            "state": int(s),
            "z": float(z),
            "tvmmp": float(q) if q else None,
        }
        if d:
            row["tvmmp_dyn"] = float(d)
        rows.append(row)
    return rows


def _verify_row(state: int, l: int, z: float, *, run: str = "L", held: bool = True) -> dict[str, Any]:
    lp = 1.0 + 0.1 * l + 0.01 * state
    return {
        "run": run, "state": state, "l": l, "z": z, "status": "optimal", "held": held,
        "alpha_lp": lp, "alpha_sim": 0.9 * lp if held else 0.0, "ratio": 0.9 if held else math.nan,
    }  # fmt: skip


def _cli(*words: str) -> Callable[[Path], None]:
    def run(tmp: Path) -> None:
        assert main([w.replace("{tmp}", str(tmp)) for w in words]) == 0

    return run


def _empty_tvms(_: Path) -> Any:
    from mjtvm.jobs.result_figures import tvms_png
    from tests.jobs.test_result_figures import EMPTY_TVMS

    return tvms_png(EMPTY_TVMS, "case2, empty")


FIGURES: dict[str, tuple[int, Callable[[Path], Any]]] = {
    "show --png": (1, _cli("show", "case2", "--png", "{tmp}/show.png")),
    "solve --png": (1, _cli("solve", "case2", "--quiet", "--png", "{tmp}/solve.png")),
    "solve --png, no solution": (1, _cli("solve", "case2", "--mg", "100", "--quiet", "--png", "{tmp}/s.png")),
    "solve --png, a coupled hand": (
        1,
        _cli("solve", "shadow_hand_coupled-sphere", "--quiet", "--png", "{tmp}/solve.png"),
    ),
    "tvms --png": (1, _cli("tvms", "case2", "--quiet", "--png", "{tmp}/tvms.png")),
    "tvms --png, an empty TVMS": (1, _empty_tvms),
    "replay: fig8, fig9a, fig9b": (
        3,
        _cli("replay", "--states", "4", "--sweeps", "--out", "{tmp}", "--quiet"),
    ),
    "verify, one state": (1, _cli("verify", "--states", "1", "--out", "{tmp}", "--quiet")),
    "verify, states not held": (
        1,
        lambda _: verify_report.plot_alpha(
            [_verify_row(s, l, 0.1 + 0.01 * s, held=s != 1) for s in range(5) for l in range(2)], "case2"
        ),
    ),
    "verify --gears": (1, lambda _: plot_gears(_gear_rows(), "case2, L: $\\mu$ = 0.3, $mg$ = 1 N")),
    "rank, shipped dataset": (
        3,
        _cli(
            "rank",
            str(ROOT / "models/shadow_hand/shadow_hand_coupled-sphere.toml"),
            str(ROOT / "mjtvm/data/examples/shadow-sphere-dataset.npz"),
            "--out",
            "{tmp}",
            "--jobs",
            "1",
            "--quiet",
        ),
    ),
    "rank, five objects named as DexGraspNet names them": (3, lambda _: rank_plots(_rank_rows())),
    "rank --verify: AUC, one target without an AUC": (
        1,
        lambda _: auc_plot(auc_table(_sim_rows(), resamples=50)),
    ),
}


def _sim_rows() -> list[dict[str, Any]]:
    """Rows of ``rank --verify``: no grasp holds (no AUC), the speed succeeds for half."""
    rng = np.random.default_rng(0)
    return [
        {
            "tvmmp": float(t),
            "alpha": [[float(t), float(t) + 0.01]],
            "epsilon_l1": float(rng.random()),
            "force_closure": bool(i % 3),
            "sim_hold": False,
            "sim_speed_success": bool(t > 0.5),
        }
        for i, t in enumerate(rng.random(12))
    ]


@pytest.mark.parametrize("name", list(FIGURES))
def test_every_figure_is_legible(name: str, saved: list[Figure], tmp_path: Path) -> None:
    count, draw = FIGURES[name]
    draw(tmp_path)
    assert len(saved) == count
    found = [f"figure {i}: {p}" for i, fig in enumerate(saved) for p in problems(fig)]
    assert not found, "\n".join(found)
