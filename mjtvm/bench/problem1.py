r"""Timing of Problem 1 (the TVMS) on the paper's states, against the cdd baseline.

The paper (MATLAB, Core Solo U1300 1.06 GHz) reports 0.19 s for Case 1 (Problem 1, no
RVDS) and 129 s for Case 2's initial state (Problem 1 without RVDS). mjtvm's targets are
:data:`TARGETS_S`. For each state, in one run:

* ``tvms(state, rvds_cone=False)`` (support LPs on HiGHS): the median wall time over
  ``repeats`` calls after ``warmup`` calls, the time inside HiGHS ``run()``
  (:func:`~mjtvm.bench.timing.highs_run_timer`), the LP count, the dimension, the number of
  vertices and the scaled affine volume;
* ``tvms(state, method="cdd", rvds_cone=False)``: the paper's vertex enumeration in a child
  process, its wall time or "did not finish in ``time_limit`` s", and how far its
  vertices lie from the LP method's (Hausdorff distance relative to the extent);
* memory: the process's peak resident set (``resource.getrusage``) before and after the
  state's LP runs, the peak of Python allocations during one more LP run under
  :mod:`tracemalloc` (HiGHS' and Qhull's own buffers are not traced), and the cdd child's
  peak resident set.

Run it as ``python -m mjtvm.bench.problem1`` (prints a table, then the JSON report).
"""

from __future__ import annotations

import json
import resource
import statistics
import time
import tracemalloc
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core.state import GraspState
from ..polytopes.tvms import TvmsResult, tvms
from ..polytopes.volume import hausdorff
from .timing import highs_run_timer, machine_info

__all__ = ["PAPER_S", "TARGETS_S", "bench_tvms_state", "format_tvms_table", "run_tvms_benchmark"]

PAPER_S = {"case1": 0.19, "case2": 129.0}  #: the paper's Problem 1 times (s)
TARGETS_S = {"case1": 0.05, "case2": 2.0}  #: mjtvm's targets for the LP method (s)


def _rss_mib(who: int = resource.RUSAGE_SELF) -> float:
    """Peak resident set size in MiB (``ru_maxrss`` is in KiB on Linux)."""
    return resource.getrusage(who).ru_maxrss / 1024.0


def _hausdorff(a: TvmsResult, b: TvmsResult) -> float | None:
    """Hausdorff distance of two vertex sets relative to the extent (``None`` if either is empty)."""
    if not len(a.vertices) or not len(b.vertices):
        return None
    extent = float(np.max(np.abs(a.vertices * a.scale)))
    return hausdorff(a.vertices * a.scale, b.vertices * b.scale) / max(extent, 1e-300)


def _summary(r: TvmsResult) -> dict[str, Any]:
    return {
        "status": r.status,
        "dimension": r.dimension,
        "vertices": len(r.vertices),
        "volume": r.volume,
        "affine_volume": r.affine_volume,
        "num_lps": r.timings.num_lps,
        "lifted_vertices": r.lifted_vertices,
    }


def bench_tvms_state(
    state: GraspState,
    *,
    repeats: int = 5,
    warmup: int = 1,
    time_limit: float = 120.0,
    trace_memory: bool = True,
) -> dict[str, Any]:
    """Time and measure Problem 1 on one state (see the module docstring)."""
    rss_before = _rss_mib()
    for _ in range(warmup):
        tvms(state, rvds_cone=False)
    totals, runs, results = [], [], []
    with highs_run_timer() as spent:
        for _ in range(max(repeats, 1)):
            spent.clear()
            t0 = time.perf_counter()
            results.append(tvms(state, rvds_cone=False))
            totals.append(time.perf_counter() - t0)
            runs.append(sum(spent))
    result = results[-1]
    rss_after = _rss_mib()
    traced = None
    if trace_memory:
        tracemalloc.start()
        tvms(state, rvds_cone=False)
        traced = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
    t0 = time.perf_counter()
    cdd = tvms(state, method="cdd", rvds_cone=False, time_limit=time_limit)
    cdd_s = time.perf_counter() - t0
    return {
        "size": {"joints": state.num_joints, "contacts": len(state.contacts), "refs": len(state.refs)},
        "lp": {
            "median_s": statistics.median(totals),
            "min_s": min(totals),
            "highs_run_s": statistics.median(runs),
            "repeats": len(totals),
            **_summary(result),
        },
        "cdd": {
            "finished": cdd.status != "timeout",
            "wall_s": cdd_s,
            "time_limit_s": time_limit,
            "hausdorff_vs_lp": _hausdorff(result, cdd) if cdd.status == "bounded" else None,
            **_summary(cdd),
        },
        "memory_mib": {
            "peak_rss_before": rss_before,
            "peak_rss_after_lp": rss_after,
            "tracemalloc_peak_lp": traced,
            "cdd_child_peak_rss": _rss_mib(resource.RUSAGE_CHILDREN),
        },
    }


def run_tvms_benchmark(
    cases: Sequence[str] = ("case1", "case2"),
    *,
    repeats: dict[str, int] | None = None,
    time_limit: float = 120.0,
    trace_memory: bool = True,
) -> dict[str, Any]:
    """Benchmark the shipped scenarios (:func:`~mjtvm.sim.scenario.load_scenario`); JSON-ready report."""
    from ..sim.scenario import load_scenario

    reps = {"case1": 50, "case2": 1} | (repeats or {})
    per_case = {}
    for name in cases:
        state = load_scenario(name).state()
        per_case[name] = bench_tvms_state(
            state, repeats=reps.get(name, 3), time_limit=time_limit, trace_memory=trace_memory
        )
        per_case[name]["paper_s"] = PAPER_S.get(name)
        per_case[name]["target_s"] = TARGETS_S.get(name)
        target = TARGETS_S.get(name)
        per_case[name]["meets_target"] = (
            None if target is None else per_case[name]["lp"]["median_s"] <= target
        )
    return {
        "schema": "mjtvm.bench-tvms/1",
        "machine": machine_info(),
        "settings": {"time_limit_s": time_limit, "repeats": reps, "rvds_cone": False, "box": "eliminated"},
        "per_case": per_case,
    }


def format_tvms_table(report: dict[str, Any]) -> str:
    """A plain-text table of a :func:`run_tvms_benchmark` report."""
    head = (
        f"{'case':<6} {'dim':>3} {'verts':>6} {'LPs':>6} {'LP s':>9} {'run() s':>8} {'target':>7} "
        f"{'paper s':>8} {'cdd s':>22} {'Hausdorff':>9} {'RSS MiB':>8} {'traced':>7}"
    )
    lines = [head, "-" * len(head)]
    for name, r in report["per_case"].items():
        lp, cdd, mem = r["lp"], r["cdd"], r["memory_mib"]
        cdd_txt = (
            f"{cdd['wall_s']:.3f}" if cdd["finished"] else f"did not finish in {cdd['time_limit_s']:.0f}"
        )
        haus = "-" if cdd["hausdorff_vs_lp"] is None else f"{cdd['hausdorff_vs_lp']:.1e}"
        traced = "-" if mem["tracemalloc_peak_lp"] is None else f"{mem['tracemalloc_peak_lp']:.1f}"
        lines.append(
            f"{name:<6} {lp['dimension']:>3} {lp['vertices']:>6} {lp['num_lps']:>6} {lp['median_s']:9.4f} "
            f"{lp['highs_run_s']:8.3f} {r['target_s']:7.2f} {r['paper_s']:8.2f} {cdd_txt:>22} {haus:>9} "
            f"{mem['peak_rss_after_lp']:8.0f} {traced:>7}"
        )
    m = report["machine"]
    lines += [
        "",
        "LP s = median wall time of tvms(state, rvds_cone=False); run() s = inside HiGHS; cdd s = the",
        "vertex-enumeration baseline (child process); Hausdorff = its vertices vs the LP's, relative;",
        "RSS = process peak resident set after the LP runs; traced = tracemalloc peak of one LP run.",
        f"machine: {m['cpu']}, {m['logical_cpus']} logical CPUs, Python {m['python']}",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    report = run_tvms_benchmark()
    print(format_tvms_table(report))
    print(json.dumps(report, indent=1))
