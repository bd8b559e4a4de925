"""Contact preload (minimum normal force): validation, the mjtvm.state/1 round trip, the schema,
and the LP (n^T f >= preload) on the shipped pinch example."""

from __future__ import annotations

import json
from dataclasses import replace
from importlib import resources

import jsonschema
import numpy as np
import pytest

from mjtvm.errors import StateError
from mjtvm.formats.state_file import load_state, parse_state, state_to_dict
from mjtvm.model.contacts import Contact
from mjtvm.problem2.assembly import assemble
from mjtvm.problem2.tvmmp import tvmmp

PINCH = resources.files("mjtvm").joinpath("data/examples/pinch.json")


def pinch(preload: float):  # type: ignore[no-untyped-def]
    st = load_state(str(PINCH))
    return st.with_(contacts=tuple(replace(c, preload=preload) for c in st.contacts))


def test_preload_is_validated() -> None:
    c = load_state(str(PINCH)).contacts[0]
    for bad in (-1.0, float("nan"), float("inf"), "1", True):
        with pytest.raises(StateError) as e:
            replace(c, preload=bad)
        assert e.value.field == "preload"
    base = Contact("table", "D", [0, 0, 0], [0, 0, 1.0], np.zeros((3, 4)))
    assert replace(base, preload=0.0).preload == 0.0
    with pytest.raises(StateError, match="D contact carries no force"):
        replace(base, preload=0.5)


def test_preload_round_trips_and_is_written_only_when_positive() -> None:
    doc = state_to_dict(pinch(2.5))
    assert [c["preload"] for c in doc["contacts"]] == [2.5, 2.5]
    assert parse_state(doc).contacts[1].preload == 2.5
    assert "preload" not in state_to_dict(pinch(0.0))["contacts"][0]
    doc["contacts"][0]["preload"] = -1
    with pytest.raises(StateError) as e:
        parse_state(doc)
    assert e.value.field == "contacts[0].preload"


def test_schema_agrees_on_preload() -> None:
    schema = json.loads(resources.files("mjtvm").joinpath("data/schema/state.schema.json").read_text())
    v = jsonschema.Draft202012Validator(schema)
    doc = state_to_dict(pinch(2.5))
    assert not list(v.iter_errors(doc))
    doc["contacts"][0]["preload"] = -0.1
    assert list(v.iter_errors(doc))


def test_no_preload_adds_no_row() -> None:
    assert assemble(pinch(0.0)).A.shape[0] + 2 == assemble(pinch(1.0)).A.shape[0]


def test_preload_binds_only_above_the_grasps_own_squeeze() -> None:
    """The pinch squeezes with 3.671 N per fingertip at its limiting pair (l = 1): a preload up to
    that changes nothing; 5 N lowers alpha_11 from 1.10977 to 1.10615; 10 N exceeds what the
    fingers can push (no solution)."""
    free = tvmmp(pinch(0.0))
    w = free.witnesses[0][1]
    assert w is not None
    normals = [float(f @ c.normal) for f, c in zip(w.forces, pinch(0.0).contacts)]
    assert normals == pytest.approx([3.67107, 3.67107], abs=1e-4)
    assert tvmmp(pinch(2.0)).tvmmp == pytest.approx(free.tvmmp, rel=1e-9)
    five = tvmmp(pinch(5.0))
    assert (round(free.tvmmp, 5), round(five.tvmmp, 5)) == (1.10977, 1.10615)
    w5 = five.witnesses[0][1]
    assert w5 is not None
    assert min(float(f @ c.normal) for f, c in zip(w5.forces, pinch(5.0).contacts)) >= 5.0 - 1e-7
    assert tvmmp(pinch(10.0)).tvmmp is None
