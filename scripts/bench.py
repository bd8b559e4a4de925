r"""The mjtvm benchmark run; see :mod:`mjtvm.bench.suite`, :mod:`mjtvm.bench.report` and :mod:`mjtvm.cli.bench`.

Usage: ``python scripts/bench.py [--quick] [--repeats 200] [--baseline-repeats 10]
[--time-limit 120] [--out results] [--name bench] [--notes FILE]``, the same as ``mjtvm bench``
(``mjtvm bench --help``). Prints a table and writes ``OUT/NAME.json`` and ``OUT/NAME.md``.
"""

from __future__ import annotations

import sys

from mjtvm.cli import main

if __name__ == "__main__":  # the guard matters: the 2-process sweep's workers re-import this file
    raise SystemExit(main(["bench", *sys.argv[1:]]))
