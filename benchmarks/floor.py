r"""Problem 2 against its solver's floor: how much of a state's time is HiGHS's own.

Per state, ``tvmmp(state, witnesses=False)`` (HiGHS, eliminated box, every answer certified)
is timed, and within the same calls the time inside HiGHS ``run()``
([`observe_runs()`][mjtvm.lp.highspy_start.observe_runs]): the floor is HiGHS solving exactly these LPs from
exactly these bases, and the ratio ``total / run`` is what mjtvm's Python around the solver
(assembly, equilibration, the HiGHS session, the certificates, the result) costs on top of it.
The ratio of each call is computed on that call (both in the same run, so the machine's load
cancels to first order) and its median is reported, with the medians of both times and the
process's CPU time over its wall time during the calls (``core_share``: 1 for a solve on one
core; a BLAS thread that spins beside it shows as 2).

The states: the paper's Case 2 initial state (4 LPs), Case 1 with the 8 RVDS vertices of
[`case1_rvds()`][benchmarks.cases.case1_rvds], the ``allegro-ik`` grasp (16 joints, 4 contacts, 6 RVDS
vertices) and the 22-joint dataset hand ([`dataset_state()`][benchmarks.dataset.dataset_state]) with the
weight (6 LPs) and with six test wrenches (36 LPs) as REFS. Target: ratio at most
[`TARGET_RATIO`][benchmarks.floor.TARGET_RATIO].

``dataset-36-compiled``: the 36-LP state with ``tvmmp(..., compiled=True)`` (the batch paths'
call: the LPs after the first are re-solved by the compiled dual simplex of
[`warm`][mjtvm.lp.warm] where it does not give up, 1 HiGHS run instead of 36), each call
against the time inside HiGHS ``run()`` of a HiGHS-alone call of the same state right before
it: the floor stays HiGHS solving all 36 LPs, so the ratio says what the whole call costs
over what HiGHS alone would spend in ``run()``.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any

from benchmarks.timing import timed_calls
from mjtvm.model.state import GraspState
from mjtvm.problem2.tvmmp import tvmmp

__all__ = ["FLOOR_STATES", "TARGET_RATIO", "bench_floor", "floor_states"]

TARGET_RATIO = 1.5  #: Problem 2's wall time over its time inside HiGHS ``run()``, at most
FLOOR_STATES = ("case2", "case1", "allegro-ik", "dataset-6", "dataset-36", "dataset-36-compiled")


def floor_states() -> dict[str, GraspState]:
    """The states of [`FLOOR_STATES`][benchmarks.floor.FLOOR_STATES] (module docstring)."""
    from benchmarks.cases import case1_rvds
    from benchmarks.dataset import dataset_state
    from mjtvm.grasp.resolve.file import load_grasp
    from mjtvm.paper_hand.scenario import load_scenario

    case1 = load_scenario("case1").state()
    return {
        "case2": load_scenario("case2").state(),
        "case1": case1.with_(rvds=case1_rvds(case1)),
        "allegro-ik": load_grasp("allegro-ik").state(),
        "dataset-6": dataset_state(0),
        "dataset-36": dataset_state(0, num_refs=6),
        "dataset-36-compiled": dataset_state(0, num_refs=6),
    }


def _measure(state: GraspState, repeats: int, warmup: int) -> dict[str, Any]:
    """Medians of a call's total, its time inside HiGHS ``run()`` and their per-call ratio."""
    wall, cpu = time.perf_counter(), time.process_time()
    totals, runs, calls = timed_calls(state, repeats, warmup)
    share = (time.process_time() - cpu) / (time.perf_counter() - wall)
    ratios = sorted(t / r for t, r in zip(totals, runs))
    ratio = statistics.median(ratios)
    return {
        "lps": tvmmp(state, witnesses=False).timings.num_lps,
        "highs_runs": calls,
        "total_s": statistics.median(totals),
        "highs_run_s": statistics.median(runs),
        "ratio": ratio,
        "ratio_p10": ratios[len(ratios) // 10],
        "ratio_p90": ratios[(9 * len(ratios)) // 10],
        "repeats": repeats,
        "core_share": share,
        "met": ratio <= TARGET_RATIO,
    }


def _measure_compiled(state: GraspState, repeats: int, warmup: int) -> dict[str, Any]:
    """`_measure()` of ``tvmmp(state, witnesses=False, compiled=True)``, each call's total over
    the ``run()`` time of a HiGHS-alone call just before it (module docstring)."""
    from mjtvm.lp.highs import observe_runs

    totals, runs, inside_compiled = [], [], []
    cpu_spent = wall_spent = 0.0
    for i in range(warmup + repeats):
        spent: list[float] = []
        with observe_runs(spent.append):
            tvmmp(state, witnesses=False)
        mark = len(spent)
        w0, c0 = time.perf_counter(), time.process_time()
        with observe_runs(spent.append):
            tvmmp(state, witnesses=False, compiled=True)
        total, cpu = time.perf_counter() - w0, time.process_time() - c0
        if i >= warmup:
            totals.append(total)
            runs.append(sum(spent[:mark]))
            inside_compiled.append(sum(spent[mark:]))
            cpu_spent, wall_spent = cpu_spent + cpu, wall_spent + total
    ratios = sorted(t / r for t, r in zip(totals, runs))
    ratio = statistics.median(ratios)
    return {
        "lps": tvmmp(state, witnesses=False, compiled=True).timings.num_lps,
        "highs_runs": len(spent) - mark,
        "total_s": statistics.median(totals),
        "highs_run_s": statistics.median(runs),
        "highs_run_compiled_s": statistics.median(inside_compiled),
        "ratio": ratio,
        "ratio_p10": ratios[len(ratios) // 10],
        "ratio_p90": ratios[(9 * len(ratios)) // 10],
        "repeats": repeats,
        "core_share": cpu_spent / wall_spent,
        "met": ratio <= TARGET_RATIO,
    }


def bench_floor(
    *, repeats: int = 100, warmup: int = 10, say: Callable[[str], None] = lambda _: None
) -> dict[str, Any]:
    """``{"target_ratio", "states": {name: _measure}}`` for every state of [`floor_states()`][benchmarks.floor.floor_states];
    the 36-LP states are repeated a sixth as often (their call is six times longer)."""
    out: dict[str, Any] = {"target_ratio": TARGET_RATIO, "states": {}}
    for name, state in floor_states().items():
        say(f"Problem 2 against HiGHS's own time: {name}")
        n = max(10, repeats // 6) if name.startswith("dataset-36") else repeats
        measure = _measure_compiled if name.endswith("-compiled") else _measure
        out["states"][name] = measure(state, n, max(2, warmup * n // repeats))
    return out
