#!/usr/bin/env python3
"""Physics check of the TVMMP along the lift: ``python scripts/verify.py --help``.

The same as ``mjtvm verify`` (the options are :func:`mjtvm.cli.verify.add_arguments`; errors,
exit codes and interrupts are handled by :func:`mjtvm.cli.main`).
"""

from __future__ import annotations

import sys

from mjtvm.cli import main

if __name__ == "__main__":
    raise SystemExit(main(["verify", *sys.argv[1:]]))
