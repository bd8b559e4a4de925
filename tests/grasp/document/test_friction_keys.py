"""The grasp file's friction keys: ``friction_margin``, ``mu_range`` (top-level and per contact)
and ``cone`` (docs/grasp-format.md), and how they reach the state and the CLI."""

from __future__ import annotations

import json
import math
import tomllib
from typing import Any

import numpy as np
import pytest

from mjtvm.cli import main
from mjtvm.grasp.document.document import GraspError
from mjtvm.grasp.resolve.file import load_grasp, shipped_grasps
from mjtvm.model.friction import cone_margin
from mjtvm.problem2.tvmmp import tvmmp

CASE2 = shipped_grasps()["case2"]
MODEL = str(CASE2.parent / "four_finger_hand.xml")


def _doc(**changes: Any) -> dict[str, Any]:
    """Case 2's grasp document with an absolute model path and ``changes`` applied."""
    doc = tomllib.loads(CASE2.read_text(encoding="utf-8"))
    doc["model"] = MODEL
    doc.update(changes)
    return doc


def test_old_files_keep_margin_zero_and_no_interval() -> None:
    state = load_grasp(_doc()).state()
    assert state.friction_margin == 0.0
    assert all(c.mu_range is None for c in state.contacts)


def test_friction_margin_and_cone_reach_the_state() -> None:
    """elliptic (default): delta itself; pyramidal: 1 - (1 - delta) / sqrt(2); model: the paper
    hand's MJCF has no <option cone>, so MuJoCo's default, pyramidal."""
    assert load_grasp(_doc(friction_margin=0.1)).state().friction_margin == 0.1
    pyr = load_grasp(_doc(friction_margin=0.1, cone="pyramidal")).state().friction_margin
    assert pyr == pytest.approx(1.0 - 0.9 / math.sqrt(2.0), rel=1e-15)
    assert load_grasp(_doc(cone="model")).state().friction_margin == cone_margin("pyramidal")
    # with_options replaces delta and keeps the cone
    grasp = load_grasp(_doc(cone="pyramidal")).with_options(friction_margin=0.2)
    assert grasp.state().friction_margin == pytest.approx(1.0 - 0.8 / math.sqrt(2.0), rel=1e-15)


def test_the_margin_lowers_case2_through_the_f_contacts() -> None:
    """Case 2 (F fingers 1 and 3, L fingers 2 and 4, mu 0.3): the state at margin 0.1 gives the
    same alphas as the state with both F coefficients set to 0.27 by hand."""
    state = load_grasp(_doc(friction_margin=0.1)).state()
    by_hand = load_grasp(_doc()).state()
    by_hand = by_hand.with_(
        contacts=tuple(c if c.type != "F" else type(c)(**{**vars(c), "mu": 0.27}) for c in by_hand.contacts)
    )
    a, b = tvmmp(state, witnesses=False), tvmmp(by_hand, witnesses=False)
    np.testing.assert_allclose(a.alpha, b.alpha, rtol=1e-9)
    assert a.friction is not None and a.friction.nominal_tvmmp == pytest.approx(
        tvmmp(load_grasp(_doc()).state(), witnesses=False).tvmmp, rel=1e-12
    )


def test_mu_range_top_level_and_per_contact() -> None:
    """The top-level interval goes to every F/S contact on the top-level mu; a contact's own
    replaces it; L and D contacts have none."""
    doc = _doc(mu_range=[0.25, 0.35])
    f1 = next(i for i, c in enumerate(doc["contacts"]) if c["type"] == "F")
    doc["contacts"][f1] = {**doc["contacts"][f1], "mu_range": [0.2, 0.3]}
    state = load_grasp(doc).state()
    ranges = {c.name: (c.type, c.mu_range) for c in state.contacts}
    assert [r for t, r in ranges.values() if t == "F"] == [(0.2, 0.3), (0.25, 0.35)]
    assert all(r is None for t, r in ranges.values() if t in ("L", "D"))
    res = tvmmp(state, witnesses=False)
    assert res.friction is not None and res.friction.corners == 1  # no S contact: one corner
    low = state.with_(
        contacts=tuple(
            c if c.mu_range is None else type(c)(**{**vars(c), "mu": c.mu_range[0], "mu_range": None})
            for c in state.contacts
        )
    )
    assert res.friction.worst_tvmmp == pytest.approx(tvmmp(low, witnesses=False).tvmmp, rel=1e-12)


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"friction_margin": 1.0}, r"friction_margin: expected a number in \[0, 1\)"),
        ({"friction_margin": -0.5}, r"friction_margin"),
        ({"cone": "soft"}, r"cone"),
        ({"mu_range": [0.4, 0.5]}, r"mu_range: expected \[mu_lo, mu_hi\] around the top-level mu"),
        ({"mu_range": [0.5, 0.1]}, r"mu_range"),
    ],
)
def test_bad_keys_name_the_field(changes: dict[str, Any], match: str) -> None:
    with pytest.raises(GraspError, match=match):
        load_grasp(_doc(**changes))


def test_a_contact_interval_must_hold_its_mu() -> None:
    doc = _doc()
    f1 = next(i for i, c in enumerate(doc["contacts"]) if c["type"] == "F")
    doc["contacts"][f1] = {**doc["contacts"][f1], "mu_range": [0.4, 0.5]}
    with pytest.raises(GraspError, match=rf"contacts\[{f1}\]\.mu_range: expected \[mu_lo, mu_hi\] around mu"):
        load_grasp(doc)
    li = next(i for i, c in enumerate(doc["contacts"]) if c["type"] == "L")
    doc = _doc()
    doc["contacts"][li] = {**doc["contacts"][li], "mu_range": [0.2, 0.4]}
    with pytest.raises(GraspError, match=rf"contacts\[{li}\]\.mu_range: only F and S"):
        load_grasp(doc)


def test_cli_friction_margin(capsys: pytest.CaptureFixture[str]) -> None:
    """solve --friction-margin on a shipped state: the result's friction object; a bad value
    is one line and exit 2."""
    assert main(["solve", "--friction-margin", "0.2", "--no-witnesses"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["friction"]["margin"] == 0.2
    assert doc["friction"]["nominal_tvmmp"] > doc["tvmmp"] > 0
    assert main(["solve", "--friction-margin", "1"]) == 2
    err = capsys.readouterr().err
    assert "--friction-margin: expected a number in [0, 1), got '1'" in err and err.count("\n") == 1


def test_the_driven_witness_keeps_the_margin() -> None:
    """verify drives central_witness of the state it solves: at margin 0.1 every F force of
    Case 2's witness (at its alpha_kl) has ft <= 0.9 mu fn, and the vertex witness of the
    margin-0 LP reaches mu on some F contact (the bug: forces on the cone)."""
    from mjtvm.physics.witness import central_witness

    def worst(state: Any, forces: Any) -> float:
        out = 0.0
        for c, f in zip(state.contacts, forces, strict=True):
            fn = float(f @ c.normal)
            if c.type == "F" and fn > 1e-9:
                out = max(out, float(np.linalg.norm(f - fn * c.normal)) / (fn * c.mu))
        return out

    state = load_grasp(_doc(friction_margin=0.1)).state()
    res = tvmmp(state)
    k, l = res.limiting  # type: ignore[misc]
    sol = central_witness(state, k, l, float(res.alpha[k, l]) * (1 - 1e-7))
    assert worst(state, sol["forces"]) <= 0.9 * (1 + 1e-6)
    nominal = state.with_(friction_margin=0.0)
    vertex = tvmmp(nominal).witnesses[0]
    assert max(worst(nominal, w.forces) for w in vertex if w is not None) > 0.98
