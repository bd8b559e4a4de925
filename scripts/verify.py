#!/usr/bin/env python3
"""Physics check of the TVMMP along the lift (issue 6): ``python scripts/verify.py --help``.

A thin wrapper of :func:`mjtvm.verify.run` (the options are :func:`mjtvm.verify.add_arguments`).
"""

from __future__ import annotations

import argparse
import sys

from mjtvm.errors import MjtvmError
from mjtvm.verify import add_arguments, run


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="verify", description=__doc__.splitlines()[0])
    add_arguments(parser)
    args = parser.parse_args(argv)
    try:
        return run(args)
    except MjtvmError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
