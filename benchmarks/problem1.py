r"""Timing of Problem 1 (the TVMS) on the paper's states, against the cdd baseline.

The paper (MATLAB, Core Solo U1300 1.06 GHz) reports 0.19 s for Case 1 (Problem 1, no
RVDS) and 129 s for Case 2's initial state (Problem 1 without RVDS). mjtvm's targets are
[`TARGETS_S`][benchmarks.problem1.TARGETS_S]. For each state, in one run:

* ``tvms(state, rvds_cone=False)`` (support LPs on HiGHS): the median wall time over
  ``repeats`` calls after ``warmup`` calls, the time inside HiGHS ``run()``
  ([`highs_run_timer()`][benchmarks.timing.highs_run_timer]), the LP count, the dimension, the number of
  vertices and the scaled affine volume;
* ``tvms(state, method="cdd", rvds_cone=False)``: the paper's vertex enumeration in a child
  process, its wall time or "did not finish in ``time_limit`` s", and how far its
  vertices lie from the LP method's (Hausdorff distance relative to the extent);
* memory: the process's peak resident set (``resource.getrusage``) before and after the
  state's LP runs, the peak of Python allocations during one more LP run under
  [`tracemalloc`][tracemalloc] (HiGHS' and Qhull's own buffers are not traced), and the cdd child's
  peak resident set.

Run it as ``python -m benchmarks.problem1`` (prints a table, then the JSON report).

**Problem 1 at scale** ([`bench_p1_scale()`][benchmarks.problem1.bench_p1_scale], ``python -m benchmarks.problem1 --scale``):
one row per case, each in a fresh child process whose own peak resident set is reported
beside its wall time ([`SCALE_CASES`][benchmarks.problem1.SCALE_CASES]): Case 2's initial state, exact; the Allegro test
hand's 16-joint four-fingertip grasp (``allegro-sphere``) with its TVMS restricted to the
coordinate subspace of the 3 translations and the first ``D - 3`` rotations (3-D: translations;
4-D: + omega_x; 5-D: + omega_y; 6-D: all), i.e. the section of S_ov by that subspace, which is
what the RVDS cone of ``+-e_i`` (i in the subspace) gives (6-D: no RVDS); the 16-finger
synthetic hand ([`scaling_hand()`][benchmarks.scaling.scaling_hand], its RVDS cone). The Allegro 5-D and
6-D rows ask for a 1 % volume bracket within 60 s (``tolerance=0.01, time_limit=60``).
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

from benchmarks.timing import highs_run_timer, machine_info
from mjtvm.model.state import GraspState
from mjtvm.polytopes.tvms import TvmsResult, tvms
from mjtvm.polytopes.volume import hausdorff

__all__ = [
    "PAPER_S",
    "SCALE_CASES",
    "TARGETS_S",
    "bench_p1_scale",
    "bench_tvms_state",
    "format_scale_table",
    "format_tvms_table",
    "run_tvms_benchmark",
    "tvms_hausdorff",
    "tvms_summary",
]

PAPER_S = {"case1": 0.19, "case2": 129.0}  #: the paper's Problem 1 times (s)
TARGETS_S = {"case1": 0.05, "case2": 2.0}  #: mjtvm's targets for the LP method (s)


def _rss_mib(who: int = resource.RUSAGE_SELF) -> float:
    """Peak resident set size in MiB (``ru_maxrss`` is in KiB on Linux)."""
    return resource.getrusage(who).ru_maxrss / 1024.0


def tvms_hausdorff(a: TvmsResult, b: TvmsResult) -> float | None:
    """Hausdorff distance of two TVMS vertex sets relative to the extent.

    Parameters
    ----------
    a, b : TvmsResult
        Two results of the same state (e.g. mjtvm's and a baseline's); ``a`` sets the extent.

    Returns
    -------
    float or None
        The distance over ``a``'s largest absolute coordinate, in physical units; ``None`` if
        either vertex set is empty.
    """
    if not len(a.vertices) or not len(b.vertices):
        return None
    extent = float(np.max(np.abs(a.vertices * a.scale)))
    return hausdorff(a.vertices * a.scale, b.vertices * b.scale) / max(extent, 1e-300)


def tvms_summary(r: TvmsResult) -> dict[str, Any]:
    """The report fields of one TVMS result.

    Parameters
    ----------
    r : TvmsResult
        A result of ``tvms`` (or of a baseline).

    Returns
    -------
    dict of str to Any
        ``status``, ``dimension``, ``vertices`` (their count), ``volume``, ``affine_volume``,
        ``num_lps`` and ``lifted_vertices``.
    """
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
            **tvms_summary(result),
        },
        "cdd": {
            "finished": cdd.status != "timeout",
            "wall_s": cdd_s,
            "time_limit_s": time_limit,
            "hausdorff_vs_lp": tvms_hausdorff(result, cdd) if cdd.status == "bounded" else None,
            **tvms_summary(cdd),
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
    """Benchmark the shipped scenarios ([`load_scenario()`][mjtvm.paper_hand.scenario.load_scenario]); JSON-ready report."""
    from mjtvm.paper_hand.scenario import load_scenario

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
        "schema": "benchmarks-tvms/1",
        "machine": machine_info(),
        "settings": {"time_limit_s": time_limit, "repeats": reps, "rvds_cone": False, "box": "eliminated"},
        "per_case": per_case,
    }


def format_tvms_table(report: dict[str, Any]) -> str:
    """A plain-text table of a [`run_tvms_benchmark()`][benchmarks.problem1.run_tvms_benchmark] report."""
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


#: name: (state, tvms keyword arguments, target (s, MiB) or None)
SCALE_CASES: dict[str, tuple[str, dict[str, Any], tuple[float, float] | None]] = {
    "case2 exact": ("case2", {"rvds_cone": False}, (1.0, 2048.0)),
    "allegro 3-D exact": ("allegro:3", {}, None),
    "allegro 4-D exact": ("allegro:4", {}, None),
    "allegro 5-D 1 %": ("allegro:5", {"tolerance": 0.01, "time_limit": 60.0}, (60.0, 2048.0)),
    "allegro 6-D 1 %": ("allegro:6", {"tolerance": 0.01, "time_limit": 60.0}, (60.0, 2048.0)),
    "16 fingers exact": ("scaling:16", {}, None),
}


def scale_state(spec: str) -> GraspState:
    """The state of a [`SCALE_CASES`][benchmarks.problem1.SCALE_CASES] entry (``case2``, ``allegro:D``, ``scaling:F``)."""
    if spec.startswith("allegro:"):
        from mjtvm.grasp.resolve.file import load_grasp

        dim = int(spec.split(":")[1])
        state = load_grasp("allegro-sphere").state()
        if dim == 6:
            return state.with_(rvds=None)
        return state.with_(rvds=np.array([sign * np.eye(6)[i] for i in range(dim) for sign in (1.0, -1.0)]))
    if spec.startswith("scaling:"):
        from benchmarks.scaling import scaling_hand

        return scaling_hand(int(spec.split(":")[1]))
    from mjtvm.paper_hand.scenario import load_scenario

    return load_scenario(spec).state()


def _scale_child(spec: str, kwargs: dict[str, Any], send: Any) -> None:
    state = scale_state(spec)
    t0 = time.perf_counter()
    r = tvms(state, **kwargs)
    wall = time.perf_counter() - t0
    send.send(
        {
            "wall_s": wall,
            "peak_rss_mib": _rss_mib(),
            "status": r.status,
            "stopped_by": None if r.stopped_by is None else r.stopped_by[0],
            "dimension": r.dimension,
            "vertices": len(r.vertices),
            "num_lps": r.timings.num_lps,
            "affine_volume": r.affine_volume,
            "affine_volume_bracket": None
            if r.affine_volume_bracket is None
            else r.affine_volume_bracket.tolist(),
            "hausdorff_gap": r.hausdorff_gap,
            "volume_estimate": r.to_dict()["volume_estimate"],
        }
    )


def bench_p1_scale(
    names: Sequence[str] | None = None, *, repeats: int = 1, say: Any = print
) -> dict[str, Any]:
    """Rows of [`SCALE_CASES`][benchmarks.problem1.SCALE_CASES] (module docstring): the median over ``repeats`` fresh child
    processes of the wall time of ``tvms``, and the largest child peak resident set."""
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    rows: dict[str, Any] = {}
    for name in names or list(SCALE_CASES):
        spec, kwargs, target = SCALE_CASES[name]
        runs = []
        for _ in range(max(repeats, 1)):
            say(f"problem 1 at scale: {name}")
            recv, send = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_scale_child, args=(spec, kwargs, send))
            proc.start()
            send.close()
            try:
                runs.append(recv.recv())
            except EOFError:
                runs.append({"status": "crashed", "exitcode": None})
            proc.join()
            if runs[-1]["status"] == "crashed":
                runs[-1]["exitcode"] = proc.exitcode
        ok = [r for r in runs if "wall_s" in r]
        row = dict(ok[-1]) if ok else dict(runs[-1])
        if ok:
            row["wall_s"] = statistics.median(r["wall_s"] for r in ok)
            row["peak_rss_mib"] = max(r["peak_rss_mib"] for r in ok)
        row.update(kwargs=kwargs, repeats=len(runs), target_s=None if target is None else target[0])
        row["target_mib"] = None if target is None else target[1]
        row["meets_target"] = (
            None
            if target is None or not ok
            else row["wall_s"] <= target[0] and row["peak_rss_mib"] <= target[1] and _within(row, kwargs)
        )
        rows[name] = row
    return {"schema": "benchmarks-p1-scale/1", "machine": machine_info(), "rows": rows}


def _within(row: dict[str, Any], kwargs: dict[str, Any]) -> bool:
    """Exact, or a bracket as narrow as asked."""
    if row["status"] == "bounded":
        return True
    b = row.get("affine_volume_bracket")
    if not b:
        return False
    return b[1] > 0 and (b[1] - b[0]) / b[1] <= kwargs.get("tolerance", 0.0)


def format_scale_table(report: dict[str, Any]) -> str:
    """A plain-text table of [`bench_p1_scale()`][benchmarks.problem1.bench_p1_scale]."""
    head = (
        f"{'case':<18} {'status':<22} {'dim':>3} {'verts':>6} {'LPs':>6} {'s':>8} {'MiB':>7} {'bracket':>26} "
        f"{'gap':>7} {'estimate (99.9 %)':>26}"
    )
    lines = [head, "-" * len(head)]
    for name, r in report["rows"].items():
        b = r.get("affine_volume_bracket")
        btxt = "-" if not b else f"[{b[0]:.5g}, {b[1]:.5g}]"
        gap = "-" if not b or b[1] <= 0 else f"{100 * (b[1] - b[0]) / b[1]:.2f} %"
        e = r.get("volume_estimate")
        etxt = "-" if not e else f"[{e['affine_interval'][0]:.5g}, {e['affine_interval'][1]:.5g}]"
        status = r["status"] + ("" if not r.get("stopped_by") else f"/{r['stopped_by']}")
        lines.append(
            f"{name:<18} {status:<22} {r.get('dimension')!s:>3} {r.get('vertices', 0):>6} "
            f"{r.get('num_lps', 0):>6} {r.get('wall_s', float('nan')):8.2f} {r.get('peak_rss_mib', float('nan')):7.0f} "
            f"{btxt:>26} {gap:>7} {etxt:>26}"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    import sys

    if "--scale" in sys.argv:
        scale = bench_p1_scale([a for a in sys.argv[1:] if a != "--scale"] or None)
        print(format_scale_table(scale))
        print(json.dumps(scale, indent=1))
    else:
        report = run_tvms_benchmark()
        print(format_tvms_table(report))
        print(json.dumps(report, indent=1))
