r"""The pictures of one grasp state's answers, as PNG bytes: ``mjtvm solve --png`` (Problem 2:
every alpha_kl and the limiting pair's witness in the joints' operation ranges) and
``mjtvm tvms --png`` (Problem 1: the TVMS projected on pairs of axes).

Both draw from the documents the commands print (``mjtvm.result/1``, ``mjtvm.tvms/1``), in the
one style ([`mjtvm.jobs.style`][mjtvm.jobs.style]). A state with no solution or an empty TVMS
still gets a picture: what there is (the operation ranges, crosses on the zero line) and a
note saying why the rest is not drawn. matplotlib is imported only when a figure is drawn.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

__all__ = ["solve_figure", "solve_png", "tvms_figure", "tvms_png"]

_BINDING, _INSIDE, _RANGE = "#d91a1a", "#2659e6", "0.35"  # witness points on / inside a range


def solve_png(
    result: Mapping[str, Any], ranges: Sequence[Any], title: str, *, actuators: bool = False
) -> bytes:
    """[`solve_figure()`][mjtvm.jobs.result_figures.solve_figure] as PNG bytes (120 dpi)."""
    from mjtvm.jobs.style import png

    return png(solve_figure(result, ranges, title, actuators=actuators))  # type: ignore[no-any-return]


def tvms_png(tvms: Mapping[str, Any], title: str) -> bytes:
    """[`tvms_figure()`][mjtvm.jobs.result_figures.tvms_figure] as PNG bytes (120 dpi)."""
    from mjtvm.jobs.style import png

    return png(tvms_figure(tvms, title))  # type: ignore[no-any-return]


def _alphas(result: Mapping[str, Any]) -> Any:
    import numpy as np

    return np.array([[np.nan if a is None else a for a in row] for row in result["alpha"]], dtype=float)


def solve_figure(
    result: Mapping[str, Any], ranges: Sequence[Any], title: str, *, actuators: bool = False
) -> Any:
    """Problem 2's answer (a ``mjtvm.result/1`` document) on two axes: left, alpha_kl per RVDS
    vertex l, one bar per REFS vertex k, the limiting pair (the TVMMP) marked and the pairs
    with no solution as crosses on the zero line; right, the limiting pair's witness: each
    joint's (or actuator's) operation point (|tau|, |qd|), the corner of its box of eq. (2),
    in its operation range (``ranges``: the state's
    [`OperationRange`][mjtvm.model.operation_range.OperationRange]s), the points on the
    range's boundary (the joints that bind) apart; ``actuators``: the ranges are a
    transmission's actuators' (force N m or N, speed rad/s or m/s). A matplotlib ``Figure``."""
    import numpy as np

    from mjtvm.jobs.figures import ALPHA_UNIT, X_LABELS
    from mjtvm.jobs.style import figure, finish, no_value

    alpha = _alphas(result)
    fig, axes = figure(9.0, 4.2, (1, 2))
    ax, ar = axes[0]
    n_k, n_l = alpha.shape
    width = 0.8 / n_k
    notes: list[str] = []
    for k in range(n_k):
        x = np.arange(n_l) + (k - 0.5 * (n_k - 1)) * width
        ok = np.isfinite(alpha[k])
        label = f"REFS vertex k = {k}" if ok.any() else "_empty"
        ax.bar(x[ok], alpha[k][ok], width=width, color=f"C{k % 10}", label=label)
        no_value(ax, list(x[~ok]), color=f"C{k % 10}", label=f"k = {k}: no solution" if (~ok).any() else "")
    limiting = result.get("limiting")
    finite = alpha[np.isfinite(alpha)]
    if limiting is not None and finite.size:
        k, l = limiting
        top = float(np.max(finite))
        ax.plot(
            [l + (k - 0.5 * (n_k - 1)) * width],
            [alpha[k, l] + 0.05 * top],
            "v",
            color="black",
            ms=7,
            label="limiting pair (its alpha is the TVMMP)",
        )
        ax.set_ylim(0.0, 1.15 * top)
    else:
        ax.set_ylim(0.0, 1.0)
        statuses = sorted({s for row in result.get("status", []) for s in row if s != "optimal"})
        notes.append(f"no solution at any pair ({', '.join(statuses) or 'no status'}): no TVMMP, no witness")
    ax.set_xticks(range(n_l))
    ax.set_xlim(-0.6, n_l - 0.4)
    tvmmp = result.get("tvmmp")
    ax_title = "alpha per pair" + ("" if tvmmp is None else f": TVMMP = {tvmmp:.4g}")
    notes += _witness_axes(ar, result, ranges, "actuator" if actuators else "joint")
    finish(
        fig,
        ar,
        xlabel=r"$|u|$, actuator force (N m or N)" if actuators else r"$|\tau|$, joint torque (N m)",
        ylabel=r"actuator speed (rad/s or m/s)" if actuators else r"$|\dot q|$, joint speed (rad/s)",
        title="the limiting pair's witness in the operation ranges",
        key=False,
    )
    finish(
        fig,
        ax,
        xlabel=X_LABELS["l"],
        ylabel=rf"$\alpha_{{kl}}$ {ALPHA_UNIT}",
        title=ax_title,
        notes=notes,
        also=(ar,),
    )
    from mjtvm.jobs.style import FONT

    fig.suptitle(title, fontsize=FONT["suptitle"])
    return fig


def _witness_axes(ar: Any, result: Mapping[str, Any], ranges: Sequence[Any], joint: str) -> list[str]:
    """Draw the operation ranges and the witness's points on ``ar``; the notes of what is not drawn."""
    import numpy as np

    distinct: dict[bytes, Any] = {}
    for r in ranges:
        distinct.setdefault(np.asarray(r.vertices, dtype=float).tobytes(), r)
    for i, r in enumerate(distinct.values()):
        v = np.asarray(r.vertices, dtype=float)
        ring = np.vstack([v, v[:1]])
        label = "operation range" + ("" if len(distinct) == 1 else f"s ({len(distinct)} distinct)")
        ar.plot(ring[:, 0], ring[:, 1], "-", color=_RANGE, lw=1.0, label=label if i == 0 else "_range")
    ar.set_xlim(left=0.0)
    ar.set_ylim(bottom=0.0)
    limiting = result.get("limiting")
    witnesses = result.get("witnesses")
    if limiting is None:
        return []  # the left axes' note says why
    if witnesses is None:
        return ["no witness drawn: solved with --no-witnesses"]
    witness = witnesses[limiting[0]][limiting[1]]
    if witness is None:
        return ["no witness drawn: the limiting pair has none"]
    box = np.abs(np.asarray(witness["box"], dtype=float))
    tau, qd = np.maximum(box[:, 0], box[:, 1]), np.maximum(box[:, 2], box[:, 3])
    span = max(max(r.max_speed for r in ranges), 1e-300)
    binding = np.array(
        [
            t >= r.max_torque * (1.0 - 1e-6) or q >= r.max_speed_at(t) - 1e-6 * span
            for t, q, r in zip(tau, qd, ranges, strict=True)
        ],
        dtype=bool,
    )
    for mask, color, what in ((binding, _BINDING, "on its range's boundary"), (~binding, _INSIDE, "inside")):
        if mask.any():
            ar.plot(tau[mask], qd[mask], "o", color=color, ms=4, clip_on=False, zorder=5,
                    label=f"witness: {joint} {what} ({int(mask.sum())})")  # fmt: skip
    k, l = limiting
    return [f"witness of the limiting pair k = {k}, l = {l}: (|tau|, |qd|) of each box of eq. (2)"]


_LINEAR = ("$v_x$ (m/s)", "$v_y$ (m/s)", "$v_z$ (m/s)")
_PLANAR = ("$v_x$ (m/s)", "$v_y$ (m/s)", r"$\omega_z$ (rad/s)")


def tvms_figure(tvms: Mapping[str, Any], title: str) -> Any:
    """Problem 1's polytope (a ``mjtvm.tvms/1`` document): its vertices (object twists)
    projected on three planes, in space those of the linear velocity (vx-vy, vx-vz, vy-vz), in
    the plane those of (vx, vy, omega_z), with the projections' convex hulls; an empty,
    unbounded or timed-out TVMS gets empty planes with a note. A matplotlib ``Figure``."""
    import numpy as np

    from mjtvm.jobs.style import FONT, figure, finish

    v = np.array(tvms.get("vertices") or [], dtype=float).reshape(-1, len(tvms.get("scale") or [0] * 6))
    names = _PLANAR if v.shape[1] == 3 else _LINEAR
    fig, axes = figure(9.0, 3.9, (1, 3))
    status = tvms.get("status")
    notes: list[str] = []
    if not len(v):
        notes.append(f"no vertices to draw: the TVMS is {status}" + _why(status))
    elif status == "approximate":
        stopped = (tvms.get("stopped_by") or {}).get("reason", "a budget")
        notes.append(f"approximate (stopped by {stopped}): the vertices of the inner polytope")
    for i, (ax, (a, b)) in enumerate(zip(axes[0], ((0, 1), (0, 2), (1, 2)), strict=True)):
        if len(v):
            xy = v[:, [a, b]]
            ring = _hull_ring(xy)
            if ring is not None:
                ax.fill(xy[ring, 0], xy[ring, 1], alpha=0.25, color="tab:blue")
                ax.plot(xy[ring, 0], xy[ring, 1], "-", color="tab:blue", lw=1.0,
                        label="convex hull of the projection" if i == 0 else "_hull")  # fmt: skip
            ax.plot(xy[:, 0], xy[:, 1], "o", color="tab:blue", ms=3, label="vertex" if i == 0 else "_v")
            ax.set_aspect("equal", adjustable="datalim")
            ax.margins(0.12)
        else:
            ax.plot([0.0], [0.0], "x", color="black", ms=6, mew=1.5, clip_on=False,
                    label="the zero twist (no TVMS)" if i == 0 else "_zero")  # fmt: skip
            ax.set_xlim(-1.0, 1.0)
            ax.set_ylim(-1.0, 1.0)
        plane = f"{names[a].split(' ')[0]} - {names[b].split(' ')[0]}"
        if i == 0:
            continue
        finish(fig, ax, xlabel=names[a], ylabel=names[b], title=plane, key=False)
    finish(
        fig,
        axes[0][0],
        xlabel=names[0],
        ylabel=names[1],
        title=f"{names[0].split(' ')[0]} - {names[1].split(' ')[0]}",
        notes=notes,
    )
    part = "(vx, vy, omega_z)" if v.shape[1] == 3 else "linear velocity"
    dimension = tvms.get("dimension")
    fig.suptitle(
        f"{title}: TVMS, {len(v)} vertices (dimension {dimension}), {part}", fontsize=FONT["suptitle"]
    )
    return fig


def _why(status: object) -> str:
    return {
        "empty": " (a REFS vertex cannot be balanced)",
        "unbounded": " (no vertices of an unbounded set)",
        "timeout": " (cdd gave up: --time-limit)",
    }.get(str(status), "")


def _hull_ring(xy: Any) -> Any:
    """The indices of the 2-D convex hull of ``xy``, closed (first repeated), or None when the
    points span no area (Andrew's monotone chain)."""
    import numpy as np

    order = np.lexsort((xy[:, 1], xy[:, 0]))
    pts = xy[order]

    def cross(o: Any, a: Any, b: Any) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    scale = max(float(np.ptp(xy, axis=0).max()), 1e-300) ** 2
    chain: list[int] = []
    for sweep in (range(len(pts)), range(len(pts) - 1, -1, -1)):
        start = len(chain)
        for j in sweep:
            while len(chain) >= start + 2 and cross(pts[chain[-2]], pts[chain[-1]], pts[j]) <= 1e-12 * scale:
                chain.pop()
            chain.append(j)
        chain.pop()
    if len(chain) < 3:
        return None
    return order[np.array([*chain, chain[0]])]
