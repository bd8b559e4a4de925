"""``python -m mjtvm.cli``: the ``mjtvm`` command."""

from __future__ import annotations

import sys

from mjtvm.cli.parser import main

sys.exit(main())
