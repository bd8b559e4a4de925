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

_F64 = NDArray[np.float64]

__all__ = ["plot_alpha", "rows_csv", "summarize"]


def rows_csv(rows: Sequence[dict[str, Any]]) -> str:
    """The rows as CSV (columns in order of first appearance, floats to 6 significant digits)."""
    return csv_text(rows, cell=lambda v: f"{v:.6g}" if isinstance(v, float) else v)


def _minima(rows: Sequence[dict[str, Any]], run: str, key: str) -> tuple[np.ndarray, np.ndarray]:
    by: dict[float, list[float]] = {}
    for r in rows:
        if r["run"] == run:
            by.setdefault(r.get("x", r["z"]), []).append(
                r.get(key, math.nan) if r["status"] == "optimal" else math.nan
            )
    z = np.array(sorted(by))
    return z, np.array([min(by[k]) if not any(math.isnan(v) for v in by[k]) else math.nan for k in z])


def plot_alpha(rows: Sequence[dict[str, Any]], title: str) -> bytes:
    """PNG of the TVMMP (LP), the dynamic TVMMP (rows with ``alpha_dyn``) and the minimum alpha_sim
    over the RVDS vertices along z, per run."""
    fig, ax = lift_axes(6.5, 4.2)
    for run in dict.fromkeys(r["run"] for r in rows):
        z, lp = _minima(rows, run, "alpha_lp")
        (line,) = ax.plot(z, lp, "-", label=f"TVMMP (LP, quasi-static), {run}")
        if any("alpha_dyn" in r for r in rows if r["run"] == run):
            z, dyn = _minima(rows, run, "alpha_dyn")
            label = rf"dynamic TVMMP (LP + $M\ddot q + c$), {run}"
            ax.plot(z, dyn, ":", lw=2, color=line.get_color(), label=label)
        z, sim = _minima(rows, run, "alpha_sim")
        ax.plot(
            z, sim, "o--", color=line.get_color(), ms=4, label=f"min $\\alpha_{{\\mathrm{{sim}}}}$, {run}"
        )
    x = "z" if all(r.get("x", r["z"]) == r["z"] for r in rows) else "s"  # the rows' lift_x axis
    return lift_png(fig, ax, ylabel=rf"$\alpha$ {ALPHA_UNIT}", title=title, legend_fontsize=7, x=x)


def summarize(rows: Sequence[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    r"""Per run: count, median and quartiles of alpha_sim / alpha_kl, the 3 worst pairs and their
    verdicts, s = 0.9 failures, how many pairs end in each verdict (``verdicts``), with a launch
    the median of launch_speed / alpha_kl and the launches that reached their distance; pairs with alpha_kl = 0 (no ratio) are counted apart (``zero_alpha``), and so are
    the states that do not hold at rest (``not_held``: no speed tested)."""
    out: dict[str, dict[str, Any]] = {}
    for run in dict.fromkeys(r["run"] for r in rows):
        ok = [r for r in rows if r["run"] == run and r["status"] == "optimal"]
        # a state that does not hold at rest has no speed tested (mjtvm.physics.hold)
        loose = {r["state"] for r in ok if r.get("held") is False}
        ok = [r for r in ok if r["state"] not in loose]
        # alpha_kl = 0 (the hand cannot move the object along r_l at all) has no ratio
        zero = sum(1 for r in ok if not math.isfinite(r["ratio"]))
        ok = [r for r in ok if math.isfinite(r["ratio"])]
        if not ok:
            out[run] = {"pairs": 0, "zero_alpha": zero, "not_held": len(loose)}
            continue
        ratios = sorted(r["ratio"] for r in ok)
        q = statistics.quantiles(ratios, n=4) if len(ratios) > 1 else [ratios[0]] * 3
        worst = sorted(ok, key=lambda r: r["ratio"])[:3]
        dyn: dict[str, Any] = {}
        if any("alpha_dyn" in r for r in ok):
            dr = sorted(r["ratio_dyn"] for r in ok if math.isfinite(r.get("ratio_dyn", math.nan)))
            dq = statistics.quantiles(dr, n=4) if len(dr) > 1 else [dr[0]] * 3 if dr else [math.nan] * 3
            feas = [r for r in ok if "pass_check_dyn" in r]
            dyn = {
                "median_dyn": statistics.median(dr) if dr else math.nan,
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
            "zero_alpha": zero,
            "not_held": len(loose),
            **dyn,
        }
    return out
