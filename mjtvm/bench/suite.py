r"""The project's benchmark run (issue 7, item 1): the paper's cases, the lift, the sweeps, scaling.

One run of :func:`run_suite` (``python scripts/bench.py`` or ``mjtvm bench``) measures, with
medians over repeats and :func:`time.perf_counter`, the garbage collector enabled:

* **Case 1, Problem 1**: ``tvms(load_scenario("case1").state())`` (no RVDS; paper 0.19 s);
* **Case 1, Problem 2** with the 8-vertex RVDS of the digest (section 6): +-e_y, +-e_4
  (omega_x), +-e_6 (omega_z; the paper's e_5 is a typo) and +-beta, where beta is computed
  from the model as the one in-plane (x, z, omega_y) object motion that finger 3's two
  contacts leave (:func:`case1_beta`, unscaled unit vector; paper 0.26 s);
* **Case 2's initial state**: Problem 1 without RVDS (paper 129 s; median of 3 runs after a warm-up)
  and Problem 2 with its 4 RVDS vertices (paper 0.20 s);
* the **full lift** with both contact variants (:func:`~mjtvm.apps.replay.time_replay`: no plots,
  no sweeps; imports excluded; target <= 1 s);
* the **Fig. 9 sweeps** (9 (mu, mg) combinations x 30 states, L-points) through
  :func:`~mjtvm.apps.sweep.run_sweep` on 1 process and on 2 (``jobs=2``; the 2-process time
  includes the pool's start-up, i.e. the forkserver and the workers' imports and lifts);
* the **baselines** in the same run: cvxpy rebuilt per pair
  (:func:`~mjtvm.core.reference.reference_tvmmp`) for the Problem 2 cases and the cdd vertex
  enumeration (capped at ``time_limit`` s) for Problem 1;
* **scaling**: synthetic hands of 2, 4, 8 and 16 fingers of 4 joints (:func:`scaling_hand`:
  MJCF from :func:`~mjtvm.sim.hand.hand_mjcf`, one fingertip F-contact per finger, IK-free),
  time per TVMMP state (4 RVDS vertices) and per Problem 1 (restricted to the RVDS cone),
  with the tracemalloc peak and the process's ``ru_maxrss``.

``--quick`` skips Case 2's Problem 1 and every cdd run.
"""

from __future__ import annotations

import itertools
import math
import resource
import statistics
import time
import tracemalloc
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

__all__ = [
    "PAPER_S",
    "SCHEMA",
    "TARGETS_S",
    "case1_beta",
    "case1_rvds",
    "run_suite",
    "scaling_hand",
]

SCHEMA = "mjtvm.bench/2"
PAPER_S = {"case1_p1": 0.19, "case1_p2": 0.26, "case2_p1": 129.0, "case2_p2": 0.20}
"""The paper's times (s; MATLAB, Core Solo U1300 1.06 GHz)."""
TARGETS_S = {"case1_p1": 0.05, "case2_p1": 2.0, "p2_state": 5e-3, "lift": 1.0}
"""mjtvm's targets (s); the sweep target is a speed-up: :data:`TARGET_SWEEP_SPEEDUP`."""
TARGET_SWEEP_SPEEDUP = 1.6
SCALING_FINGERS = (2, 4, 8, 16)
SCALING_RADIUS = 0.12  # m: finger bases on this circle around the object's axis


def _rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _times(fn: Callable[[], object], repeats: int, warmup: int = 1) -> list[float]:
    for _ in range(warmup):
        fn()
    out = []
    for _ in range(max(repeats, 1)):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return out


def _stats(times: Sequence[float]) -> dict[str, Any]:
    return {"median_s": statistics.median(times), "min_s": min(times), "repeats": len(times)}


def _traced_peak_mib(fn: Callable[[], object]) -> float:
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()


# ------------------------------------------------------------------ Case 1's RVDS
def case1_beta(state: Any) -> np.ndarray:
    r"""The one in-plane motion (xdot, zdot, omega_y) finger 3's two contacts leave (unit, unscaled).

    rdot = E z (E the in-plane basis) is reachable by finger 3's contacts iff G_c^T E z lies in
    range(J_c) (eq. 7): the null space of (I - U U^T) G_c^T E, U an orthonormal basis of
    range(J_c), as in ``tests/test_scenario.py``. The sign makes its xdot component >= 0.
    """
    from ..core.assembly import grasp_map_transpose

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
        raise ValueError(f"expected one in-plane motion of finger 3, got {len(null)} (singular values {sk})")
    beta = plane @ null[0]
    return beta if beta[0] >= 0 else -beta


def case1_rvds(state: Any) -> np.ndarray:
    """The digest's 8 RVDS vertices: +-e_y, +-e_4 (omega_x), +-e_6 (omega_z), +-beta."""
    e = np.eye(6)
    beta = case1_beta(state)
    return np.array([e[1], -e[1], e[3], -e[3], e[5], -e[5], beta, -beta])


# ------------------------------------------------------------------ scaling hands
def scaling_hand(fingers: int, *, mu: float = 0.5, mg: float = 1.0) -> Any:
    r"""A grasp state of a synthetic hand with ``fingers`` fingers of 4 joints (IK-free).

    The MJCF comes from :func:`~mjtvm.sim.hand.hand_mjcf` (default finger: [yaw, pitch] at the
    base, [pitch, yaw] after link 1): bases evenly on a circle of radius
    :data:`SCALING_RADIUS` around the z axis, headings pointing inwards. Every finger takes
    the same pose (link 1 vertical, link 2 pointing up and inwards at 54 deg), so all tips lie
    on one circle at one height; the sphere's centre is put on the axis where its surface
    touches every tip (0.1 mm deep). One F-contact per finger (the tip), friction ``mu``, REFS
    = the weight ``mg``, RVDS = the 4 vertices [+-1, +-1, 1, 0, 0, 0] of Case 2.
    """
    import mujoco

    from ..sim.grasp import grasp_state
    from ..sim.hand import hand_mjcf

    angles = 2 * math.pi * np.arange(fingers) / fingers
    bases = [(SCALING_RADIUS * math.cos(a), SCALING_RADIUS * math.sin(a), 0.0) for a in angles]
    headings = [float(a + math.pi) for a in angles]
    radius, tip = 0.1, 0.005
    xml = hand_mjcf(
        finger_bases=bases, finger_headings=headings, mg=mg, object_position=(0.0, 0.0, 10.0),
        model_name=f"scaling_{fingers}",
    )  # fmt: skip
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    for f in range(1, fingers + 1):
        data.joint(f"f{f}_pitch0").qpos[0] = math.pi / 2  # link 1 vertical
        data.joint(f"f{f}_pitch1").qpos[0] = math.radians(54.0) - math.pi / 2  # link 2 up, inwards
    mujoco.mj_kinematics(model, data)
    tip_pos = data.geom("f1_tip").xpos.copy()
    r_t, z_t = math.hypot(tip_pos[0], tip_pos[1]), tip_pos[2]
    reach = radius + tip - 1e-4
    z_c = z_t + math.sqrt(reach**2 - r_t**2)
    obj = model.joint("object").qposadr[0]
    data.qpos[obj : obj + 7] = [0.0, 0.0, z_c, 1.0, 0.0, 0.0, 0.0]
    rvds = np.array([[sx, sy, 1.0, 0, 0, 0] for sx in (1, -1) for sy in (1, -1)])
    state = grasp_state(
        model, data, contact_types={f"f{f}_tip": "F" for f in range(1, fingers + 1)}, mu=mu, rvds=rvds
    )
    if len(state.contacts) != fingers or any(c.name != f"f{i}_tip" for i, c in enumerate(state.contacts, 1)):
        raise ValueError(f"expected one tip contact per finger, got {[c.name for c in state.contacts]}")
    return state


# ------------------------------------------------------------------ measurements
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
    from ..polytopes.tvms import tvms
    from .problem1 import _hausdorff, _summary
    from .timing import highs_run_timer

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
        "lp": {**_stats(totals), **split, **_summary(result)},
        "memory_mib": {
            "ru_maxrss": _rss_mib(),
            "tracemalloc_peak": _traced_peak_mib(lambda: tvms(state, rvds_cone=rvds_cone))
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
            "hausdorff_vs_lp": _hausdorff(result, other) if other.status == "bounded" else None,
            "child_ru_maxrss_mib": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0,
            **_summary(other),
        }
    return out


def bench_problem2(
    state: Any, *, repeats: int = 200, baseline_repeats: int = 10, warmup: int = 10
) -> dict[str, Any]:
    """Problem 2 per state (:func:`mjtvm.bench.timing.bench_state`: ours, literal box, split, cvxpy baseline)."""
    from .timing import bench_state

    out = bench_state(state, repeats=repeats, baseline_repeats=baseline_repeats, warmup=warmup)
    out["size"] = {
        "joints": state.num_joints,
        "contacts": len(state.contacts),
        "refs": len(state.refs),
        "rvds": 0 if state.rvds is None else len(state.rvds),
    }
    return out


def bench_lift(*, repeats: int = 3, num_states: int = 30) -> dict[str, Any]:
    """:func:`~mjtvm.apps.replay.time_replay` (L and S, no plots, no sweeps) after one untimed run."""
    from ..apps.replay import time_replay

    time_replay(repeats=1, num_states=num_states)  # warm-up: lazy imports, caches
    out = time_replay(repeats=repeats, num_states=num_states)
    out["repeats"] = repeats
    return out


def sweep_points(num_states: int = 30) -> tuple[Any, ...]:
    """The Fig. 9 sweeps as :class:`~mjtvm.apps.sweep.SweepPoint` (9a: mu at mg = 2 N; 9b: mg at mu = 0.3)."""
    from ..apps.replay import SWEEP_MG_MU, SWEEP_MGS, SWEEP_MU_MG, SWEEP_MUS
    from ..apps.sweep import grid

    return grid(mus=SWEEP_MUS, mgs=(SWEEP_MU_MG,), num_states=num_states) + grid(
        mus=(SWEEP_MG_MU,), mgs=SWEEP_MGS, num_states=num_states
    )


def _pool_startup(jobs: int) -> float:
    """Wall time to start a forkserver pool of ``jobs`` workers that import mjtvm.apps.sweep."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    t0 = time.perf_counter()
    context = multiprocessing.get_context("forkserver")
    with ProcessPoolExecutor(max_workers=jobs, mp_context=context, initializer=_import_sweep) as pool:
        list(pool.map(_noop_arg, range(jobs)))
    return time.perf_counter() - t0


def _import_sweep() -> None:
    import mjtvm.apps.sweep  # noqa: F401


def _noop_arg(_: int) -> int:
    time.sleep(0.05)  # keep one task from taking every worker's slot
    return 0


def bench_sweeps(*, jobs: Sequence[int] = (1, 2), repeats: int = 3, num_states: int = 30) -> dict[str, Any]:
    r"""Wall time of :func:`~mjtvm.apps.sweep.run_sweep` over :func:`sweep_points` per process count.

    Every run starts without the in-process lift cache, so each builds the lift (the serial
    run once, every worker once); runs with ``jobs > 1`` include the pool's start-up (the
    forkserver on the first run, the workers' imports every run). Also measured: the lift's
    construction alone and the start-up of an empty pool whose workers import mjtvm.apps.sweep.
    """
    from ..apps import sweep

    points = sweep_points(num_states)
    rows_ref: list[Any] | None = None
    per_jobs: dict[str, Any] = {}
    for j in jobs:
        runs = []
        for _ in range(max(repeats, 1)):
            sweep._lift.cache_clear()
            t0 = time.perf_counter()
            rows = sweep.run_sweep(points, jobs=j, progress=False)
            runs.append(time.perf_counter() - t0)
            if rows_ref is None:
                rows_ref = rows
            elif [r["tvmmp"] for r in rows] != [r["tvmmp"] for r in rows_ref]:
                raise RuntimeError(f"run_sweep(jobs={j}) gave different rows")
        per_jobs[str(j)] = {"runs_s": runs, "first_s": runs[0], **_stats(runs)}
    sweep._lift.cache_clear()
    t0 = time.perf_counter()
    sweep._lift("case2", "default", num_states)
    lift_s = time.perf_counter() - t0
    out: dict[str, Any] = {
        "points": len(points),
        "combinations": len({(p.mu, p.mg) for p in points}) + 1,  # (0.3, 2 N) is in both sweeps
        "distinct_combinations": len({(p.mu, p.mg) for p in points}),
        "num_states": num_states,
        "per_jobs": per_jobs,
        "lift_build_s": lift_s,
        "pool_startup_s": {str(j): _pool_startup(j) for j in jobs if j > 1},
        "includes_pool_startup": True,
    }
    if "1" in per_jobs:
        out["speedup"] = {
            k: per_jobs["1"]["median_s"] / v["median_s"] for k, v in per_jobs.items() if k != "1"
        }
    return out


def _scale_one(fingers: int, repeats: int, p1_repeats: int) -> dict[str, Any]:
    from ..core.tvmmp import tvmmp
    from ..polytopes.tvms import tvms

    t0 = time.perf_counter()
    state = scaling_hand(fingers)
    build = time.perf_counter() - t0
    p2 = _times(lambda: tvmmp(state, witnesses=False), repeats, warmup=3)
    big = fingers >= 16  # Problem 1 takes seconds there: fewer runs, no warm-up, no tracemalloc
    last: list[Any] = []
    p1 = _times(
        lambda: last.append(tvms(state)),
        max(1, p1_repeats // 2) if big else p1_repeats,
        warmup=0 if big else 1,
    )
    p2_res = tvmmp(state, witnesses=False)
    from .timing import _split

    split = _split(state, max(1, min(repeats, 50)), 1)
    return {
        "joints": state.num_joints,
        "contacts": len(state.contacts),
        "build_s": build,
        "tvmmp": p2_res.tvmmp,
        "num_lps": p2_res.timings.num_lps,
        "p2": _stats(p2),
        "p2_highs_run_s": split["highs_run_s"],
        "p2_python_s": split["python_overhead_s"],
        "p1": _stats(p1),
        "p1_vertices": len(last[-1].vertices),
        "p1_dimension": last[-1].dimension,
        "memory_mib": {
            "tracemalloc_peak_p2": _traced_peak_mib(lambda: tvmmp(state, witnesses=False)),
            "tracemalloc_peak_p1": None if big else _traced_peak_mib(lambda: tvms(state)),
            "ru_maxrss": _rss_mib(),
        },
    }


def bench_scaling(
    fingers: Sequence[int] = SCALING_FINGERS,
    *,
    repeats: int = 100,
    p1_repeats: int = 5,
) -> dict[str, Any]:
    """Per hand size: build time, Problem 2 per state (4 RVDS vertices), Problem 1 (RVDS cone), memory."""

    per = {str(f): _scale_one(f, repeats, p1_repeats) for f in fingers}
    keys = list(per)
    ratios = {
        f"{b}/{a}": {
            "fingers": int(b) / int(a),
            "p2_time": per[b]["p2"]["median_s"] / per[a]["p2"]["median_s"],
            "p1_time": per[b]["p1"]["median_s"] / per[a]["p1"]["median_s"],
        }
        for a, b in itertools.pairwise(keys)
    }
    if len(keys) > 1:
        a, b = keys[0], keys[-1]
        ratios[f"{b}/{a}"] = {
            "fingers": int(b) / int(a),
            "p2_time": per[b]["p2"]["median_s"] / per[a]["p2"]["median_s"],
            "p1_time": per[b]["p1"]["median_s"] / per[a]["p1"]["median_s"],
        }
    linear = all(r["p2_time"] <= r["fingers"] for r in ratios.values())
    first, lastf = keys[0], keys[-1]
    exponent = (
        math.log(per[lastf]["p2"]["median_s"] / per[first]["p2"]["median_s"])
        / math.log(int(lastf) / int(first))
        if len(keys) > 1
        else None
    )
    return {
        "hand": "synthetic MJCF (hand_mjcf): bases on a 0.12 m circle, headings inwards, 4 joints per finger, "
        "one fingertip F-contact each, mu 0.5, mg 1 N, RVDS [+-1, +-1, 1, 0, 0, 0]",
        "per_fingers": per,
        "ratios": ratios,
        "p2_at_most_linear": linear,
        "p2_loglog_exponent": exponent,
    }


# ------------------------------------------------------------------ the run
def run_suite(
    *,
    quick: bool = False,
    repeats: int = 200,
    baseline_repeats: int = 10,
    p1_repeats: int = 20,
    lift_repeats: int = 3,
    sweep_repeats: int = 3,
    scaling_fingers: Sequence[int] = SCALING_FINGERS,
    time_limit: float = 120.0,
    cases: bool = True,
    lift: bool = True,
    sweeps: bool = True,
    progress: bool | Callable[[str], None] = True,
) -> dict[str, Any]:
    """Every measurement of the module docstring; returns the JSON-ready report (times in s).

    ``progress``: print each step's name (True), call ``progress(name)`` at each step's start
    (a progress bar: ``mjtvm bench``), or stay silent (False).
    """
    from ..sim.scenario import load_scenario
    from .timing import machine_info

    def say(text: str) -> None:
        if callable(progress):
            progress(text)
        elif progress:
            print(f"[bench] {text}", flush=True)

    t_start = time.perf_counter()
    report: dict[str, Any] = {
        "schema": SCHEMA,
        "machine": machine_info(),
        "settings": {
            "quick": quick,
            "repeats": repeats,
            "baseline_repeats": baseline_repeats,
            "p1_repeats": p1_repeats,
            "lift_repeats": lift_repeats,
            "sweep_repeats": sweep_repeats,
            "cdd_time_limit_s": time_limit,
            "solver": "highs",
            "baseline_p2": "mjtvm.core.reference.reference_tvmmp (cvxpy CLARABEL, rebuilt per pair)",
            "baseline_p1": "tvms(method='cdd') (pycddlib vertex enumeration in a child process, capped)",
        },
        "paper_s": PAPER_S,
        "targets_s": TARGETS_S,
        "target_sweep_speedup": TARGET_SWEEP_SPEEDUP,
        "cases": {},
    }
    if cases:
        case1 = load_scenario("case1").state()
        say("case 1, problem 1")
        report["cases"]["case1_p1"] = bench_problem1(
            case1, repeats=p1_repeats, cdd=not quick, time_limit=time_limit
        )
        say("case 1, problem 2 (8 RVDS vertices)")
        report["cases"]["case1_p2"] = bench_problem2(
            case1.with_(rvds=case1_rvds(case1)), repeats=repeats, baseline_repeats=baseline_repeats
        )
        report["cases"]["case1_p2"]["beta"] = case1_beta(case1).tolist()
        case2 = load_scenario("case2").state()
        if not quick:
            say("case 2, problem 1 without RVDS (a warm-up and 3 runs of ~2 s; then cdd capped)")
            report["cases"]["case2_p1"] = bench_problem1(
                case2.with_(rvds=None),
                repeats=3,
                warmup=1,
                cdd=True,
                time_limit=time_limit,
                trace_memory=False,
            )
        say("case 2, problem 2")
        report["cases"]["case2_p2"] = bench_problem2(
            case2, repeats=repeats, baseline_repeats=baseline_repeats
        )
    if lift:
        say("full lift (L and S)")
        report["lift"] = bench_lift(repeats=lift_repeats)
    if sweeps:
        say("Fig. 9 sweeps on 1 and 2 processes")
        report["sweeps"] = bench_sweeps(repeats=sweep_repeats)
    if scaling_fingers:
        say(f"scaling: {', '.join(map(str, scaling_fingers))} fingers")
        report["scaling"] = bench_scaling(scaling_fingers, repeats=max(1, repeats // 2), p1_repeats=5)
    report["targets"] = _targets(report)
    report["total_wall_s"] = time.perf_counter() - t_start
    return report


def _targets(report: dict[str, Any]) -> dict[str, Any]:
    c = report["cases"]
    out: dict[str, Any] = {}
    if "case1_p1" in c:
        out["case1_p1"] = c["case1_p1"]["lp"]["median_s"] <= TARGETS_S["case1_p1"]
    if "case2_p1" in c:
        out["case2_p1"] = c["case2_p1"]["lp"]["median_s"] <= TARGETS_S["case2_p1"]
    for key in ("case1_p2", "case2_p2"):
        if key in c:
            out[key] = c[key]["ours"]["median_s"] <= TARGETS_S["p2_state"]
    if "lift" in report:
        out["lift"] = report["lift"]["median_s"] <= TARGETS_S["lift"]
    if "sweeps" in report and "2" in report["sweeps"].get("speedup", {}):
        out["sweep_speedup_2"] = report["sweeps"]["speedup"]["2"] >= TARGET_SWEEP_SPEEDUP
    if "scaling" in report:
        out["scaling_p2_at_most_linear"] = report["scaling"]["p2_at_most_linear"]
    return out
