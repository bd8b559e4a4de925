r"""The paper's cases in the benchmark suite: Case 1's RVDS ([`case1_beta()`][benchmarks.cases.case1_beta],
[`case1_rvds()`][benchmarks.cases.case1_rvds]), Problem 1 and Problem 2 per state, and the rows of Cases 1 and 2.
"""

from __future__ import annotations

import resource
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from benchmarks.measure import rss_mib, stats, traced_peak_mib
from mjtvm.errors import ParamError

__all__ = ["bench_problem1", "bench_problem2", "case1_beta", "case1_rvds", "paper_cases"]


def case1_beta(state: Any) -> np.ndarray:
    r"""The one in-plane motion (xdot, zdot, omega_y) finger 3's two contacts leave (unit, unscaled).

    rdot = E z (E the in-plane basis) is reachable by finger 3's contacts iff G_c^T E z lies in
    range(J_c) (eq. 7): the null space of (I - U U^T) G_c^T E, U an orthonormal basis of
    range(J_c), as in ``tests/paper_hand/test_scenario.py``. The sign makes its xdot component >= 0.
    """
    from mjtvm.problem2.assembly import grasp_map_transpose

    by_name = {c.name: c for c in state.contacts}
    names = ["f3_link1", "f3_link2"]
    jac = np.vstack([by_name[n].jacobian for n in names])
    gt = np.vstack([grasp_map_transpose(by_name[n].position, state.object_position) for n in names])
    plane = np.eye(6)[:, [0, 2, 4]]
    u, s, _ = np.linalg.svd(jac)
    u = u[:, : int((s > 1e-9 * s[0]).sum())]
    k = (gt - u @ (u.T @ gt)) @ plane
    _, sk, vt = np.linalg.svd(k)
    sk = np.r_[sk, np.zeros(3 - len(sk))]
    null = vt[sk <= 1e-9 * max(sk[0], 1.0)]
    if len(null) != 1:
        raise ParamError(
            "state", f"expected one in-plane motion of finger 3, got {len(null)} (singular values {sk})"
        )
    beta = plane @ null[0]
    return beta if beta[0] >= 0 else -beta


def case1_rvds(state: Any) -> np.ndarray:
    """The digest's 8 RVDS vertices: +-e_y, +-e_4 (omega_x), +-e_6 (omega_z), +-beta."""
    e = np.eye(6)
    beta = case1_beta(state)
    return np.array([e[1], -e[1], e[3], -e[3], e[5], -e[5], beta, -beta])


def bench_problem1(
    state: Any,
    *,
    repeats: int = 5,
    warmup: int = 1,
    rvds_cone: bool = False,
    cdd: bool = True,
    time_limit: float = 120.0,
    trace_memory: bool = True,
) -> dict[str, Any]:
    """Problem 1 by support LPs (median over ``repeats``), memory, and the capped cdd baseline."""
    from benchmarks.problem1 import tvms_hausdorff, tvms_summary
    from benchmarks.timing import highs_run_timer
    from mjtvm.polytopes.tvms import tvms

    for _ in range(warmup):
        tvms(state, rvds_cone=rvds_cone)
    totals, runs, project, volume = [], [], [], []
    with highs_run_timer() as spent:
        for _ in range(max(repeats, 1)):
            spent.clear()
            t0 = time.perf_counter()
            result = tvms(state, rvds_cone=rvds_cone)
            totals.append(time.perf_counter() - t0)
            runs.append(sum(spent))
            project.append(result.timings.project_s)
            volume.append(result.timings.volume_s)
    split = {
        "highs_run_s": statistics.median(runs),
        "project_s": statistics.median(project),
        "volume_s": statistics.median(volume),
    }
    out: dict[str, Any] = {
        "size": {"joints": state.num_joints, "contacts": len(state.contacts), "refs": len(state.refs)},
        "lp": {**stats(totals), **split, **tvms_summary(result)},
        "memory_mib": {
            "ru_maxrss": rss_mib(),
            "tracemalloc_peak": traced_peak_mib(lambda: tvms(state, rvds_cone=rvds_cone))
            if trace_memory
            else None,
        },
        "cdd": None,
    }
    if cdd:
        t0 = time.perf_counter()
        other = tvms(state, method="cdd", rvds_cone=rvds_cone, time_limit=time_limit)
        wall = time.perf_counter() - t0
        out["cdd"] = {
            "finished": other.status != "timeout",
            "wall_s": wall,
            "time_limit_s": time_limit,
            "hausdorff_vs_lp": tvms_hausdorff(result, other) if other.status == "bounded" else None,
            "child_ru_maxrss_mib": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0,
            **tvms_summary(other),
        }
    return out


def bench_problem2(
    state: Any, *, repeats: int = 200, baseline_repeats: int = 10, warmup: int = 10
) -> dict[str, Any]:
    """Problem 2 per state ([`benchmarks.timing.bench_state()`][benchmarks.timing.bench_state]: ours, literal box, split, cvxpy baseline)."""
    from benchmarks.timing import bench_state

    out = bench_state(state, repeats=repeats, baseline_repeats=baseline_repeats, warmup=warmup)
    out["size"] = {
        "joints": state.num_joints,
        "contacts": len(state.contacts),
        "refs": len(state.refs),
        "rvds": 0 if state.rvds is None else len(state.rvds),
    }
    return out


def paper_cases(
    *,
    quick: bool,
    repeats: int,
    baseline_repeats: int,
    p1_repeats: int,
    time_limit: float,
    say: Callable[[str], None],
) -> dict[str, Any]:
    """The rows ``case1_p1``, ``case1_p2`` (8 RVDS vertices, with beta), ``case2_p1`` (not
    ``quick``) and ``case2_p2`` of the report."""
    from mjtvm.paper_hand.scenario import load_scenario

    out: dict[str, Any] = {}
    case1 = load_scenario("case1").state()
    say("case 1, problem 1")
    out["case1_p1"] = bench_problem1(case1, repeats=p1_repeats, cdd=not quick, time_limit=time_limit)
    say("case 1, problem 2 (8 RVDS vertices)")
    out["case1_p2"] = bench_problem2(
        case1.with_(rvds=case1_rvds(case1)), repeats=repeats, baseline_repeats=baseline_repeats
    )
    out["case1_p2"]["beta"] = case1_beta(case1).tolist()
    case2 = load_scenario("case2").state()
    if not quick:
        say("case 2, problem 1 without RVDS (a warm-up and 3 runs of ~2 s; then cdd capped)")
        out["case2_p1"] = bench_problem1(
            case2.with_(rvds=None), repeats=3, warmup=1, cdd=True, time_limit=time_limit, trace_memory=False
        )
    say("case 2, problem 2")
    out["case2_p2"] = bench_problem2(case2, repeats=repeats, baseline_repeats=baseline_repeats)
    return out
