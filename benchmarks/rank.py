r"""Speed and memory of ``mjtvm rank`` (issue 34, points 4 and 5), in CPU time beside wall time.

Measured on the shipped Shadow example ([`RANK_GRASP`][benchmarks.rank.RANK_GRASP] on
``mjtvm/data/examples/shadow-sphere-dataset.npz``: 36 grasps, 4 of them broken on purpose):

* **throughput** ([`bench_throughput()`][benchmarks.rank.bench_throughput]): ``rank_row`` (``measures="classic"`` and ``"none"``) over every grasp in
  this process, with the classic measures and without them (TVMMP and its diagnosis alone),
  in grasps per CPU-second (``time.process_time``) beside the wall time;
* **throughput, 22 joints and 36 LPs** ([`bench_throughput_22()`][benchmarks.rank.bench_throughput_22]): the same on the
  hand of issue 34's target, the five-finger Shadow hand ([`RANK_GRASP_22`][benchmarks.rank.RANK_GRASP_22]: 22 joints, five
  fingertip F contacts, 6 REFS x 6 RVDS vertices), over [`GRASPS_22`][benchmarks.rank.GRASPS_22] grasps that
  ``tools/make_rank_dataset.py --grasp`` writes into a temporary folder (seeded, none broken:
  every grasp is a full 36-LP solve; the generation is not timed);
* **Problem 2 over HiGHS** (`bench_p2_floor()`): ``tvmmp(state, witnesses=False,
  compiled=True)`` (``mjtvm rank``'s call) over the batch of the dataset's grasp states against
  the time inside HiGHS ``run()`` of a HiGHS-alone pass over the same states, both summed over
  the batch;
* **16 against 32 fingers** (`bench_fingers()`): Problem 2 per LP on the scaling hands of
  [`benchmarks.scaling`][benchmarks.scaling] with 16 and 32 fingers;
* **two processes** (`bench_jobs()`): ``rank_rows`` of the dataset repeated
  [`JOBS_COPIES`][benchmarks.rank.JOBS_COPIES] times (ids made unique) on 1 and 2 local processes, wall
  speed-up, the workers' CPU time (``RUSAGE_CHILDREN``) counted in the core share;
* **peak memory** (`bench_memory()`): ``mjtvm rank`` as a process on generated datasets of
  [`RSS_GRASPS`][benchmarks.rank.RSS_GRASPS] grasps (the example's grasps repeated, each with its own
  object scale, the case that compiled one model per grasp), its own peak resident set
  (``VmHWM``: ``ru_maxrss`` would carry the parent's over fork and exec);
* **the simulation** (`bench_verify()`): ``mjtvm rank --verify`` as a process on the example's
  first [`VERIFY_GRASPS`][benchmarks.rank.VERIFY_GRASPS] grasps (``--quick``: `VERIFY_GRASPS_QUICK`), in
  grasps per CPU-second of the whole process (``RUSAGE_CHILDREN``: its start and imports
  included) and of its ``main()`` alone;
* **a Dask cluster** (`bench_dask()`): the largest of those datasets again with ``--cluster`` on a
  local cluster of [`DASK_WORKERS`][benchmarks.rank.DASK_WORKERS] worker processes, every file
  compared byte for byte with the one-process run's.

Every row carries its ``core_share`` (CPU time over wall time, per process used); a row
below [`CORE_SHARE_MIN`][benchmarks.rank.CORE_SHARE_MIN] is ``loaded``: its ``met`` is ``None``, never ``True``.
"""

from __future__ import annotations

import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "CORE_SHARE_MIN",
    "GRASPS_22",
    "JOBS_COPIES",
    "RANK_GRASP",
    "RANK_GRASP_22",
    "RSS_GRASPS",
    "TARGETS",
    "VERIFY_GRASPS",
    "VERIFY_GRASPS_QUICK",
    "bench_rank",
    "bench_throughput",
    "bench_throughput_22",
]

RANK_GRASP = "shadow_hand_coupled-sphere"
"""The shipped grasp file of the example dataset."""
ROOT = Path(__file__).resolve().parents[1]
RANK_GRASP_22 = ROOT / "models" / "shadow_hand" / "shadow_hand_5f_coupled-sphere.toml"
"""The five-finger Shadow hand's grasp file of the 22-joint, 36-LP rows (a path in the checkout:
the generator that perturbs it is ``tools/make_rank_dataset.py``, beside it)."""
GRASPS_22 = 36
"""Grasps of the 22-joint rows' generated dataset (seed 24, none broken)."""
TARGETS = {
    "rank_classic": 40.0,
    "rank_none": 100.0,
    "p2_over_highs": 1.5,
    "fingers_32_over_16": 2.5,
    "rank_speedup_2": 1.8,
    "rank_verify": 5.0,
}
"""Grasps per CPU-second with and without the classic measures (at least), Problem 2 over its
HiGHS ``run()`` time (at most), the per-LP time of 32 fingers over 16 (at most), the wall
speed-up of 2 processes (at least), grasps per CPU-second of ``rank --verify`` (at least:
issue 35)."""
CORE_SHARE_MIN = 0.8
"""A row whose processes got less of a core than this is ``loaded`` (never reported as met)."""
JOBS_COPIES = 4
"""How many times the 36-grasp dataset is repeated for the 2-process row."""
VERIFY_GRASPS = 36
"""Grasps of the ``rank --verify`` row: the whole example (29 of them simulated)."""
VERIFY_GRASPS_QUICK = 8
"""Grasps of the ``rank --verify`` row with ``--quick``."""
RSS_GRASPS = (400, 4000, 40000)
"""Dataset sizes of the peak-memory rows."""


def _dataset() -> Path:
    import mjtvm

    return Path(mjtvm.__file__).parent / "data" / "examples" / "shadow-sphere-dataset.npz"


def _verdict(value: float, target: float, share: float, *, at_least: bool) -> dict[str, Any]:
    loaded = share < CORE_SHARE_MIN
    ok = value >= target if at_least else value <= target
    return {"target": target, "core_share": share, "loaded": loaded, "met": None if loaded else ok}


def _cpu_wall(fn: Callable[[], object]) -> tuple[float, float]:
    c, w = time.process_time(), time.perf_counter()
    fn()
    return time.process_time() - c, time.perf_counter() - w


def bench_throughput(
    *, repeats: int = 3, grasp: str | Path = RANK_GRASP, dataset: Path | None = None
) -> dict[str, Any]:
    """Grasps per CPU-second of ``rank_row`` over ``dataset`` (default: the example dataset) of
    ``grasp``, with (``classic``) and without (``none``) the classic measures: medians over
    ``repeats`` passes after a warm one, with the wall time inside HiGHS ``run()`` per grasp
    (``highs_run_ms_per_grasp``) and its inverse, the rate no code around that solver can
    exceed (``highs_ceiling_grasps_per_s``)."""
    from mjtvm.jobs.rank import batch_models, rank_row
    from mjtvm.jobs.rank_inputs import read_datasets
    from mjtvm.lp.highs import observe_runs

    entries = read_datasets(str(grasp), [str(dataset or _dataset())])
    batch = batch_models(str(grasp))
    out: dict[str, Any] = {"grasps": len(entries)}
    for key, target in (("classic", TARGETS["rank_classic"]), ("none", TARGETS["rank_none"])):
        for e in entries:  # warm: models compiled, ranges validated, imports done
            rank_row(batch, e, measures=key)
        runs, inside = [], []
        for _ in range(max(1, repeats)):
            spent: list[float] = []
            with observe_runs(spent.append):
                runs.append(_cpu_wall(lambda: [rank_row(batch, e, measures=key) for e in entries]))  # noqa: B023
            inside.append(sum(spent))
        cpu = statistics.median(r[0] for r in runs)
        wall = statistics.median(r[1] for r in runs)
        gps = len(entries) / cpu
        highs = statistics.median(inside) / len(entries)
        out[key] = {
            "cpu_s": cpu,
            "wall_s": wall,
            "cpu_ms_per_grasp": 1e3 * cpu / len(entries),
            "grasps_per_cpu_s": gps,
            "grasps_per_s": len(entries) / wall,
            # the time inside HiGHS run() alone, and the rate no code around it can pass
            "highs_run_ms_per_grasp": 1e3 * highs,
            "highs_ceiling_grasps_per_s": 1.0 / highs if highs > 0.0 else None,
            **_verdict(gps, target, cpu / wall, at_least=True),
        }
    return out


def _generator() -> Any:
    """``tools/make_rank_dataset.py`` as a module (the tools folder is not a package)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "make_rank_dataset", ROOT / "tools" / "make_rank_dataset.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def bench_throughput_22(*, repeats: int = 3, grasps: int = GRASPS_22) -> dict[str, Any]:
    """`bench_throughput()` on the five-finger Shadow hand (22 joints, 36 LPs a grasp) over
    ``grasps`` grasps generated from [`RANK_GRASP_22`][benchmarks.rank.RANK_GRASP_22] (seed 24, none broken), with
    the hand's size: ``joints``, ``contacts`` and ``lps`` (REFS x RVDS vertices) of its grasp file."""
    from mjtvm.grasp.resolve.file import load_grasp

    state = load_grasp(RANK_GRASP_22).state()
    size = {
        "grasp": RANK_GRASP_22.stem,
        "joints": len(state.joint_names),
        "contacts": len(state.contacts),
        "lps": len(state.refs) * (0 if state.rvds is None else len(state.rvds)),
    }
    with tempfile.TemporaryDirectory() as tmp:
        ds = Path(tmp) / "shadow-5f.npz"
        np.savez(ds, **_generator().make(grasps, 0, 24, grasp_file=RANK_GRASP_22))
        return {**size, **bench_throughput(repeats=repeats, grasp=RANK_GRASP_22, dataset=ds)}


def _states(grasp: str | Path = RANK_GRASP, dataset: Path | None = None) -> list[Any]:
    """The grasp states of ``dataset`` (default: the example dataset) of ``grasp``, the broken
    grasps left out."""
    from mjtvm.errors import MjtvmError
    from mjtvm.jobs.rank import batch_models
    from mjtvm.jobs.rank_inputs import read_datasets

    batch = batch_models(str(grasp))
    states = []
    for e in read_datasets(str(grasp), [str(dataset or _dataset())]):
        try:
            states.append(batch.grasp(e).state())
        except MjtvmError:
            continue  # the broken grasps
    return states


def _states_22(grasps: int) -> list[Any]:
    """The states of ``grasps`` generated grasps of the five-finger Shadow hand (as
    `bench_throughput_22()`'s: seed 24, none broken; 36 LPs each)."""
    with tempfile.TemporaryDirectory() as tmp:
        ds = Path(tmp) / "shadow-5f.npz"
        np.savez(ds, **_generator().make(grasps, 0, 24, grasp_file=RANK_GRASP_22))
        return _states(RANK_GRASP_22, ds)


def bench_p2_floor(*, repeats: int = 5, states: Sequence[Any] | None = None) -> dict[str, Any]:
    """Problem 2 over the batch of the example's states on the batch path ``mjtvm rank`` runs
    (``tvmmp(state, witnesses=False, compiled=True)``: the compiled re-solves of
    [`warm`][mjtvm.lp.warm]) against the floor, the time inside HiGHS ``run()`` of a
    HiGHS-alone pass over the same states right before it (``compiled=False``: every LP by
    HiGHS), both summed over the batch (medians over ``repeats`` passes). ``highs_path`` is
    the HiGHS-alone pass itself (``mjtvm solve``'s path) over its own ``run()`` time.
    ``states``: another batch (`bench_rank()`'s ``p2_floor_22``: the 22-joint hand's grasps)."""
    from mjtvm.lp.highs import observe_runs
    from mjtvm.problem2.tvmmp import tvmmp

    states = list(_states() if states is None else states)
    for s in states:  # warm: imports, the kernels' cache load
        tvmmp(s, witnesses=False)
        tvmmp(s, witnesses=False, compiled=True)
    passes: list[dict[str, float]] = []
    for _ in range(max(1, repeats)):
        alone: list[float] = []
        with observe_runs(alone.append):
            cpu_h, wall_h = _cpu_wall(lambda: [tvmmp(s, witnesses=False) for s in states])
        inside: list[float] = []
        with observe_runs(inside.append):
            cpu, wall = _cpu_wall(lambda: [tvmmp(s, witnesses=False, compiled=True) for s in states])
        passes.append(
            {
                "cpu": cpu,
                "wall": wall,
                "run": sum(alone),
                "runs": len(alone),
                "cpu_h": cpu_h,
                "wall_h": wall_h,
                "run_c": sum(inside),
                "runs_c": len(inside),
            }
        )

    def med(key: str) -> float:
        return statistics.median(p[key] for p in passes)

    ratio = statistics.median(p["wall"] / p["run"] for p in passes)
    lps = sum(tvmmp(s, witnesses=False).timings.num_lps for s in states)
    return {
        "states": len(states),
        "lps": lps,
        "wall_s": med("wall"),
        "cpu_s": med("cpu"),
        "highs_run_s": med("run"),
        "highs_runs": int(med("runs")),
        "highs_run_compiled_s": med("run_c"),
        "highs_runs_compiled": int(med("runs_c")),
        "ratio": ratio,
        "highs_path": {
            "wall_s": med("wall_h"),
            "cpu_s": med("cpu_h"),
            "ratio": statistics.median(p["wall_h"] / p["run"] for p in passes),
        },
        **_verdict(ratio, TARGETS["p2_over_highs"], med("cpu") / med("wall"), at_least=False),
    }


def bench_fingers(*, repeats: int = 5, fingers: Sequence[int] = (16, 32)) -> dict[str, Any]:
    """Problem 2 per LP on the scaling hands of 16 and 32 fingers (median over ``repeats``)."""
    from benchmarks.scaling import scaling_hand
    from mjtvm.problem2.tvmmp import tvmmp

    out: dict[str, Any] = {}
    for n in fingers:
        state = scaling_hand(n)
        tvmmp(state, witnesses=False)
        runs = [_cpu_wall(lambda s=state: tvmmp(s, witnesses=False)) for _ in range(max(1, repeats))]
        lps = tvmmp(state, witnesses=False).timings.num_lps
        cpu, wall = statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs)
        out[str(n)] = {
            "lps": lps,
            "cpu_s": cpu,
            "wall_s": wall,
            "cpu_s_per_lp": cpu / lps,
            "core_share": cpu / wall,
        }
    a, b = out[str(fingers[0])], out[str(fingers[1])]
    ratio = b["cpu_s_per_lp"] / a["cpu_s_per_lp"]
    share = min(a["core_share"], b["core_share"])
    return {
        "per_fingers": out,
        "ratio": ratio,
        **_verdict(ratio, TARGETS["fingers_32_over_16"], share, at_least=False),
    }


def bench_jobs(*, jobs: int = 2, copies: int = JOBS_COPIES) -> dict[str, Any]:
    """``rank_rows`` of the example repeated ``copies`` times on 1 and ``jobs`` processes: wall
    times, speed-up, rows identical; the core share counts the workers' CPU time."""
    from mjtvm.jobs.rank import rank_rows
    from mjtvm.jobs.rank_inputs import read_datasets

    base = read_datasets(RANK_GRASP, [str(_dataset())])
    entries = [replace(e, id=f"{e.id}#{k}") for k in range(copies) for e in base]
    out: dict[str, Any] = {"grasps": len(entries)}
    rows: dict[int, list[dict[str, Any]]] = {}
    for n in (1, jobs):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        c, w = time.process_time(), time.perf_counter()
        rows[n] = rank_rows(RANK_GRASP, entries, jobs=n, progress=False)
        wall = time.perf_counter() - w
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        child = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
        cpu = time.process_time() - c + child
        out[str(n)] = {"wall_s": wall, "cpu_s": cpu, "core_share": cpu / (wall * n)}
    speedup = out["1"]["wall_s"] / out[str(jobs)]["wall_s"]
    same = json.dumps(rows[1], default=str) == json.dumps(rows[jobs], default=str)
    share = min(out["1"]["core_share"], out[str(jobs)]["core_share"])
    return {"jobs": jobs, "speedup": speedup, "rows_identical": same, **out,
            **_verdict(speedup, TARGETS["rank_speedup_2"], share, at_least=True)}  # fmt: skip


# The child's own peak: VmHWM of /proc/self/status (kB), the high-water mark of the address
# space exec gave it. Not ru_maxrss, which Linux keeps across fork and exec: a child of a large
# process would report its parent's size (the suite's 428 MiB for a 202 MiB child).
_RSS_CHILD = """
import resource, sys, time
from mjtvm.cli.parser import main
c, w = time.process_time(), time.perf_counter()
rc = main(["rank", sys.argv[1], sys.argv[2], "--out", sys.argv[3], "--no-plots", "--quiet", *sys.argv[4:]])
cpu, wall = time.process_time() - c, time.perf_counter() - w
try:
    hwm = next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM:"))
except (OSError, StopIteration):
    hwm = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(rc, hwm, cpu, wall)
"""
DASK_WORKERS = 2
"""Worker processes (one thread each) of the local Dask cluster of the largest memory size."""
_COMPARED = ("rank.json", "rank.csv", "rank.parquet", "rank-objects.csv")


def _rank_child(ds: Path, out: Path, *extra: str) -> tuple[int, list[str], str]:
    done = subprocess.run(
        [sys.executable, "-c", _RSS_CHILD, RANK_GRASP, str(ds), str(out), *extra],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    fields = done.stdout.split()[-4:] if done.stdout.split() else []
    return done.returncode, fields, (done.stderr.strip().splitlines() or ["?"])[-1][:200]


def bench_dask(ds: Path, one: Path, out: Path, *, workers: int = DASK_WORKERS) -> dict[str, Any]:
    """``mjtvm rank --cluster`` on a local Dask cluster of ``workers`` processes over the
    dataset ``ds`` whose one-process files are in ``one``: whether every file is identical
    (bytes), the wall time, the core share (the client's and the workers' CPU time over
    ``workers`` cores)."""
    import distributed
    import psutil

    with distributed.LocalCluster(
        n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        procs = [psutil.Process(w.process.pid) for w in cluster.workers.values()]
        before = sum(sum(p.cpu_times()[:2]) for p in procs)
        w = time.perf_counter()
        rc, fields, err = _rank_child(ds, out, "--cluster", cluster.scheduler_address)
        wall = time.perf_counter() - w
        workers_cpu = sum(sum(p.cpu_times()[:2]) for p in procs) - before
    if rc != 0 or len(fields) != 4:
        return {"error": err}
    identical = all((one / f).read_bytes() == (out / f).read_bytes() for f in _COMPARED)
    cpu = workers_cpu + float(fields[2])
    return {
        "grasps": int(np.load(ds)["id"].shape[0]), "workers": workers, "wall_s": wall, "cpu_s": cpu,
        "core_share": cpu / (wall * workers), "files_identical": identical, "files": list(_COMPARED),
    }  # fmt: skip


def write_dataset(path: Path, grasps: int) -> Path:
    """The example's grasps repeated to ``grasps`` rows, ids unique, each with its own object
    scale (1 + 1e-6 x its index times the example's: distinct models, the same grasps)."""
    with np.load(_dataset()) as z:
        arrays = {k: z[k] for k in z.files}
    n = len(arrays["id"])
    take = np.arange(grasps) % n
    out = {k: v[take] for k, v in arrays.items()}
    out["id"] = np.array([f"{arrays['id'][i]}#{k}" for k, i in enumerate(take)])
    out["obj_scale"] = arrays["obj_scale"][take] * (1.0 + 1e-6 * np.arange(grasps))
    np.savez(path, **out)
    return path


def bench_memory(
    *, sizes: Sequence[int] = RSS_GRASPS, dask: bool = True, say: Callable[[str], None] = lambda _: None
) -> dict[str, Any]:
    """Peak RSS (MiB) of ``mjtvm rank`` as a process per dataset size, its CPU and wall time,
    the growth per 1,000 grasps between the smallest and the largest size, and (``dask``)
    the largest dataset again on a local Dask cluster, its files compared with these
    (`bench_dask()`)."""
    out: dict[str, Any] = {"sizes": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            say(f"rank memory: {n} grasps")
            ds = write_dataset(Path(tmp) / f"gen{n}.npz", n)
            rc, fields, err = _rank_child(ds, Path(tmp) / f"out{n}")
            if rc != 0 or len(fields) != 4:
                out["sizes"][str(n)] = {"error": err}
                continue
            rc, rss_kib, cpu, wall = int(fields[0]), float(fields[1]), float(fields[2]), float(fields[3])
            out["sizes"][str(n)] = {
                "exit": rc, "peak_rss_mib": rss_kib / 1024.0, "cpu_s": cpu, "wall_s": wall,
                "core_share": cpu / wall, "loaded": cpu / wall < CORE_SHARE_MIN,
            }  # fmt: skip
        if dask and sizes and "peak_rss_mib" in out["sizes"][str(max(sizes))]:
            n = max(sizes)
            say(f"rank on a local Dask cluster: {n} grasps")
            out["dask"] = bench_dask(Path(tmp) / f"gen{n}.npz", Path(tmp) / f"out{n}", Path(tmp) / f"dask{n}")
    ok = [int(k) for k, v in out["sizes"].items() if "peak_rss_mib" in v]
    if len(ok) >= 2:
        lo, hi = out["sizes"][str(min(ok))], out["sizes"][str(max(ok))]
        out["mib_per_1000_grasps"] = 1e3 * (hi["peak_rss_mib"] - lo["peak_rss_mib"]) / (max(ok) - min(ok))
    return out


def bench_verify(*, grasps: int = VERIFY_GRASPS) -> dict[str, Any]:
    """``mjtvm rank --verify`` as a process on the example's first ``grasps`` grasps (module
    docstring): ``grasps``, ``simulated`` (rows with a hold verdict), ``cpu_s`` (the child
    process's whole CPU time, ``RUSAGE_CHILDREN``), ``main_cpu_s`` (its ``main()`` alone),
    ``wall_s``, ``grasps_per_cpu_s`` (over ``cpu_s``), the target, core share and verdict, or
    ``error``."""
    with tempfile.TemporaryDirectory() as tmp:
        ds = write_dataset(Path(tmp) / "verify.npz", grasps)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        w = time.perf_counter()
        rc, fields, err = _rank_child(ds, Path(tmp) / "out", "--verify")
        wall = time.perf_counter() - w
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if rc != 0 or len(fields) != 4 or int(fields[0]) != 0:
            return {"error": err}
        rows = json.loads((Path(tmp) / "out" / "rank.json").read_text())
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    gps = grasps / cpu
    return {
        "grasps": grasps,
        "simulated": sum(r.get("sim_hold") is not None for r in rows),
        "cpu_s": cpu,
        "main_cpu_s": float(fields[2]),
        "wall_s": wall,
        "grasps_per_cpu_s": gps,
        **_verdict(gps, TARGETS["rank_verify"], cpu / wall, at_least=True),
    }


def bench_rank(
    *,
    repeats: int = 3,
    sizes: Sequence[int] = RSS_GRASPS,
    grasps_22: int = GRASPS_22,
    verify_grasps: int = VERIFY_GRASPS,
    say: Callable[[str], None] = lambda _: None,
) -> dict[str, Any]:
    """Every row of this module (module docstring), as ``report["rank"]``; ``grasps_22`` grasps
    in the 22-joint rows, ``verify_grasps`` in the ``rank --verify`` row."""
    say("rank: throughput with and without the classic measures")
    out: dict[str, Any] = {
        "grasp": RANK_GRASP,
        "dataset": _dataset().name,
        "throughput": bench_throughput(repeats=repeats),
    }
    say("rank: throughput on the 22-joint, 36-LP Shadow hand")
    out["throughput_22"] = bench_throughput_22(repeats=repeats, grasps=grasps_22)
    say("rank: Problem 2 over HiGHS run() on the batch")
    out["p2_floor"] = bench_p2_floor(repeats=max(3, repeats))
    say("rank: Problem 2 over HiGHS on the 22-joint hand's batch")
    out["p2_floor_22"] = bench_p2_floor(repeats=max(3, repeats), states=_states_22(grasps_22))
    say("rank: 16 against 32 fingers per LP")
    out["fingers"] = bench_fingers(repeats=max(3, repeats))
    say("rank: 2 processes")
    out["jobs"] = bench_jobs()
    say(f"rank --verify: {verify_grasps} grasps")
    out["verify"] = bench_verify(grasps=verify_grasps)
    out["memory"] = bench_memory(sizes=sizes, say=say)
    return out


MEMORY_FILE = "rank-memory.json"
"""The file of a memory run of its own (`main()`), beside ``bench.json``: the page's memory
rows come from it when it is there (the 40,000-grasp size takes ~30 min, too long for the suite)."""


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m benchmarks.rank --memory 400,4000,40000 --out DIR``: `bench_memory()` alone,
    written to ``DIR/rank-memory.json`` with the machine and the date."""
    import argparse
    import datetime

    from benchmarks.timing import machine_info
    from mjtvm.formats.files import atomic_write

    p = argparse.ArgumentParser(prog="python -m benchmarks.rank")
    p.add_argument("--memory", required=True, metavar="N,N,...", help="dataset sizes (grasps)")
    p.add_argument("--out", required=True, metavar="DIR")
    args = p.parse_args(argv)
    sizes = tuple(int(v) for v in args.memory.split(","))
    started = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    memory = bench_memory(sizes=sizes, say=lambda s: print(s, flush=True))
    doc = {
        "command": "python -m benchmarks.rank --memory " + args.memory,
        "started": started,
        "machine": machine_info(),
        "memory": memory,
    }
    path = atomic_write(Path(args.out) / MEMORY_FILE, json.dumps(doc, indent=1) + "\n")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
