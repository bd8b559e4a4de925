r"""Rerun the IK of every shipped scenario and write ``mjtvm/data/scenarios/*.json``.

Usage: ``python scripts/make_scenarios.py [OUTPUT_DIR]`` (default: the package's
``mjtvm/data/scenarios``). Each file's scenario data is kept; each variant's ``solution``
(joint angles, IK residuals, achieved contacts) is recomputed by
:func:`mjtvm.sim.scenario.make_documents`. ``tests/sim/test_scenario.py`` checks that the committed
files equal this output.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mjtvm.sim.scenario import format_document, make_documents, scenario_path


def main(argv: list[str] | None = None) -> int:
    """Write every scenario file; return the process exit code."""
    args = sys.argv[1:] if argv is None else argv
    docs = make_documents()
    for name, doc in docs.items():
        out = Path(args[0]) / f"{name}.json" if args else scenario_path(name)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(format_document(doc) + "\n", encoding="utf-8")
        sys.stdout.write(f"wrote {out}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
