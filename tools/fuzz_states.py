#!/usr/bin/env python3
r"""Fuzz the state loader at scale: mutated shipped states and damaged bytes.

Every shipped example (``mjtvm/data/examples/*.json``) and the states exported from the
scenarios ``case1``, ``case1-s``, ``case2`` are mutated by :mod:`tests.support.fuzz` (the same
mutations as ``tests/problem2/test_fuzz.py``); a fraction of the runs feeds damaged bytes
(truncated JSON, invalid UTF-8, deep brackets, huge literals) through ``load_state``.
A state that loads is solved with ``mjtvm.tvmmp``. Outcomes are counted:

* ``solved``: loaded and solved, output JSON-clean (finite);
* ``StateError <field>``: refused by the loader (indices shown as ``[i]``), or by
  ``tvmmp`` (a state without RVDS);
* ``SolverError <solver>: <status>``: the solver failed (a package error: allowed);
* ``FAILURE``: any other exception, or non-finite output; its traceback is printed.

Usage::

    python tools/fuzz_states.py --count 10000 --seed 1

Exit status 0 when there is no failure, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import random
import re
import sys
import time
import traceback
from collections import Counter
from importlib import resources
from pathlib import Path
from typing import Any

from mjtvm import MjtvmError, SolverError, StateError, load_state, tvmmp
from mjtvm.paper_hand.scenario import scenario_document

# The test oracles live in tests/support, outside the installed package: import them from
# this checkout.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from tests.support.fuzz import mutate_bytes, mutate_document

_INDEX = re.compile(r"\[\d+\]")


def sources() -> dict[str, str]:
    """The JSON text of every state to mutate, by name."""
    examples = resources.files("mjtvm.data").joinpath("examples")
    out = {p.name: p.read_text(encoding="utf-8") for p in examples.iterdir() if p.name.endswith(".json")}
    out.update({name: json.dumps(scenario_document(name)) for name in ("case1", "case1-s", "case2")})
    return dict(sorted(out.items()))


def outcome(source: Any) -> str:
    """Load and solve one input; return its outcome (raises on a failure)."""
    try:
        state = load_state(source)
    except StateError as e:
        if "\n" in str(e):
            raise AssertionError(f"a multi-line error message: {e!r}") from e
        field = _INDEX.sub("[i]", e.field) or "(document)"
        return f"StateError {field}"
    try:
        result = tvmmp(state, witnesses=False)
    except SolverError as e:
        return f"SolverError {e.solver}: {e.status}"
    except StateError as e:
        return f"StateError from tvmmp: {e.field}"
    except MjtvmError as e:
        return f"{type(e).__name__} from tvmmp"
    json.dumps(result.to_dict(witnesses=False), allow_nan=False)  # ValueError on NaN or infinity
    return "solved"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=10_000, help="number of mutated inputs (default 10000)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument(
        "--bytes-fraction",
        type=float,
        default=0.2,
        help="share of inputs given as damaged bytes (default 0.2)",
    )
    args = parser.parse_args(argv)
    if args.count < 1 or not 0.0 <= args.bytes_fraction <= 1.0:
        parser.error("--count must be >= 1 and --bytes-fraction in [0, 1]")
    texts = sources()
    names = list(texts)
    rng = random.Random(args.seed)
    counts: Counter[str] = Counter()
    kinds: Counter[str] = Counter()
    failures = 0
    t0 = time.perf_counter()
    for i in range(args.count):
        name = rng.choice(names)
        doc = json.loads(texts[name])
        as_bytes = rng.random() < args.bytes_fraction
        kinds["bytes" if as_bytes else "document"] += 1
        source = mutate_bytes(doc, rng) if as_bytes else mutate_document(doc, rng)
        try:
            counts[outcome(source)] += 1
        except Exception:  # the point of the script: anything outside the family is a failure
            failures += 1
            counts["FAILURE"] += 1
            print(
                f"--- FAILURE at input {i} (seed {args.seed}, source {name}, bytes {as_bytes})",
                file=sys.stderr,
            )
            traceback.print_exc()
    elapsed = time.perf_counter() - t0
    print(
        f"inputs: {args.count} (seed {args.seed}; {kinds['document']} documents, {kinds['bytes']} byte strings)"
    )
    print(f"sources: {', '.join(names)}")
    print(f"time: {elapsed:.1f} s ({1e3 * elapsed / args.count:.2f} ms per input)")
    for key, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])):
        print(f"{n:7d}  {key}")
    print(f"failures (exceptions outside MjtvmError, or non-finite output): {failures}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
