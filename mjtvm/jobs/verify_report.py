r"""The physics check's report: its rows as CSV, the alpha curves along the lift as a PNG, and
per run the distribution of alpha_sim / alpha_kl ([`verify_lift()`][mjtvm.jobs.verify.verify_lift]'s rows).
"""

from __future__ import annotations

import math
import statistics
from collections import Counter
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.jobs.figures import ALPHA_UNIT, lift_axes, lift_png
from mjtvm.jobs.files import csv_text
from mjtvm.jobs.style import no_value

_F64 = NDArray[np.float64]

__all__ = ["cause_kind", "plot_alpha", "rows_csv", "summarize"]


def rows_csv(rows: Sequence[dict[str, Any]]) -> str:
    """The rows as CSV (columns in order of first appearance, floats to 6 significant digits)."""
    return csv_text(rows, cell=lambda v: f"{v:.6g}" if isinstance(v, float) else v)


def _minima(rows: Sequence[dict[str, Any]], run: str, key: str) -> tuple[np.ndarray, np.ndarray]:
    """Per lift position of ``run``: the minimum of ``key`` over the RVDS vertices (NaN where a
    vertex has no value: not optimal, or a state that does not hold at rest for alpha_sim)."""
    by: dict[float, list[float]] = {}
    for r in rows:
        if r["run"] == run:
            loose = key == "alpha_sim" and r.get("held") is False
            ok = r["status"] == "optimal" and not loose
            by.setdefault(r.get("x", r["z"]), []).append(r.get(key, math.nan) if ok else math.nan)
    z = np.array(sorted(by))
    return z, np.array([min(by[k]) if not any(math.isnan(v) for v in by[k]) else math.nan for k in z])


def _one_state(ax: Any, rows: Sequence[dict[str, Any]]) -> list[str]:
    """One state: alpha_kl, alpha_dyn and alpha_sim per RVDS vertex l, as grouped bars; the
    note on the runs with no solution (none: empty)."""
    runs = [
        run
        for run in dict.fromkeys(r["run"] for r in rows)
        if any(r["run"] == run and r["status"] == "optimal" for r in rows)
    ]
    missing = [run for run in dict.fromkeys(r["run"] for r in rows) if run not in runs]
    notes = [f"no solution: {', '.join(missing)}"] if missing else []
    keys = [("alpha_lp", "TVMMP (LP)"), ("alpha_dyn", "dynamic"), ("alpha_sim", r"$\alpha_{\mathrm{sim}}$")]
    keys = [k for k in keys if any(k[0] in r for r in rows)]
    width = 0.8 / max(1, len(keys) * len(runs))
    for i, run in enumerate(runs):
        mine = sorted((r for r in rows if r["run"] == run), key=lambda r: r["l"])
        for j, (key, label) in enumerate(keys):
            x = (
                np.array([r["l"] for r in mine])
                + (i * len(keys) + j - 0.5 * (len(keys) * len(runs) - 1)) * width
            )
            y = [r.get(key, math.nan) if r["status"] == "optimal" else math.nan for r in mine]
            ax.bar(x, y, width=width, label=f"{label}, {run}")
    ax.set_xticks(sorted({int(r["l"]) for r in rows}))
    return notes


def plot_alpha(rows: Sequence[dict[str, Any]], title: str) -> bytes:
    """PNG of the TVMMP (LP), the dynamic TVMMP (rows with ``alpha_dyn``) and the minimum alpha_sim
    over the RVDS vertices along the lift, per run; for a single state, the three per RVDS vertex
    l. States that do not hold at rest have no alpha_sim: they are marked on the axis and named
    in a note, never drawn at 0."""
    fig, ax = lift_axes(6.5, 4.2)
    loose = sorted({(r.get("x", r["z"]), r["state"]) for r in rows if r.get("held") is False})
    if len({r["state"] for r in rows}) == 1:
        notes = _one_state(ax, rows)
        state = rows[0]["state"] if rows else "-"
        return _finish(fig, ax, f"{title}, state {state}", loose, x=None, notes=notes)
    for run in dict.fromkeys(r["run"] for r in rows):
        z, lp = _minima(rows, run, "alpha_lp")
        (line,) = ax.plot(z, lp, ".-", label=f"TVMMP (LP, quasi-static), {run}")
        if any("alpha_dyn" in r for r in rows if r["run"] == run):
            z, dyn = _minima(rows, run, "alpha_dyn")
            label = rf"dynamic TVMMP (LP + $M\ddot q + c$), {run}"
            ax.plot(z, dyn, ":", lw=2, color=line.get_color(), label=label)
        z, sim = _minima(rows, run, "alpha_sim")
        ax.plot(
            z, sim, "o--", color=line.get_color(), ms=4, label=f"min $\\alpha_{{\\mathrm{{sim}}}}$, {run}"
        )
    x = "z" if all(r.get("x", r["z"]) == r["z"] for r in rows) else "s"  # the rows' lift_x axis
    if loose:
        xs = [p[0] for p in loose]
        no_value(ax, xs, color="0.4", label="not held at rest (no speed tested)")
    return _finish(fig, ax, title, loose, x=x)


def _finish(
    fig: Any, ax: Any, title: str, loose: list[tuple[float, int]], *, x: str | None, notes: Sequence[str] = ()
) -> bytes:
    """The notes (runs with no solution, states that do not hold), the axes' labels, the PNG."""
    notes = list(notes)
    if loose:
        states = ", ".join(str(s) for _, s in loose[:8]) + (", ..." if len(loose) > 8 else "")
        notes.append(f"not held at rest: state{'s' if len(loose) > 1 else ''} {states}")
    if not ax.has_data():
        ax.text(0.5, 0.5, "no optimal pair to draw", transform=ax.transAxes, ha="center", color="0.3")
    label = rf"$\alpha$ {ALPHA_UNIT}"
    return lift_png(fig, ax, ylabel=label, title=title, x=x or "l", notes=notes)


def cause_kind(cause: str) -> str:
    """The kind of a ``cause`` ([`ratio_cause()`][mjtvm.physics.verdict.ratio_cause]): its
    words before the first colon or semicolon (``margin``, ``rotor inertia``, ``slip``, ...)."""
    return cause.split(";")[0].split(":")[0].strip()


def summarize(rows: Sequence[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    r"""Per run: count, median and quartiles of alpha_sim / alpha_kl, the 3 worst pairs and their
    verdicts, s = 0.9 failures, how many pairs end in each verdict (``verdicts``), with
    ``--dynamics`` the medians of alpha_sim / alpha_dyn under both drives (``median_dyn``,
    ``median_dyn_ff``) and their spread (``spread_dyn``), how many of
    those outside [0.9, 1.05] have each kind of cause (``causes``: `cause_kind()`), with a launch
    the median of launch_speed / alpha_kl and the launches that reached their distance, the
    pairs whose pass/fail is not monotone about s* (``non_monotone``). Counted apart, out of
    every statistic: pairs with alpha_kl = 0 (no ratio, ``zero_alpha``), the states that do
    not hold at rest (``not_held``: no speed tested) and the censored pairs (s* at a bracket
    end, ``censored``: a bound, not a ratio)."""
    out: dict[str, dict[str, Any]] = {}
    for run in dict.fromkeys(r["run"] for r in rows):
        ok = [r for r in rows if r["run"] == run and r["status"] == "optimal"]
        # a state that does not hold at rest has no speed tested (mjtvm.physics.hold)
        loose = {r["state"] for r in ok if r.get("held") is False}
        ok = [r for r in ok if r["state"] not in loose]
        # alpha_kl = 0 (the hand cannot move the object along r_l at all) has no ratio
        zero = sum(1 for r in ok if not math.isfinite(r["ratio"]))
        ok = [r for r in ok if math.isfinite(r["ratio"])]
        # s* at a bracket end (fails at rest, passes at s = 2) is a bound, not a ratio
        censored = sum(1 for r in ok if r.get("censored"))
        ok = [r for r in ok if not r.get("censored")]
        apart = {"zero_alpha": zero, "not_held": len(loose), "censored": censored}
        if not ok:
            out[run] = {"pairs": 0, **apart}
            continue
        ratios = sorted(r["ratio"] for r in ok)
        q = statistics.quantiles(ratios, n=4) if len(ratios) > 1 else [ratios[0]] * 3
        worst = sorted(ok, key=lambda r: r["ratio"])[:3]
        dyn: dict[str, Any] = {}
        if any("alpha_dyn" in r for r in ok):
            dr = sorted(r["ratio_dyn"] for r in ok if math.isfinite(r.get("ratio_dyn", math.nan)))
            dq = statistics.quantiles(dr, n=4) if len(dr) > 1 else [dr[0]] * 3 if dr else [math.nan] * 3
            feas = [r for r in ok if "pass_check_dyn" in r]
            ff = sorted(r["ratio_dyn_ff"] for r in ok if math.isfinite(r.get("ratio_dyn_ff", math.nan)))
            dyn = {
                "median_dyn": statistics.median(dr) if dr else math.nan,
                # the second drive (mjtvm.physics.feedforward): its median, and the spread
                # between the drives' medians, alpha_dyn's uncertainty
                "median_dyn_ff": statistics.median(ff) if ff else math.nan,
                "spread_dyn": abs(statistics.median(ff) - statistics.median(dr)) if ff and dr else math.nan,
                "q1_dyn": dq[0],
                "q3_dyn": dq[2],
                "fail_at_check_dyn": sum(not r["pass_check_dyn"] for r in feas),
                "dyn_feasible": len(feas),
            }
        if any("launch_speed" in r for r in ok):
            lr = [r["launch_speed"] / r["alpha_lp"] for r in ok if r["alpha_lp"] > 0]
            dyn["launch_median"] = statistics.median(lr) if lr else math.nan
            dyn["launch_reached"] = sum(r["launch_verdict"] == "reached" for r in ok)
        out[run] = {
            "pairs": len(ok),
            "states": len({r["state"] for r in ok}),
            "median": statistics.median(ratios),
            "q1": q[0],
            "q3": q[2],
            "min": ratios[0],
            "max": ratios[-1],
            "worst": [(r["state"], r["l"], round(r["ratio"], 3), r["verdict"]) for r in worst],
            "fail_at_check": sum(not r["pass_check"] for r in ok),
            "verdicts": dict(Counter(r["verdict"] for r in ok).most_common()),
            # the pairs outside [CAUSE_LOW, CAUSE_HIGH] by the kind of their cause
            "causes": dict(
                Counter(cause_kind(r.get("cause", "")) for r in ok if r.get("cause")).most_common()
            ),
            "non_monotone": sum(r.get("monotone") is False for r in ok),
            **apart,
            **dyn,
        }
    return out
