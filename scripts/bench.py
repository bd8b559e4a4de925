r"""The mjtvm benchmark run (issue 7, item 1); see :mod:`mjtvm.bench_suite` and :mod:`mjtvm.bench_report`.

Usage: ``python scripts/bench.py [--quick] [--repeats 200] [--baseline-repeats 10]
[--time-limit 120] [--out results/bench.json] [--md results/bench.md] [--notes FILE]``
(also ``mjtvm bench``). Prints a table and writes the JSON report and the table.
"""

from __future__ import annotations

from mjtvm.bench_report import main

if __name__ == "__main__":  # the guard matters: the 2-process sweep's workers re-import this file
    raise SystemExit(main())
