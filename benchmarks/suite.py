r"""The project's benchmark run: the paper's cases, the lift, the sweeps, scaling.

One run of [`run_suite()`][benchmarks.suite.run_suite] (``python -m benchmarks`` or ``python -m benchmarks``) measures, with
medians over repeats and [`time.perf_counter()`][time.perf_counter], the garbage collector enabled:

* **Case 1, Problem 1**: ``tvms(load_scenario("case1").state())`` (no RVDS; paper 0.19 s);
* **Case 1, Problem 2** with the 8-vertex RVDS of the digest (section 6): +-e_y, +-e_4
  (omega_x), +-e_6 (omega_z; the paper's e_5 is a typo) and +-beta, where beta is computed
  from the model as the one in-plane (x, z, omega_y) object motion that finger 3's two
  contacts leave ([`case1_beta()`][benchmarks.cases.case1_beta], unscaled unit vector; paper 0.26 s);
* **Case 2's initial state**: Problem 1 without RVDS (paper 129 s; median of 3 runs after a warm-up)
  and Problem 2 with its 4 RVDS vertices (paper 0.20 s);
* the **full lift** with both contact variants ([`time_replay()`][mjtvm.jobs.replay.time_replay]: no plots,
  no sweeps; imports excluded; target <= 1 s);
* the **Fig. 9 sweeps** (9 (mu, mg) combinations x 30 states, L-points) through
  [`run_sweep()`][mjtvm.jobs.sweep.run_sweep] on 1 process and on 2 (``jobs=2``), every run from
  cold caches (the lift, the states' grasps); the 2-process time includes the pool's
  start-up (on Linux the workers are forked after the lift is built);
* the **baselines** in the same run: cvxpy rebuilt per pair
  ([`reference_tvmmp()`][oracles.reference.reference_tvmmp]) for the Problem 2 cases and the cdd vertex
  enumeration (capped at ``time_limit`` s) for Problem 1;
* **scaling**: synthetic hands of 2, 4, 8 and 16 fingers of 4 joints ([`scaling_hand()`][benchmarks.scaling.scaling_hand]:
  MJCF from [`hand_mjcf()`][mjtvm.paper_hand.hand.hand_mjcf], one fingertip F-contact per finger, IK-free),
  time per TVMMP state (4 RVDS vertices) and per Problem 1 (restricted to the RVDS cone),
  with the tracemalloc peak and the process's ``ru_maxrss``;
* **hands mjtvm does not generate** ([`benchmarks.hands`][benchmarks.hands]): each test hand's grasp file
  loaded, its state, Problem 2 and its lift;
* **dataset scale** ([`benchmarks.dataset`][benchmarks.dataset]): batches of 200 synthetic 22-joint,
  five-contact states with a six-direction RVDS, Problem 2 with one REFS vertex (6 LPs) and
  with six (36 LPs) as grasps/s on one process, the 36-LP batch on 2 processes, and
  ``mjtvm solve STATE.json`` and ``import mjtvm`` as processes (``--quick``: one repeat);
* **peers** ([`benchmarks.peers`][benchmarks.peers]): velocity and force polytopes of one fingertip of 3, 4,
  7 and 12 joints and pycapacity's four-link example against pycapacity (when installed),
  pairs interleaved, as ratios (target: at least as fast);
* **Problem 2 against its solver's floor** ([`benchmarks.floor`][benchmarks.floor]): per state, the wall
  time of Problem 2 over its time inside HiGHS ``run()`` in the same calls, on Case 2, Case 1,
  the ``allegro-ik`` grasp and the 22-joint dataset hand (6 and 36 LPs);
* **``mjtvm rank``** ([`benchmarks.rank`][benchmarks.rank]): grasps per CPU-second on the Shadow example
  dataset and on the five-finger Shadow hand (22 joints, 36 LPs) with and without the classic
  measures, Problem 2 over HiGHS ``run()`` summed over its
  batch, 32 against 16 fingers per LP, 2 processes, and peak RSS at 400, 4,000 (``--quick``)
  and 40,000 generated grasps, each with its core share;
* **Problem 1 at scale** ([`bench_p1_scale()`][benchmarks.problem1.bench_p1_scale], not with ``--quick``):
  Case 2 exact, the Allegro grasp's TVMS in 3-D to 6-D (exact or a 1 % bracket within 60 s),
  the 16-finger hand, each in a fresh process with its peak resident memory.

``--quick`` skips Case 2's Problem 1 and every cdd run.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

from benchmarks.cases import case1_beta, case1_rvds, paper_cases
from benchmarks.hands import HANDS, bench_hands
from benchmarks.measure import stats
from benchmarks.scaling import SCALING_FINGERS, bench_scaling, scaling_hand

__all__ = [
    "P2_TARGET_KEYS",
    "PAPER_S",
    "SCHEMA",
    "TARGETS_S",
    "case1_beta",
    "case1_rvds",
    "run_suite",
    "scaling_hand",
]

SCHEMA = "benchmarks/2"
PAPER_S = {"case1_p1": 0.19, "case1_p2": 0.26, "case2_p1": 129.0, "case2_p2": 0.20}
"""The paper's times (s; MATLAB, Core Solo U1300 1.06 GHz)."""
TARGETS_S = {"case1_p1": 0.05, "case2_p1": 1.0, "p2_state": 5e-3, "case2_p2_state": 1.5e-3, "lift": 1.0}
"""mjtvm's targets (s): ``p2_state`` for a Problem 2 state in general, ``case2_p2_state`` for
Case 2's initial state; the sweep target is a speed-up:
[`TARGET_SWEEP_SPEEDUP`][benchmarks.suite.TARGET_SWEEP_SPEEDUP]."""
P2_TARGET_KEYS = {"case1_p2": "p2_state", "case2_p2": "case2_p2_state"}
"""The target (a key of [`TARGETS_S`][benchmarks.suite.TARGETS_S]) of each Problem 2 row of the report."""
TARGET_SWEEP_SPEEDUP = 1.6


# ------------------------------------------------------------------ measurements
def bench_lift(*, repeats: int = 3, num_states: int = 30) -> dict[str, Any]:
    """[`time_replay()`][mjtvm.jobs.replay.time_replay] (L and S, no plots, no sweeps) after one untimed run."""
    from mjtvm.jobs.replay import time_replay

    time_replay(repeats=1, num_states=num_states)  # warm-up: lazy imports, caches
    out = time_replay(repeats=repeats, num_states=num_states)
    out["repeats"] = repeats
    return out


def sweep_points(num_states: int = 30) -> tuple[Any, ...]:
    """The Fig. 9 sweeps as [`SweepPoint`][mjtvm.jobs.sweep.SweepPoint] (9a: mu at mg = 2 N; 9b: mg at mu = 0.3)."""
    from mjtvm.jobs.replay import SWEEP_MG_MU, SWEEP_MGS, SWEEP_MU_MG, SWEEP_MUS
    from mjtvm.jobs.sweep import grid

    return grid(mus=SWEEP_MUS, mgs=(SWEEP_MU_MG,), num_states=num_states) + grid(
        mus=(SWEEP_MG_MU,), mgs=SWEEP_MGS, num_states=num_states
    )


def _pool_startup(jobs: int) -> float:
    """Wall time to start a pool of ``jobs`` workers as [`run_sweep()`][mjtvm.jobs.sweep.run_sweep] does
    (forked on Linux, else from a forkserver) whose workers import mjtvm.jobs.sweep."""
    import multiprocessing
    import warnings
    from concurrent.futures import ProcessPoolExecutor

    from mjtvm.jobs.pool import forks

    t0 = time.perf_counter()
    context = multiprocessing.get_context("fork" if forks() else "forkserver")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "This process .* is multi-threaded", DeprecationWarning)
        with ProcessPoolExecutor(max_workers=jobs, mp_context=context, initializer=_import_sweep) as pool:
            list(pool.map(_noop_arg, range(jobs)))
    return time.perf_counter() - t0


def _import_sweep() -> None:
    import mjtvm.jobs.sweep  # noqa: F401


def _noop_arg(_: int) -> int:
    time.sleep(0.05)  # keep one task from taking every worker's slot
    return 0


def bench_sweeps(*, jobs: Sequence[int] = (1, 2), repeats: int = 3, num_states: int = 30) -> dict[str, Any]:
    r"""Wall time of [`run_sweep()`][mjtvm.jobs.sweep.run_sweep] over [`sweep_points()`][benchmarks.suite.sweep_points] per process count.

    Every run starts without the in-process caches of the lift and of the states' MuJoCo
    grasps, as a ``mjtvm sweep`` command does: each run builds the lift once (in this process;
    on a forkserver pool, every worker once) and reads every state's grasp once; runs with
    ``jobs > 1`` include the pool's start-up (forked workers on Linux; elsewhere the forkserver
    on the first run and the workers' imports every run). Also measured: the lift's
    construction alone and the start-up of an empty pool whose workers import mjtvm.jobs.sweep.
    """
    from mjtvm.jobs import sweep
    from mjtvm.jobs.pool import forks

    points = sweep_points(num_states)
    rows_ref: list[Any] | None = None
    per_jobs: dict[str, Any] = {}
    for j in jobs:
        runs = []
        for _ in range(max(repeats, 1)):
            sweep.point_lift.cache_clear()
            sweep.point_state.cache_clear()  # before, runs after the first kept the grasps of the states
            t0 = time.perf_counter()
            rows = sweep.run_sweep(points, jobs=j, progress=False)
            runs.append(time.perf_counter() - t0)
            if rows_ref is None:
                rows_ref = rows
            elif rows != rows_ref:  # every field, alphas and statuses included, to the bit
                raise RuntimeError(f"run_sweep(jobs={j}) gave different rows")
        per_jobs[str(j)] = {"runs_s": runs, "first_s": runs[0], **stats(runs)}
    sweep.point_lift.cache_clear()
    t0 = time.perf_counter()
    sweep.point_lift("case2", "default", num_states)
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
        "start_method": "fork" if forks() else "forkserver",
    }
    if "1" in per_jobs:
        serial = per_jobs["1"]["median_s"]
        out["speedup"] = {k: serial / v["median_s"] for k, v in per_jobs.items() if k != "1"}
        # Amdahl: the lift is built once before any state can be solved, the rest divides at
        # best evenly; the speed-up no pool can pass with this serial run and this lift.
        out["speedup_ceiling"] = {
            k: serial / (lift_s + max(serial - lift_s, 0.0) / int(k)) for k in per_jobs if k != "1"
        }
    return out


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
    hands: Sequence[str] = HANDS,
    dataset: bool = True,
    peers: bool = True,
    floor: bool = True,
    rank: bool = True,
    rank_sizes: Sequence[int] | None = None,
    scale: bool = True,
    progress: bool | Callable[[str], None] = True,
) -> dict[str, Any]:
    """Every measurement of the module docstring; returns the JSON-ready report (times in s).

    ``progress``: print each step's name (True), call ``progress(name)`` at each step's start
    (a progress bar: ``python -m benchmarks``), or stay silent (False).
    """
    from benchmarks.timing import machine_info

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
            "baseline_p2": "oracles.reference.reference_tvmmp (cvxpy CLARABEL, rebuilt per pair)",
            "baseline_p1": "tvms(method='cdd') (pycddlib vertex enumeration in a child process, capped)",
        },
        "paper_s": PAPER_S,
        "targets_s": TARGETS_S,
        "target_sweep_speedup": TARGET_SWEEP_SPEEDUP,
        "cases": {},
    }
    if cases:
        report["cases"] = paper_cases(
            quick=quick,
            repeats=repeats,
            baseline_repeats=baseline_repeats,
            p1_repeats=p1_repeats,
            time_limit=time_limit,
            say=say,
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
    if peers:
        from benchmarks import peers as bench_peers

        say("peers: velocity and force polytopes against pycapacity")
        report["peers"] = bench_peers.bench_peers(repeats=max(5, repeats // 4), lp_repeats=1 if quick else 3)
    if scale and not quick:
        from benchmarks.problem1 import bench_p1_scale

        report["problem1_scale"] = bench_p1_scale(say=say)
    if hands:
        say(f"hands: {', '.join(hands)}")
        report["hands"] = bench_hands(hands, repeats=max(1, repeats // 10))
    if dataset:
        from benchmarks.dataset import bench_dataset

        say("dataset scale: batches of 200 states, mjtvm solve as a process")
        report["dataset"] = bench_dataset(repeats=1 if quick else 3, cli_repeats=3 if quick else 7)
    if floor:
        from benchmarks.floor import bench_floor

        report["floor"] = bench_floor(repeats=max(10, repeats // 2), say=say)
    if rank:
        from benchmarks.rank import RSS_GRASPS, VERIFY_GRASPS, VERIFY_GRASPS_QUICK, bench_rank

        sizes = rank_sizes if rank_sizes is not None else RSS_GRASPS[:2] if quick else RSS_GRASPS
        report["rank"] = bench_rank(
            repeats=3, sizes=sizes, verify_grasps=VERIFY_GRASPS_QUICK if quick else VERIFY_GRASPS, say=say
        )
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
    for key, target in P2_TARGET_KEYS.items():
        if key in c:
            out[key] = c[key]["ours"]["median_s"] <= TARGETS_S[target]
    if "lift" in report:
        out["lift"] = report["lift"]["median_s"] <= TARGETS_S["lift"]
    if "sweeps" in report and "2" in report["sweeps"].get("speedup", {}):
        out["sweep_speedup_2"] = report["sweeps"]["speedup"]["2"] >= TARGET_SWEEP_SPEEDUP
    if "scaling" in report:
        out["scaling_p2_at_most_linear"] = report["scaling"]["p2_at_most_linear"]
    if "dataset" in report:
        out.update({f"dataset_{k}": v for k, v in report["dataset"]["met"].items()})
    if report.get("peers", {}).get("met") is not None:
        out["peers_pycapacity"] = report["peers"]["met"]
    if "floor" in report:
        out.update({f"floor_{k}": v["met"] for k, v in report["floor"]["states"].items()})
    if "rank" in report:  # None where the row was loaded: neither met nor missed
        rk = report["rank"]
        out["rank_classic"] = rk["throughput"]["classic"]["met"]
        out["rank_none"] = rk["throughput"]["none"]["met"]
        if "throughput_22" in rk:
            out["rank_22_classic"] = rk["throughput_22"]["classic"]["met"]
            out["rank_22_none"] = rk["throughput_22"]["none"]["met"]
        out.update({f"rank_{k}": rk[k]["met"] for k in ("p2_floor", "fingers", "jobs")})
        if "p2_floor_22" in rk:
            out["rank_p2_floor_22"] = rk["p2_floor_22"]["met"]
        if "met" in rk.get("verify", {}):
            out["rank_verify"] = rk["verify"]["met"]
    return out
