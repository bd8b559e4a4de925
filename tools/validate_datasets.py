r"""Does TVMMP predict what a hand can do? The dataset benchmark of docs/physics-check.md.

For each run: a seeded dataset made by ``tools/make_rank_dataset.py`` and
``mjtvm rank GRASP DATASET --verify`` on it, both as subprocesses, exactly the commands the
report names (so the page's figures are the command's). From the run's ``NAME.json`` (the rows)
and ``NAME-auc.json`` (each measure's ROC AUC against the simulated hold and speed success) it
keeps the counts and the AUC rows, with the CPU time of the rank command (its processes' own,
``RUSAGE_CHILDREN``), the wall time and the core share. Nothing is tuned here: the settings are
the commands' defaults.

Usage: ``python tools/validate_datasets.py [--runs shadow-sphere,shadow-mesh,...] [--grasps 240]
[--jobs 1] [--out results/validate-datasets]``. Writes ``OUT/<run>.npz`` (the dataset), the rank
command's outputs ``OUT/<run>.*`` and ``OUT/validate-datasets.json`` (the report
``tools/datasets_page.py`` renders into docs/physics-check.md).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import resource
import shlex
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling module below, however run
from datasets_page import SCHEMA

ROOT = Path(__file__).resolve().parent.parent
# label -> (grasp file, tools/make_rank_dataset.py's options besides -n and --out): seeded, so
# the same command writes the same dataset.
RUNS: dict[str, tuple[str, tuple[str, ...]]] = {
    "shadow-sphere": (
        "models/shadow_hand/shadow_hand_coupled-sphere.toml",
        ("--broken", "0", "--seed", "35"),
    ),
    "shadow-mesh": (
        "models/shadow_hand/shadow_hand_coupled-sphere.toml",
        ("--broken", "0", "--seed", "36", "--mesh", "6"),
    ),
    "allegro-sphere": ("models/allegro/allegro-sphere.toml", ("--broken", "0", "--seed", "35")),
    "leap-sphere": ("models/leap_hand/leap_hand-sphere.toml", ("--broken", "0", "--seed", "35")),
}
DEFAULT_RUNS = tuple(RUNS)


def _run(argv: list[str]) -> tuple[float, float]:
    """Run ``argv`` (output to this process's stderr); its CPU seconds (children) and wall seconds.

    Raises
    ------
    SystemExit
        If the command fails (its exit code).
    """
    cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall0 = time.perf_counter()
    done = subprocess.run(argv, cwd=ROOT, stdout=sys.stderr, check=False)
    wall = time.perf_counter() - wall0
    cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{shlex.join(argv)} exited with {done.returncode}")
    return (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime), wall


def run_summary(rows: Sequence[dict[str, Any]]) -> dict[str, int]:
    """The counts of a ``mjtvm rank --verify`` run's rows: grasps, evaluated (no failure),
    simulated (a hold or speed verdict), held, speed success."""
    simulated = [r for r in rows if r.get("sim_hold") is not None or r.get("sim_speed_success") is not None]
    return {
        "grasps": len(rows),
        "evaluated": sum(1 for r in rows if r.get("failure") is None),
        "simulated": len(simulated),
        "held": sum(1 for r in simulated if r.get("sim_hold") is True),
        "speed_success": sum(1 for r in simulated if r.get("sim_speed_success") is True),
    }


def validate(label: str, grasps: int, jobs: int, out: Path) -> dict[str, Any]:
    """Make run ``label``'s dataset and rank it with ``--verify``; the report's entry of the run."""
    grasp, options = RUNS[label]
    data = out / f"{label}.npz"
    make = [sys.executable, "tools/make_rank_dataset.py", "-n", str(grasps), *options, "--grasp", grasp]
    rank = ["mjtvm", "rank", grasp, str(data), "--verify", "--jobs", str(jobs), "--out", str(out)]
    rank += ["--name", label, "--quiet"]
    _run([*make, "--out", str(data)])
    cpu, wall = _run([sys.executable, "-m", "mjtvm.cli", *rank[1:]])
    rows = json.loads((out / f"{label}.json").read_text(encoding="utf-8"))
    auc = json.loads((out / f"{label}-auc.json").read_text(encoding="utf-8"))
    shown = {str(out): "DIR", str(data): f"DIR/{label}.npz"}
    return {
        "label": label,
        "grasp": grasp,
        "make": shlex.join(["python", *make[1:], "--out", f"DIR/{label}.npz"]),
        "rank": shlex.join(shown.get(a, a) for a in rank),
        **run_summary(rows),
        "auc": auc["rows"],
        "cpu_s": cpu,
        "wall_s": wall,
        "jobs": jobs,
        "core_share": cpu / (jobs * wall) if wall > 0 else math.nan,
    }


def _machine() -> dict[str, Any]:
    """The CPU model and core counts of ``mjtvm bench``'s report (rates differ by machine)."""
    sys.path.insert(0, str(ROOT))
    from benchmarks.timing import machine_info

    m = machine_info()
    return {k: m[k] for k in ("cpu", "logical_cpus", "usable_cpus")}


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", default=",".join(DEFAULT_RUNS), help=f"comma list of {', '.join(RUNS)}")
    ap.add_argument("--grasps", type=int, default=240, help="grasps per dataset (default: 240)")
    ap.add_argument("--jobs", type=int, default=1, help="rank --jobs (default: 1)")
    ap.add_argument("--out", type=Path, default=Path("results/validate-datasets"), help="output folder")
    args = ap.parse_args(argv)
    labels = [s for s in args.runs.split(",") if s]
    unknown = [s for s in labels if s not in RUNS]
    if unknown:
        ap.error(f"--runs: unknown {', '.join(unknown)} (expected some of {', '.join(RUNS)})")
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    runs = [validate(label, args.grasps, args.jobs, out) for label in labels]
    report = {
        "schema": SCHEMA,
        "command": shlex.join(["python", "tools/validate_datasets.py", *(argv or sys.argv[1:])]),
        "date": datetime.date.today().isoformat(),
        "machine": _machine(),
        "runs": runs,
    }
    path = out / "validate-datasets.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    tmp.replace(path)
    sys.stdout.write(f"wrote {path}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
