r"""Benchmark Problem 2 (TVMMP) on Case-2-sized states; see :mod:`mjtvm.bench`.

Usage: ``python scripts/bench.py [--seeds 0 1 2] [--repeats 300] [--baseline-repeats 10]
[--out results/bench.json]``
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mjtvm.bench import format_table, run_benchmark


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark, print a table and write the JSON report."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="random_state seeds")
    parser.add_argument("--repeats", type=int, default=300, help="timed calls of tvmmp per state (>= 200)")
    parser.add_argument("--baseline-repeats", type=int, default=10, help="timed calls of the cvxpy baseline")
    parser.add_argument("--warmup", type=int, default=20, help="untimed calls before timing")
    parser.add_argument("--baseline-solver", default="CLARABEL", help="cvxpy solver of the baseline")
    parser.add_argument("--out", type=Path, default=Path("results/bench.json"), help="JSON report")
    args = parser.parse_args(argv)
    if args.repeats < 1 or args.baseline_repeats < 1 or args.warmup < 0:
        parser.error("--repeats and --baseline-repeats must be >= 1, --warmup >= 0")
    report = run_benchmark(
        args.seeds,
        repeats=args.repeats,
        baseline_repeats=args.baseline_repeats,
        warmup=args.warmup,
        baseline_solver=args.baseline_solver,
    )
    print(format_table(report))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
