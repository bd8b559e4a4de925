r"""Speed at dataset scale: batches of Problem 2 on a 22-joint hand, and ``mjtvm solve`` as a process.

A dataset of grasps (``mjtvm rank``) solves Problem 2 once per grasp, so what counts is the
throughput of [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp] over many states and the fixed cost of a
command. Measured here:

* **batch Problem 2** ([`bench_batch()`][benchmarks.dataset.bench_batch]): [`BATCH_STATES`][benchmarks.dataset.BATCH_STATES] seeded synthetic states
  ([`dataset_state()`][benchmarks.dataset.dataset_state], [`random_state()`][benchmarks.synthetic.random_state]) of a Shadow-sized hand:
  five fingers of 4, 4, 4, 5 and 5 joints (22, as the Shadow hand's fingers and thumb), one
  fingertip F-contact per finger, friction 0.5, the RVDS of the six translations
  $\pm e_x, \pm e_y, \pm e_z$ ([`SIX_RVDS`][benchmarks.dataset.SIX_RVDS]). REFS: one vertex (a wrench that random
  admissible contact forces balance, standing for the object's weight: 6 LPs per grasp) or six
  such test wrenches (36 LPs). ``tvmmp(state, witnesses=False)`` over the whole batch in a loop,
  states built beforehand; grasps/s = states / the median batch time;
* the same batches **on 2 processes** (`_pool_batch()`): a forked (Linux; else forkserver)
  pool of 2 workers, each solving half of the batch (the states are pickled to the workers),
  the pool's start-up included; the speed-up is the serial median over this median, and
  every alpha must equal the serial run's to the bit. Each solving process's CPU time is
  recorded too: its share of a core (CPU time over the run's wall time) tells a pool that
  does not scale from a machine that other jobs load;
* **``mjtvm solve STATE.json`` as a process** ([`bench_cli()`][benchmarks.dataset.bench_cli]): the wall time of
  ``python -m mjtvm.cli solve STATE.json`` (one 6-LP state of the batch written with
  [`dump_state()`][mjtvm.formats.state_file.dump_state]), and of ``python -c "import mjtvm"`` alone, medians
  over runs after one untimed run (the file cache warm); beside them the floor a process that
  solves pays before any of mjtvm's code runs (``python -c "pass"``, and ``import numpy,
  highspy, jsonschema``, the modules ``solve`` needs). The paper's 0.2 s per state (MATLAB, one
  Problem 2 state) stands beside them.

The targets ([`TARGETS`][benchmarks.dataset.TARGETS]) are the dataset-scale goals; a miss is reported, never hidden.
"""

from __future__ import annotations

import multiprocessing
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.measure import stats
from benchmarks.synthetic import random_state
from mjtvm.lp.highs import observe_runs
from mjtvm.model.state import GraspState
from mjtvm.problem2.tvmmp import tvmmp

__all__ = [
    "BATCH_STATES",
    "DATASET_FINGER_JOINTS",
    "SIX_RVDS",
    "TARGETS",
    "bench_batch",
    "bench_cli",
    "bench_dataset",
    "dataset_state",
]

DATASET_FINGER_JOINTS = (4, 4, 4, 5, 5)
"""Joints per finger of the dataset-sized hand (22 in all; the Shadow hand's fingers and thumb)."""
SIX_RVDS = np.vstack([np.eye(6)[:3], -np.eye(6)[:3]])
"""``(6, 6)`` the RVDS of the six translations +-e_x, +-e_y, +-e_z (unit, m/s)."""
BATCH_STATES = 200
"""States per batch."""
TARGETS = {
    "batch_weight": 100.0,
    "batch_six_wrenches": 40.0,
    "batch_speedup_2": 1.8,
    "solve_process": 0.3,
}
"""The dataset-scale targets: grasps/s on one core with the weight (6 LPs) and with six test
wrenches (36 LPs) as REFS (at least), the speed-up of the 36-LP batch on 2 processes (at
least), and the wall time of ``mjtvm solve STATE.json`` as a process (s, at most)."""
PAPER_SOLVE_S = 0.20
"""The paper's Problem 2 time per state (s; Case 2's initial state, MATLAB, 1.06 GHz Core Solo)."""


NDArrayList = list[list[float]]
"""A state's alphas as nested lists (picklable, compared exactly)."""


def dataset_state(seed: int, *, num_refs: int = 1) -> GraspState:
    """A seeded synthetic state of the dataset-sized hand (module docstring); feasible by construction."""
    return random_state(
        seed,
        fingers=len(DATASET_FINGER_JOINTS),
        joints_per_finger=DATASET_FINGER_JOINTS,
        contact_types=("F",) * len(DATASET_FINGER_JOINTS),
        num_refs=num_refs,
        mu=0.5,
        rvds=SIX_RVDS,
    )


def _solve_all(states: Sequence[GraspState]) -> list[NDArrayList]:
    """The alphas of every state (``witnesses=False``), as nested lists (picklable, exact)."""
    return [tvmmp(s, witnesses=False).alpha.tolist() for s in states]


def _solve_chunk(states: Sequence[GraspState]) -> tuple[list[NDArrayList], float]:
    """A worker's part: the alphas of its states and the CPU time it took (s)."""
    c0 = time.process_time()
    alphas = _solve_all(states)
    return alphas, time.process_time() - c0


def _pool_batch(states: Sequence[GraspState], jobs: int) -> tuple[float, list[float], list[NDArrayList]]:
    """Wall time of the batch on a new pool of ``jobs`` workers (start-up included), each
    worker's CPU time, and the alphas."""
    from mjtvm.jobs.pool import forks

    chunks = [list(states[i::jobs]) for i in range(jobs)]
    t0 = time.perf_counter()
    context = multiprocessing.get_context("fork" if forks() else "forkserver")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "This process .* is multi-threaded", DeprecationWarning)
        with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
            parts = list(pool.map(_solve_chunk, chunks))
    wall = time.perf_counter() - t0
    alphas: list[NDArrayList] = [[] for _ in states]
    for i, (part, _) in enumerate(parts):
        alphas[i::jobs] = part
    return wall, [cpu for _, cpu in parts], alphas


def bench_batch(
    *, num_states: int = BATCH_STATES, num_refs: int = 1, repeats: int = 3, jobs: Sequence[int] = (1,)
) -> dict[str, Any]:
    """One batch of [`dataset_state()`][benchmarks.dataset.dataset_state] states: its timing per process count, grasps/s, speed-up.

    Returns ``{"states", "joints", "contacts", "refs", "rvds", "lps_per_grasp", "feasible",
    "build_s", "instrumented_s", "highs_run_s", "per_jobs": {"1": stats + "grasps_per_s", ...},
    "speedup": {...}}``: the first (untimed) run is instrumented, its wall time and the part of
    it inside HiGHS ``run``; every later run must give its alphas (else RuntimeError).
    """
    t0 = time.perf_counter()
    states = [dataset_state(seed, num_refs=num_refs) for seed in range(num_states)]
    build = time.perf_counter() - t0
    first = tvmmp(states[0], witnesses=False)
    spent: list[float] = []
    t0 = time.perf_counter()
    with observe_runs(spent.append):  # the warm-up run, and the alphas every other run must give
        reference = _solve_all(states)
    instrumented = time.perf_counter() - t0
    per_jobs: dict[str, Any] = {}
    for j in jobs:
        runs, cpu = [], []  # cpu: per run, the CPU time of each process that solved
        for _ in range(max(repeats, 1)):
            if j == 1:
                t0, c0 = time.perf_counter(), time.process_time()
                alphas = _solve_all(states)
                runs.append(time.perf_counter() - t0)
                cpu.append([time.process_time() - c0])
            else:
                wall, worker_cpu, alphas = _pool_batch(states, j)
                runs.append(wall)
                cpu.append(worker_cpu)
            same = len(alphas) == len(reference) and all(
                np.array_equal(np.asarray(a, dtype=float), np.asarray(b, dtype=float), equal_nan=True)
                for a, b in zip(alphas, reference, strict=True)
            )
            if not same:  # nan (an infeasible pair) equals nan here
                raise RuntimeError(f"the batch on {j} process(es) gave different alphas")
        st = stats(runs)
        # The share of a core each solving process had over the run: below 1 on a machine
        # that other jobs load, whatever mjtvm does.
        share = [sum(c) / (len(c) * w) for c, w in zip(cpu, runs, strict=True)]
        per_jobs[str(j)] = {
            "runs_s": runs,
            **st,
            "grasps_per_s": num_states / st["median_s"],
            "cpu_s": [sum(c) for c in cpu],
            "core_share": share,
        }
    out: dict[str, Any] = {
        "states": num_states,
        "joints": states[0].num_joints,
        "contacts": len(states[0].contacts),
        "refs": num_refs,
        "rvds": len(SIX_RVDS),
        "lps_per_grasp": first.timings.num_lps,
        "feasible": sum(bool(np.all(np.isfinite(np.array(a))) and np.min(a) > 0) for a in reference),
        "build_s": build,
        "instrumented_s": instrumented,
        "highs_run_s": sum(spent),
        "per_jobs": per_jobs,
    }
    if "1" in per_jobs:
        serial = per_jobs["1"]["median_s"]
        out["speedup"] = {k: serial / v["median_s"] for k, v in per_jobs.items() if k != "1"}
    return out


def _process_times(argv: Sequence[str], repeats: int) -> list[float]:
    """Wall times of ``argv`` run as a child process (stdout discarded) after one untimed run."""
    out = []
    for i in range(repeats + 1):
        t0 = time.perf_counter()
        subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        if i:
            out.append(time.perf_counter() - t0)
    return out


def bench_cli(*, repeats: int = 7) -> dict[str, Any]:
    """``mjtvm solve STATE.json`` (a 6-LP [`dataset_state()`][benchmarks.dataset.dataset_state]) and ``import mjtvm`` as processes."""
    from mjtvm.formats.state_file import dump_state

    with tempfile.TemporaryDirectory(prefix="mjtvm-bench-") as tmp:
        path = Path(tmp) / "state.json"
        path.write_text(dump_state(dataset_state(0)), encoding="utf-8")
        solve = _process_times([sys.executable, "-m", "mjtvm.cli", "solve", str(path)], repeats)
    imp = _process_times([sys.executable, "-c", "import mjtvm"], repeats)
    deps = _process_times([sys.executable, "-c", "import numpy, highspy, jsonschema"], repeats)
    bare = _process_times([sys.executable, "-c", "pass"], repeats)
    return {
        "state": "dataset_state(0): 22 joints, 5 contacts, 1 REFS x 6 RVDS",
        "solve": {"runs_s": solve, **stats(solve)},
        "import_mjtvm": {"runs_s": imp, **stats(imp)},
        "import_dependencies": {"runs_s": deps, **stats(deps)},
        "python_startup": {"runs_s": bare, **stats(bare)},
        "paper_s": PAPER_SOLVE_S,
    }


def bench_dataset(
    *, num_states: int = BATCH_STATES, repeats: int = 3, cli_repeats: int = 7, jobs: int = 2
) -> dict[str, Any]:
    """The batches (6 and 36 LPs per grasp; the 36-LP one also on ``jobs`` processes), the
    command's process, and the targets met (``targets``: name -> bool)."""
    weight = bench_batch(num_states=num_states, num_refs=1, repeats=repeats)
    six = bench_batch(num_states=num_states, num_refs=6, repeats=repeats, jobs=(1, jobs))
    cli = bench_cli(repeats=cli_repeats)
    speedup = six["speedup"][str(jobs)]
    return {
        "hand": "synthetic (random_state): fingers of 4, 4, 4, 5, 5 joints, one fingertip F-contact each, "
        "mu 0.5, RVDS +-e_x, +-e_y, +-e_z; REFS: balanced random wrenches",
        "batch_weight": weight,
        "batch_six_wrenches": six,
        "cli": cli,
        "jobs": jobs,
        "targets": dict(TARGETS),
        "met": {
            "batch_weight": weight["per_jobs"]["1"]["grasps_per_s"] >= TARGETS["batch_weight"],
            "batch_six_wrenches": six["per_jobs"]["1"]["grasps_per_s"] >= TARGETS["batch_six_wrenches"],
            "batch_speedup_2": speedup >= TARGETS["batch_speedup_2"],
            "solve_process": cli["solve"]["median_s"] <= TARGETS["solve_process"],
        },
    }
