"""``docs/measures.md``: its field table is exactly what ``GraspMeasures.to_dict`` writes."""

from __future__ import annotations

import json
from dataclasses import fields
from pathlib import Path

import numpy as np

from mjtvm import GraspMeasures, classic_measures
from tests.docs.test_outputs_doc import field_tables
from tests.measures.test_wrenches import antipodal_disk

DOC = Path(__file__).resolve().parents[2] / "docs" / "measures.md"


def test_documented_keys_are_the_written_keys() -> None:
    documented = field_tables(DOC.read_text(encoding="utf-8"))["measures"]
    written = classic_measures(antipodal_disk(0.5)).to_dict()
    assert documented == list(written) == [f.name for f in fields(GraspMeasures)]


def test_to_dict_is_json_without_inf_or_nan() -> None:
    """An unbounded polytope (the object spins in the pinch) and a skipped one are null."""
    free = antipodal_disk(0.5, kind="L")
    unbounded = classic_measures(free).to_dict()
    skipped = classic_measures(free, polytope=False).to_dict()
    assert unbounded["velocity_volume"] is None and skipped["velocity_volume"] is None
    assert skipped["velocity_dimension"] == -1
    assert json.loads(json.dumps(unbounded, allow_nan=False)) == unbounded
    assert np.isinf(classic_measures(free).velocity_volume)
