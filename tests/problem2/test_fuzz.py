"""Fuzzing the loader: mutated shipped states raise only package errors, and those that
load are solved with only package errors and JSON-clean output (issue 12, item 3).

``tools/fuzz_states.py`` runs the same mutations at scale.
"""

from __future__ import annotations

import json
import random
from functools import cache
from importlib import resources
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mjtvm import MjtvmError, StateError, load_state, tvmmp
from mjtvm.paper_hand.scenario import scenario_document
from tests.support.fuzz import mutate_bytes, mutate_document

EXAMPLES = resources.files("mjtvm.data").joinpath("examples")
SCENARIOS = ("case1", "case1-s", "case2")
SOURCES = tuple(sorted(p.name for p in EXAMPLES.iterdir() if p.name.endswith(".json"))) + SCENARIOS


@cache
def _doc_text(name: str) -> str:
    # Cached as text: every example decodes a fresh copy, so no mutation leaks between them.
    if name in SCENARIOS:
        return json.dumps(scenario_document(name))
    return EXAMPLES.joinpath(name).read_text(encoding="utf-8")


def doc(name: str) -> dict[str, Any]:
    out: dict[str, Any] = json.loads(_doc_text(name))
    return out


def check(source: Any) -> str:
    """Load and solve; return the outcome, failing on any exception outside the family."""
    try:
        state = load_state(source)
    except StateError as e:
        assert e.field is not None and str(e).strip() and "\n" not in str(e)
        return "state-error"
    try:
        result = tvmmp(state, witnesses=False)
    except MjtvmError:
        return "solver-or-state-error"
    json.dumps(result.to_dict(witnesses=False), allow_nan=False)  # finite output only
    return "solved"


FUZZ = settings(
    derandomize=True,
    deadline=None,
    database=None,
    max_examples=600,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


@pytest.mark.parametrize("name", SOURCES)
@FUZZ
@given(rng=st.randoms(use_true_random=False))
def test_mutated_states_raise_only_package_errors(name: str, rng: random.Random) -> None:
    check(mutate_document(doc(name), rng))


@settings(FUZZ, max_examples=300)
@given(rng=st.randoms(use_true_random=False))
def test_damaged_bytes_raise_only_package_errors(rng: random.Random) -> None:
    assert check(mutate_bytes(doc(rng.choice(SOURCES)), rng)) in (
        "state-error",
        "solved",
        "solver-or-state-error",
    )


def test_the_mutator_reaches_every_outcome() -> None:
    """The fuzz is not vacuous: some mutants load and solve, most are refused."""
    outcomes = [check(mutate_document(doc("pinch.json"), random.Random(seed))) for seed in range(300)]
    assert outcomes.count("solved") >= 20
    assert outcomes.count("state-error") >= 150
