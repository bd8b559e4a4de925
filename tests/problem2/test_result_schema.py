"""The shipped JSON Schemas (mjtvm/data/schema) accept every result and tvms document the
package writes for its shipped states, including infeasible, unbounded and fallback ones,
and refuse what the writer must never produce (NaN/Infinity, missing keys)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from benchmarks.synthetic import random_state
from mjtvm import tvmmp
from mjtvm.formats.state_file import load_state
from mjtvm.paper_hand.scenario import load_scenario
from mjtvm.polytopes.tvms import tvms

DATA = Path(__file__).resolve().parents[2] / "mjtvm" / "data"
EXAMPLES = sorted((DATA / "examples").glob("*.json"))
SCENARIOS = ("case1", "case1-s", "case2")
#: Problem 2 directions for the scenarios shipped without RVDS: +-e_y, +-omega_x, +-omega_z
PAPER_DIRS = np.eye(6)[[1, 1, 3, 3, 5, 5]] * np.array([1.0, -1.0] * 3)[:, None]


def validator(name: str) -> jsonschema.Draft202012Validator:
    schema = json.loads((DATA / "schema" / f"{name}.schema.json").read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


RESULT, TVMS = validator("result"), validator("tvms")


def check(v: jsonschema.Draft202012Validator, doc: dict) -> None:
    """Valid for the schema and strict JSON (allow_nan=False), after a JSON round trip."""
    text = json.dumps(doc, allow_nan=False)
    v.validate(json.loads(text))


def shipped_states():  # type: ignore[no-untyped-def]
    for path in EXAMPLES:
        yield path.name, load_state(path)
    for name in SCENARIOS:
        yield name, load_scenario(name).state()


@pytest.mark.parametrize("name,state", list(shipped_states()), ids=lambda x: x if isinstance(x, str) else "")
def test_shipped_states_documents_validate(name, state):
    assert EXAMPLES, "no shipped example state"
    check(TVMS, tvms(state).to_dict())
    if state.rvds is None:
        state = replace(state, rvds=PAPER_DIRS)
    for solver in ("highs", "clarabel"):
        res = tvmmp(state, solver=solver)
        check(RESULT, res.to_dict())
        check(RESULT, res.to_dict(witnesses=False))
        # every pair another backend settled carries a note (Clarabel stalls on some of
        # Case 1-S's S-point LPs; HiGHS settles them)
        doc = res.to_dict()
        noted = [n["pair"] for n in doc["notes"]]
        for k, row in enumerate(doc["settled_by"]):
            assert all(b == solver or [k, l] in noted for l, b in enumerate(row))


def test_infeasible_unbounded_and_fallback_documents_validate(monkeypatch):
    pinch = load_state(EXAMPLES[0])
    impossible = pinch.with_(refs=pinch.refs * 1e6)  # a load no torque can hold
    res = tvmmp(impossible)
    assert not res.feasible and res.tvmmp is None
    check(RESULT, res.to_dict())
    free = random_state(0, space=2, fingers=2, joints_per_finger=3, contact_types=("L", "L", "D"))
    doc = tvms(free, rvds_cone=False).to_dict()
    assert doc["status"] == "unbounded"
    check(TVMS, doc)
    check(TVMS, tvms(impossible).to_dict())
    from mjtvm.errors import SolverError
    from mjtvm.lp import solvers

    def unknown(self, *, duals=False):  # type: ignore[no-untyped-def]
        raise SolverError("highs", "Unknown")

    monkeypatch.setattr(solvers.HighsSession, "solve", unknown)
    doc = tvmmp(pinch).to_dict()
    assert doc["notes"] and doc["settled_by"][0][0] == "clarabel"
    check(RESULT, doc)


def test_the_schemas_refuse_what_the_writer_must_not_write():
    doc = tvmmp(load_state(EXAMPLES[0])).to_dict()
    for bad in ({**doc, "alpha": [[-1.0] * 4]}, {k: v for k, v in doc.items() if k != "status"}):
        with pytest.raises(jsonschema.ValidationError):
            RESULT.validate(bad)
    with pytest.raises(ValueError, match="Out of range float values are not JSON compliant"):
        json.dumps({**doc, "tvmmp": float("inf")}, allow_nan=False)
