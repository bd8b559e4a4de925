r"""Rerun the IK of the paper's cases; write their sources and their grasp files.

Usage: ``python tools/make_scenarios.py [OUTPUT_DIR]`` (default: the package's
``mjtvm/data/scenarios`` for the sources and ``models/paper_hand`` for the grasp files).
Each source's scenario data (the paper's points, IK start and bounds) is kept; each variant's
``solution`` (joint angles, IK residuals, achieved contacts) is recomputed by
:func:`mjtvm.paper_hand.placement.make_documents`, a variant's own hand model (one not in
:func:`mjtvm.paper_hand.hand.model_files`, e.g. Case 1's ``four_finger_hand_thin.xml``) is written by
:func:`mjtvm.paper_hand.placement.variant_model_text`, and the variant's ``mjtvm.grasp/1`` file
(:func:`mjtvm.paper_hand.scenario.grasp_document`) is written from it: ``case2.toml``,
``case2-humanlike.toml``, ... ``tests/paper_hand/test_scenario.py`` checks that the committed files
equal this output.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mjtvm.grasp.resolve.file import models_root
from mjtvm.grasp.resolve.variants import grasp_file_name
from mjtvm.paper_hand.hand import model_files
from mjtvm.paper_hand.placement import make_documents, variant_model_text
from mjtvm.paper_hand.scenario import grasp_document, scenario_path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from tests.support.documents import format_document, format_toml


def main(argv: list[str] | None = None) -> int:
    """Write every scenario source and grasp file; return the process exit code."""
    args = sys.argv[1:] if argv is None else argv
    grasps = Path(args[0]) if args else models_root() / "paper_hand"
    docs = make_documents()
    for name, doc in docs.items():
        out = Path(args[0]) / f"{name}.json" if args else scenario_path(name)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(format_document(doc) + "\n", encoding="utf-8")
        sys.stdout.write(f"wrote {out}\n")
        for variant in doc["variants"]:
            model = str(doc["variants"][variant]["model"])
            if model not in model_files():  # a hand of its own (Case 1's line-thin links)
                (grasps / model).write_text(variant_model_text(doc, variant), encoding="utf-8")
                sys.stdout.write(f"wrote {grasps / model}\n")
            path = grasps / grasp_file_name(name, variant)
            path.write_text(format_toml(grasp_document(doc, variant)), encoding="utf-8")
            sys.stdout.write(f"wrote {path}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
