"""The classic measures of known states against their stored values: a check to run by hand
after a change to ``mjtvm.measures`` (about a minute: it makes 40 grasps with MuJoCo), not a
test of the suite.

The states: the 40 five-finger Shadow grasps of the 22-joint throughput benchmark (seed 24,
``benchmarks.rank.bench_throughput_22``), the example dataset's Shadow grasps, the paper's
scenarios (both hands) and the shipped state files. The stored values
(``data/classic-reference.json``) are those of the numpy hull before the compiled kernels
(commit 711f3cb). Epsilons must agree within 1e-9 relative (the L-infinity gap within 1e-9
of the epsilon), the closure margin within 1e-8 (HiGHS's tolerances), every other number
within 1e-12 relative and every flag exactly. It also prints the CPU time per grasp of
``classic_measures`` (as ``mjtvm rank`` calls it) on the 40 grasps.

Usage::

    python -m tests.measures.check_reference           # compare; exit 1 on a difference
    python -m tests.measures.check_reference --write   # store the current values
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from mjtvm.errors import MjtvmError
from mjtvm.formats.state_file import load_state
from mjtvm.jobs.rank import batch_models
from mjtvm.jobs.rank_inputs import read_datasets
from mjtvm.measures import classic_measures
from mjtvm.model.state import GraspState
from mjtvm.paper_hand.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = Path(__file__).parent / "data" / "classic-reference.json"
GRASP_22 = ROOT / "models" / "shadow_hand" / "shadow_hand_5f_coupled-sphere.toml"
EXAMPLE_GRASP = "shadow_hand_coupled-sphere"
EXAMPLE_DATASET = ROOT / "mjtvm" / "data" / "examples" / "shadow-sphere-dataset.npz"
STATE_FILES = (
    "mjtvm/data/examples/pinch.json",
    "tests/measures/data/qhull-wide-shadow.json",
    "tests/problem2/data/undecided-hold.json",
)
TOLERANCE = {"epsilon_l1": 1e-9, "epsilon_linf": 1e-9, "epsilon_linf_gap": 1e-9, "closure_margin": 1e-8}


def _dataset_states(grasp: str, dataset: str) -> list[GraspState]:
    batch = batch_models(grasp)
    states = []
    for e in read_datasets(grasp, [dataset]):
        try:
            states.append(batch.grasp(e).state())
        except MjtvmError:  # the dataset's broken grasps (no contact, penetration)
            continue
    return states


def states() -> dict[str, GraspState]:
    """Every state of the check by name."""
    spec = importlib.util.spec_from_file_location(
        "make_rank_dataset", ROOT / "tools" / "make_rank_dataset.py"
    )
    assert spec is not None and spec.loader is not None
    maker = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(maker)
    out: dict[str, GraspState] = {}
    with tempfile.TemporaryDirectory() as tmp:
        ds = Path(tmp) / "shadow-5f.npz"
        np.savez(ds, **maker.make(40, 0, 24, grasp_file=GRASP_22))
        for i, s in enumerate(_dataset_states(str(GRASP_22), str(ds))):
            out[f"shadow-5f/{i}"] = s
    for i, s in enumerate(_dataset_states(EXAMPLE_GRASP, str(EXAMPLE_DATASET))):
        out[f"example/{i}"] = s
    for name in ("case1", "case1-s", "case2"):
        for hand in ("default", "humanlike"):
            out[f"scenario/{name}:{hand}"] = load_scenario(name, variant=hand).state()
    for path in STATE_FILES:
        out[path] = load_state(ROOT / path)
    return out


def _relative(key: str, want: float, got: float, ref: dict[str, Any]) -> float:
    """The difference relative to the value (the L-infinity gap's: to the epsilon's)."""
    scale = max(abs(want), abs(got), 1e-300)
    if key == "epsilon_linf_gap":
        scale = max(abs(ref["epsilon_linf"]), 1e-300)
    return abs(want - got) / scale if math.isfinite(want) or want != got else 0.0


def _differences(name: str, ref: dict[str, Any], now: dict[str, Any]) -> list[str]:
    out = []
    for key, want in ref.items():
        got = now.get(key)
        if isinstance(want, float) and isinstance(got, float):
            rel = _relative(key, want, got, ref)
            if not rel <= TOLERANCE.get(key, 1e-12):
                out.append(f"{name}: {key} {want!r} -> {got!r} ({rel:.1e} relative)")
        elif want != got:
            out.append(f"{name}: {key} {want!r} -> {got!r}")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="store the current values")
    args = parser.parse_args(argv)
    every = states()
    docs = {name: classic_measures(s, polytope=False).to_dict() for name, s in every.items()}
    grasps = [s for name, s in every.items() if name.startswith("shadow-5f/")]
    c = time.process_time()
    for s in grasps:
        classic_measures(s, polytope=False)
    ms = 1e3 * (time.process_time() - c) / len(grasps)
    print(f"classic_measures: {ms:.2f} CPU ms a grasp on {len(grasps)} five-finger Shadow grasps")
    if args.write:
        REFERENCE.write_text(json.dumps(docs, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        print(f"wrote {REFERENCE} ({len(docs)} states)")
        return 0
    ref = json.loads(REFERENCE.read_text(encoding="utf-8"))
    problems = [f"{name}: not in the reference" for name in docs if name not in ref]
    problems += [f"{name}: missing" for name in ref if name not in docs]
    for name in sorted(set(ref) & set(docs)):
        problems += _differences(name, ref[name], docs[name])
    worst: dict[str, float] = {}
    for name in set(ref) & set(docs):
        for key, want in ref[name].items():
            got = docs[name][key]
            if isinstance(want, float) and isinstance(got, float):
                worst[key] = max(worst.get(key, 0.0), _relative(key, want, got, ref[name]))
    for key, value in sorted(worst.items()):
        print(f"  {key:18s} largest relative difference {value:.1e}")
    print("\n".join(problems) or f"all {len(docs)} states agree")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
