r"""Timing of Problem 2 (TVMMP) on Case-2-sized states, against a cvxpy baseline.

The paper reports 0.20 s per state for Problem 2 at the Case 2 initial state (MATLAB,
Core Solo U1300 1.06 GHz); mjtvm's target is at most [`TARGET_S`][benchmarks.timing.TARGET_S] per state. A
Case-2-sized state has 16 joints (four fingers of four), five contacts (F, L, F, L, D),
one REFS vertex and four RVDS vertices (eq. 37), so four LPs. Measured per state:

* ``tvmmp(state, witnesses=False)`` (HiGHS, eliminated box) and the same with
  ``box="literal"``: median wall time over many repeats after a warm-up;
* where the time goes: the HiGHS ``run()`` calls are timed through
  [`observe_runs()`][mjtvm.lp.highspy_start.observe_runs] for the duration of one measurement, the rest of a call is
  Python overhead, of which `assemble()` alone is timed too;
* the baseline [`reference_tvmmp()`][oracles.reference.reference_tvmmp], which rebuilds a cvxpy problem
  for every pair, in the same run.

All times come from [`time.perf_counter()`][time.perf_counter]; the garbage collector stays enabled.
"""

from __future__ import annotations

import importlib.metadata
import os
import platform
import statistics
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.synthetic import random_state
from mjtvm.lp.highs import observe_runs
from mjtvm.model.state import GraspState
from mjtvm.problem2.assembly import assemble
from mjtvm.problem2.tvmmp import tvmmp
from oracles.reference import reference_tvmmp

__all__ = [
    "PAPER_S",
    "TARGET_S",
    "case2_state",
    "format_table",
    "highs_split",
    "machine_info",
    "run_benchmark",
    "timed_calls",
]

TARGET_S = 5e-3  #: target wall time per state (s)
PAPER_S = 0.20  #: the paper's Problem 2 time at the Case 2 initial state (s)
_PACKAGES = ("mjtvm", "numpy", "scipy", "highspy", "clarabel", "cvxpy")


def case2_state(seed: int) -> GraspState:
    """A seeded synthetic state of the size of the paper's Case 2 (16 joints, 5 contacts, 1 x 4 LPs)."""
    return random_state(
        seed, fingers=4, joints_per_finger=4, contact_types=("F", "L", "F", "L", "D"), num_refs=1, num_rvds=4
    )


def machine_info() -> dict[str, Any]:
    """CPU model (``/proc/cpuinfo``), core counts, OS, Python and package versions."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions: dict[str, str | None] = {}
    for name in _PACKAGES:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            versions[name] = None
    affinity = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None
    return {
        "cpu": cpu,
        "logical_cpus": os.cpu_count(),
        "usable_cpus": affinity,
        "platform": platform.platform(),
        "python": platform.python_version(),
        "packages": versions,
    }


def _timed(fn: Callable[[], object], repeats: int, warmup: int) -> list[float]:
    for _ in range(warmup):
        fn()
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return out


@contextmanager
def highs_run_timer() -> Iterator[list[float]]:
    """Record the wall time of every HiGHS ``run`` ([`observe_runs()`][mjtvm.lp.highspy_start.observe_runs])."""
    spent: list[float] = []
    with observe_runs(spent.append):
        yield spent


def timed_calls(state: GraspState, repeats: int, warmup: int) -> tuple[list[float], list[float], int]:
    """Per timed call of ``tvmmp(state, witnesses=False)`` (after ``warmup`` untimed ones): its
    wall time and its time inside HiGHS ``run()`` (s), and the ``run()`` calls of the last one."""
    totals, runs = [], []
    with highs_run_timer() as spent:
        for i in range(warmup + repeats):
            spent.clear()
            t0 = time.perf_counter()
            tvmmp(state, witnesses=False)
            total = time.perf_counter() - t0
            if i >= warmup:
                totals.append(total)
                runs.append(sum(spent))
    return totals, runs, len(spent)


def highs_split(state: GraspState, repeats: int, warmup: int) -> dict[str, float]:
    """Medians of one Problem 2 call's total, its HiGHS ``run()`` time and the rest.

    Parameters
    ----------
    state : GraspState
        The state solved by ``tvmmp(state, witnesses=False)``.
    repeats, warmup : int
        Timed and untimed (first) instrumented calls.

    Returns
    -------
    dict of str to float
        ``total_s``, ``highs_run_s``, ``python_overhead_s`` (medians, s) and
        ``highs_run_calls`` (HiGHS ``run()`` calls per Problem 2 call).
    """
    totals, runs, calls = timed_calls(state, repeats, warmup)
    other = [t - r for t, r in zip(totals, runs)]
    return {
        "total_s": statistics.median(totals),
        "highs_run_s": statistics.median(runs),
        "python_overhead_s": statistics.median(other),
        "highs_run_calls": float(calls),
    }


def _summary(times: Sequence[float]) -> dict[str, float]:
    a = np.asarray(times)
    return {
        "median_s": float(np.median(a)),
        "p10_s": float(np.percentile(a, 10)),
        "p90_s": float(np.percentile(a, 90)),
        "min_s": float(a.min()),
        "repeats": len(a),
    }


def bench_state(
    state: GraspState,
    *,
    repeats: int = 300,
    baseline_repeats: int = 10,
    warmup: int = 20,
    baseline_solver: str = "CLARABEL",
) -> dict[str, Any]:
    """Every measurement of the module docstring for one state; times in seconds."""
    ours = _summary(_timed(lambda: tvmmp(state, witnesses=False), repeats, warmup))
    literal = _summary(_timed(lambda: tvmmp(state, witnesses=False, box="literal"), repeats, warmup))
    asm = _summary(_timed(lambda: assemble(state, copies=1, box="eliminated"), repeats, warmup))
    split = highs_split(state, repeats, warmup)
    split["assemble_s"] = asm["median_s"]
    result = tvmmp(state, witnesses=False)
    ref_alpha: list[Any] = []
    base = _summary(
        _timed(
            lambda: ref_alpha.append(reference_tvmmp(state, solver=baseline_solver)[0]), baseline_repeats, 1
        )
    )
    diff = (
        float(np.nanmax(np.abs(result.alpha - ref_alpha[-1]))) if np.any(np.isfinite(result.alpha)) else 0.0
    )
    return {
        "ours": ours,
        "literal": literal,
        "split": split,
        "baseline": base,
        "ratio_baseline_over_ours": base["median_s"] / ours["median_s"],
        "num_lps": result.timings.num_lps,
        "tvmmp": result.tvmmp,
        "max_abs_alpha_diff_vs_baseline": diff,
    }


def run_benchmark(
    seeds: Sequence[int] = (0, 1, 2),
    *,
    repeats: int = 300,
    baseline_repeats: int = 10,
    warmup: int = 20,
    baseline_solver: str = "CLARABEL",
) -> dict[str, Any]:
    """Benchmark [`case2_state()`][benchmarks.timing.case2_state] for each seed; returns the JSON-ready report."""
    per_seed = {}
    for seed in seeds:
        state = case2_state(seed)
        per_seed[str(seed)] = bench_state(
            state,
            repeats=repeats,
            baseline_repeats=baseline_repeats,
            warmup=warmup,
            baseline_solver=baseline_solver,
        )
        per_seed[str(seed)]["size"] = {
            "joints": state.num_joints,
            "contacts": len(state.contacts),
            "refs": len(state.refs),
            "rvds": 0 if state.rvds is None else len(state.rvds),
        }
    ours = statistics.median(r["ours"]["median_s"] for r in per_seed.values())
    base = statistics.median(r["baseline"]["median_s"] for r in per_seed.values())
    return {
        "schema": "benchmarks/1",
        "machine": machine_info(),
        "settings": {
            "seeds": list(seeds),
            "repeats": repeats,
            "baseline_repeats": baseline_repeats,
            "warmup": warmup,
            "solver": "highs",
            "baseline": f"oracles.reference.reference_tvmmp (cvxpy {baseline_solver}, rebuilt per pair)",
        },
        "target_s": TARGET_S,
        "paper_s": PAPER_S,
        "median_ours_s": ours,
        "median_baseline_s": base,
        "ratio_baseline_over_ours": base / ours,
        "meets_target": ours <= TARGET_S,
        "per_seed": per_seed,
    }


def format_table(report: dict[str, Any]) -> str:
    """A plain-text table of a [`run_benchmark()`][benchmarks.timing.run_benchmark] report (times in ms)."""
    head = (
        f"{'seed':>4} {'ours':>8} {'literal':>8} {'run()':>8} {'python':>8} {'assemble':>9} "
        f"{'cvxpy':>8} {'ratio':>7} {'|dalpha|':>9}"
    )
    lines = [head, "-" * len(head)]
    for seed, r in report["per_seed"].items():
        s = r["split"]
        lines.append(
            f"{seed:>4} {1e3 * r['ours']['median_s']:8.3f} {1e3 * r['literal']['median_s']:8.3f} "
            f"{1e3 * s['highs_run_s']:8.3f} {1e3 * s['python_overhead_s']:8.3f} {1e3 * s['assemble_s']:9.3f} "
            f"{1e3 * r['baseline']['median_s']:8.1f} {r['ratio_baseline_over_ours']:7.1f} "
            f"{r['max_abs_alpha_diff_vs_baseline']:9.1e}"
        )
    m = report["machine"]
    lines += [
        "",
        "medians per state in ms; ours = tvmmp(state, witnesses=False) (HiGHS, eliminated box); run() = time",
        "inside the HiGHS run() calls, python = the rest of the call (of which assemble = assemble() alone);",
        "cvxpy = reference_tvmmp rebuilt per pair; ratio = cvxpy / ours.",
        f"overall: ours {1e3 * report['median_ours_s']:.3f} ms, cvxpy {1e3 * report['median_baseline_s']:.1f} ms, "
        f"ratio {report['ratio_baseline_over_ours']:.1f}; target <= {1e3 * report['target_s']:.0f} ms: "
        f"{'met' if report['meets_target'] else 'NOT met'} (paper: {1e3 * report['paper_s']:.0f} ms, MATLAB, 1.06 GHz)",
        f"machine: {m['cpu']}, {m['logical_cpus']} logical CPUs, Python {m['python']}, "
        + ", ".join(f"{k} {v}" for k, v in m["packages"].items()),
    ]
    return "\n".join(lines)
