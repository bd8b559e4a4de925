r"""The friction margin and the friction interval (:mod:`mjtvm.model.friction`, docs/state-format.md).

The closed form: an object (a point at the origin, planar or spatial) is held between an F
finger pushing along +x (normal n = +x, joint 1 a slide along x) and a second finger on the
other side (normal -x, joint 2 a slide along x), against its weight mg along -y (planar) or
-z (spatial), and moved along +x (RVDS r = e_x). Both joints move at qd = alpha (eq. 7-8), the
x forces are equal (a = c) and the F friction carries the weight: mg <= mu a (eq. 24; the
friction direction is an edge of the pyramid, so exact for 16 edges too). Each joint has the
linear torque-speed range |tau| / T + |qd| / W <= 1, so the fastest motion squeezes least,
a = mg / mu, and

    alpha(mu) = W (1 - mg / (mu T)),

with the F force on its cone's edge (ft / fn = mu). A margin delta makes it
W (1 - mg / ((1 - delta) mu T)) with ft / fn = (1 - delta) mu.

With the second finger an S-point sliding along s = -/+ y (rho = 0: the motion is along x),
its force is c (n - mu_S s), whose y part +/- mu_S c takes from or adds to the weight the F
friction carries: a = mg / (mu_F +/- mu_S) and alpha = W (1 - mg / ((mu_F +/- mu_S) T)), so
alpha increases in mu_S for one slide and decreases for the other: the worst case over an
interval is at one end or the other.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mjtvm.errors import ParamError, StateError
from mjtvm.formats.schema import schema_problem
from mjtvm.formats.state_file import dump_state, load_state, state_to_dict
from mjtvm.model.contacts import Contact
from mjtvm.model.friction import (
    CONE_SCALE,
    cone_margin,
    interval_corners,
    margin_contacts,
    nominal_state,
)
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.problem2.tvmmp import tvmmp
from oracles.reference import reference_tvmmp

EXAMPLES = Path(__file__).resolve().parents[2] / "mjtvm" / "data" / "examples"
MG, T, W = 1.0, 10.0, 2.0


def alpha_closed(mu_eff: float) -> float:
    """W (1 - mg / (mu T)): the module docstring's alpha (0 where the range cannot squeeze)."""
    return max(W * (1.0 - MG / (mu_eff * T)), 0.0)


def squeeze(
    mu: float,
    *,
    space: int = 2,
    second: str = "L",
    slide: float = -1.0,
    mu_s: float = 0.0,
    margin: float = 0.0,
    mu_range: tuple[float, float] | None = None,
    s_range: tuple[float, float] | None = None,
) -> GraspState:
    """The module docstring's grasp: F finger (coefficient ``mu``) and an L or S finger
    (``slide``: the sign of its slide direction along the weight's axis, coefficient ``mu_s``)."""
    d = space
    up = d - 1  # the weight's axis: y in the plane, z in space
    ex = np.eye(d)[0]
    jac1, jac2 = np.zeros((d, 2)), np.zeros((d, 2))
    jac1[0, 0], jac2[0, 1] = 1.0, 1.0
    f = Contact("f", "F", np.zeros(d), ex, jac1, mu=mu, mu_range=mu_range)
    if second == "L":
        other = Contact("g", "L", np.zeros(d), -ex, jac2)
    else:
        s = slide * np.eye(d)[up]
        other = Contact("g", "S", np.zeros(d), -ex, jac2, mu=mu_s, slide_direction=s, mu_range=s_range)
    big_d = 3 if d == 2 else 6
    w = np.zeros(big_d)
    w[up] = -MG
    r = np.zeros(big_d)
    r[0] = 1.0
    rng = OperationRange([[0.0, 0.0], [T, 0.0], [0.0, W]])
    return GraspState(
        space=d,
        object_position=np.zeros(d),
        joint_names=("q1", "q2"),
        operation_ranges=(rng, rng),
        gravity_torque=np.zeros(2),
        contacts=(f, other),
        refs=w.reshape(1, -1),
        rvds=r.reshape(1, -1),
        friction_margin=margin,
    )


def ratio(state: GraspState) -> float:
    """ft / fn of the F contact in the witness of pair (0, 0)."""
    res = tvmmp(state)
    wit = res.witnesses[0][0]
    assert wit is not None
    force = wit.forces[0]
    fn = float(force[0])
    return float(np.linalg.norm(force[1:])) / fn


# ------------------------------------------------------------------ the margin, closed form
@pytest.mark.parametrize("space", [2, 3])
def test_the_witness_sits_on_the_cone_edge_without_a_margin(space: int) -> None:
    """alpha = W (1 - mg / (mu T)) = 1.6 for mu = 0.5, its F force exactly on the cone (0.5)."""
    state = squeeze(0.5, space=space)
    res = tvmmp(state)
    assert res.tvmmp == pytest.approx(alpha_closed(0.5), rel=1e-9)
    assert res.tvmmp == pytest.approx(1.6, rel=1e-9)
    assert ratio(state) == pytest.approx(0.5, rel=1e-7)
    assert res.friction is None  # margin 0, no interval: the old result


@pytest.mark.parametrize("space", [2, 3])
@pytest.mark.parametrize("delta", [0.1, 0.2, 0.5])
def test_the_margin_moves_alpha_as_one_minus_delta_mu(space: int, delta: float) -> None:
    """alpha(delta) = W (1 - mg / ((1 - delta) mu T)) (delta 0.2: 1.5), ft / fn = (1 - delta) mu,
    and the nominal alpha 1.6 beside it."""
    state = squeeze(0.5, space=space, margin=delta)
    res = tvmmp(state)
    assert res.tvmmp == pytest.approx(alpha_closed((1 - delta) * 0.5), rel=1e-9)
    assert ratio(state) == pytest.approx((1 - delta) * 0.5, rel=1e-7)
    assert res.friction is not None
    assert res.friction.margin == delta
    assert res.friction.nominal_tvmmp == pytest.approx(1.6, rel=1e-9)
    assert res.friction.certified and not res.uncertified()
    doc = res.to_dict()
    assert doc["friction"] == {
        "margin": delta,
        "nominal_tvmmp": res.friction.nominal_tvmmp,
        "certified": True,
    }
    assert schema_problem("result", doc) is None


def test_the_margin_decides_feasibility_at_the_cone() -> None:
    """The weight alone on an F contact: f = (0.3, 1) is on the cone of mu = 0.5 at
    (1 - delta) 0.5 = 0.3, i.e. delta = 0.4; delta 0.39 holds it, 0.41 does not."""
    c = Contact("f", "F", [0.0, 0.0], [0.0, 1.0], [[1.0], [0.0]], mu=0.5)
    state = GraspState(
        space=2,
        object_position=[0.0, 0.0],
        joint_names=("q",),
        operation_ranges=(OperationRange([[0, 0], [10, 0], [10, 1], [0, 1]]),),
        gravity_torque=[0.0],
        contacts=(c,),
        refs=[[-0.3, -1.0, 0.0]],
        rvds=[[0.0, 0.0, 0.0]],
    )
    assert tvmmp(state.with_(friction_margin=0.39)).feasible
    assert not tvmmp(state.with_(friction_margin=0.41)).feasible
    assert reference_tvmmp(state.with_(friction_margin=0.41), solver="HIGHS")[1] == (("skipped",),)


def test_the_margin_reaches_the_f_contacts_only() -> None:
    """margin_contacts: F at (1 - delta) mu, S and L as they are; the state itself at 0."""
    state = squeeze(0.5, second="S", mu_s=0.2, margin=0.2)
    f, g = margin_contacts(state)
    assert f.mu == pytest.approx(0.4, rel=1e-15) and g.mu == 0.2
    at_zero = state.with_(friction_margin=0.0)
    assert margin_contacts(at_zero) is at_zero.contacts
    # The S finger slides -y: its friction +0.2 c carries the weight with the F one at 0.4.
    assert tvmmp(state).tvmmp == pytest.approx(alpha_closed(0.4 + 0.2), rel=1e-9)


def test_margin_and_scaled_mu_agree() -> None:
    """The two paths: a state at margin delta and the same state with every F mu times (1 - delta)
    give the same alphas (the margin is applied to the state's mu before assembly)."""
    state = load_state(EXAMPLES / "pinch.json").with_(friction_margin=0.25)
    scaled = state.with_(contacts=margin_contacts(state), friction_margin=0.0)
    assert [c.mu for c in scaled.contacts] == [0.375, 0.375]
    a, b = tvmmp(state), tvmmp(scaled)
    np.testing.assert_allclose(a.alpha, b.alpha, rtol=1e-12)
    assert a.tvmmp is not None and a.tvmmp < tvmmp(nominal_state(state)).tvmmp  # type: ignore[operator]


@pytest.mark.parametrize("delta", [0.0, 0.15, 0.3])
def test_reference_applies_the_margin_on_its_own(delta: float) -> None:
    """reference.py builds its pyramid at (1 - delta) mu itself: its alphas equal tvmmp's on
    pinch.json and on the closed form, spatial and planar."""
    for state in (
        load_state(EXAMPLES / "pinch.json").with_(friction_margin=delta),
        squeeze(0.5, space=3, margin=delta),
        squeeze(0.5, space=2, margin=delta, second="S", mu_s=0.1, slide=1.0),
    ):
        ref_alpha, ref_status = reference_tvmmp(state, solver="HIGHS")
        res = tvmmp(state, witnesses=False)
        assert res.status == ref_status
        np.testing.assert_allclose(res.alpha, ref_alpha, rtol=1e-6)


# ------------------------------------------------------------------ the interval
def test_f_interval_worst_case_is_mu_lo() -> None:
    """F alone: the worst case over [0.4, 0.7] is alpha(0.4) = 1.5 (the cones are nested), at the
    margin 0.1 alpha(0.36); solving at the two ends agrees."""
    state = squeeze(0.5, mu_range=(0.4, 0.7))
    res = tvmmp(state)
    assert res.tvmmp == pytest.approx(1.6, rel=1e-9)  # the nominal mu
    assert res.friction is not None and res.friction.corners == 1
    assert res.friction.worst_tvmmp == pytest.approx(alpha_closed(0.4), rel=1e-9)
    ends = [tvmmp(squeeze(m)).tvmmp for m in (0.4, 0.7)]
    assert res.friction.worst_tvmmp == pytest.approx(min(ends), rel=1e-12)  # type: ignore[type-var]
    assert res.friction.worst_mu == (("f", 0.4),)
    at_margin = tvmmp(state.with_(friction_margin=0.1)).friction
    assert at_margin is not None
    assert at_margin.worst_tvmmp == pytest.approx(alpha_closed(0.9 * 0.4), rel=1e-9)
    assert at_margin.nominal_tvmmp == pytest.approx(1.6, rel=1e-9)


@pytest.mark.parametrize(("slide", "worst_end"), [(-1.0, 0), (1.0, 1)])
def test_s_interval_worst_case_at_the_end_the_closed_form_says(slide: float, worst_end: int) -> None:
    """S with slide -/+y: alpha = W (1 - mg / ((mu_F +/- mu_S) T)): the worst end is mu_lo for
    one, mu_hi for the other. The corners' minimum equals the closed form there, the
    reference's at the ends, and no interior mu is below it."""
    lo, hi = 0.05, 0.25
    state = squeeze(0.6, second="S", slide=slide, mu_s=0.15, s_range=(lo, hi))
    sign = -1.0 if slide > 0 else 1.0  # slide +y: the S friction -mu c s points down, with the weight
    res = tvmmp(state)
    assert res.friction is not None and res.friction.corners == 2
    ends = (lo, hi)
    expected = min(alpha_closed(0.6 + sign * m) for m in ends)
    assert expected == pytest.approx(alpha_closed(0.6 + sign * ends[worst_end]), rel=1e-12)
    assert res.friction.worst_tvmmp == pytest.approx(expected, rel=1e-9)
    assert dict(res.friction.worst_mu)["g"] == ends[worst_end]
    refs = [
        reference_tvmmp(squeeze(0.6, second="S", slide=slide, mu_s=m), solver="HIGHS")[0][0, 0] for m in ends
    ]
    assert res.friction.worst_tvmmp == pytest.approx(min(refs), rel=1e-6)
    for m in np.linspace(lo, hi, 7):
        inner = tvmmp(squeeze(0.6, second="S", slide=slide, mu_s=float(m))).tvmmp
        assert inner is not None and inner >= res.friction.worst_tvmmp - 1e-9


def test_two_s_contacts_pull_opposite_ways() -> None:
    """F (mu 0.8) and two S fingers on the other side, s1 sliding -y (its friction carries the
    weight), s2 +y (its friction adds to it), each in [0.1, 0.3]: 4 corners. The least squeeze
    leaves s2 without force (a = c1 = mg / (mu_F + mu1)), so alpha = W (1 - mg / ((0.8 + mu1) T))
    and the worst corner has mu1 = 0.1: alpha(0.9)."""
    d = 2
    ex, ey = np.eye(d)
    jf, j1, j2 = np.zeros((d, 3)), np.zeros((d, 3)), np.zeros((d, 3))
    jf[0, 0], j1[0, 1], j2[0, 2] = 1.0, 1.0, 1.0
    # x balance a = c1 + c2; y: b + mu1 c1 - mu2 c2 = mg with |b| <= mu_F a (eq. 16-17, 24).
    contacts = (
        Contact("f", "F", [0.0, 0.0], ex, jf, mu=0.8),
        Contact("s1", "S", [0.0, 0.0], -ex, j1, mu=0.2, slide_direction=-ey, mu_range=(0.1, 0.3)),
        Contact("s2", "S", [0.0, 0.0], -ex, j2, mu=0.2, slide_direction=ey, mu_range=(0.1, 0.3)),
    )
    rng = OperationRange([[0.0, 0.0], [T, 0.0], [0.0, W]])
    state = GraspState(
        space=2,
        object_position=[0.0, 0.0],
        joint_names=("q1", "q2", "q3"),
        operation_ranges=(rng, rng, rng),
        gravity_torque=np.zeros(3),
        contacts=contacts,
        refs=[[0.0, -MG, 0.0]],
        rvds=[[1.0, 0.0, 0.0]],
    )
    corners = interval_corners(state)
    assert sorted((c.contacts[1].mu, c.contacts[2].mu) for c in corners) == [
        (0.1, 0.1),
        (0.1, 0.3),
        (0.3, 0.1),
        (0.3, 0.3),
    ]
    res = tvmmp(state)
    assert res.friction is not None and res.friction.corners == 4
    by_corner = {(c.contacts[1].mu, c.contacts[2].mu): tvmmp(c).tvmmp for c in corners}
    assert res.friction.worst_tvmmp == min(by_corner.values())  # type: ignore[type-var]
    assert res.friction.worst_tvmmp == pytest.approx(alpha_closed(0.9), rel=1e-9)
    assert dict(res.friction.worst_mu)["s1"] == 0.1
    # The reference at every corner: the worst case is the reference's minimum too.
    ref = min(reference_tvmmp(c, solver="HIGHS")[0][0, 0] for c in corners)
    assert res.friction.worst_tvmmp == pytest.approx(ref, rel=1e-6)
    # Quasi-concavity on a 5 x 5 grid: nothing inside the box is below the corners' minimum.
    for m1 in np.linspace(0.1, 0.3, 5):
        for m2 in np.linspace(0.1, 0.3, 5):
            cs = (
                contacts[0],
                replace(contacts[1], mu=float(m1), mu_range=None),
                replace(contacts[2], mu=float(m2), mu_range=None),
            )
            inner = tvmmp(state.with_(contacts=cs), witnesses=False).tvmmp
            assert inner is not None and inner >= res.friction.worst_tvmmp - 1e-9  # type: ignore[operator]


# ------------------------------------------------------------------ cones
def test_cone_margin() -> None:
    """elliptic: delta itself; pyramidal: 1 - (1 - delta) / sqrt(2) (0.29289 at 0)."""
    assert cone_margin("elliptic", 0.1) == 0.1
    assert cone_margin("pyramidal") == pytest.approx(1.0 - 1.0 / math.sqrt(2.0), rel=1e-15)
    assert 1.0 - cone_margin("pyramidal", 0.1) == pytest.approx(0.9 / math.sqrt(2.0), rel=1e-15)
    assert CONE_SCALE["pyramidal"] ** 2 == pytest.approx(0.5, rel=1e-15)
    with pytest.raises(ParamError, match="cone: expected 'elliptic' or 'pyramidal'"):
        cone_margin("soft")


def test_a_pyramidal_cone_holds_the_mu_over_sqrt2_pyramid() -> None:
    """MuJoCo's condim-3 pyramid (edges n +- mu t1, n +- mu t2) contains every edge of the LP's
    16-edge pyramid at mu / sqrt(2), whatever the rotation of the tangent frame: each edge's
    tangent part (mu / sqrt 2)(cos th, sin th) has |x| + |y| <= mu (the square's H-form)."""
    mu = 0.6
    for rot in np.linspace(0.0, np.pi / 2, 13):
        th = 2 * np.pi * np.arange(16) / 16 + rot
        x, y = mu / math.sqrt(2) * np.cos(th), mu / math.sqrt(2) * np.sin(th)
        assert np.all(np.abs(x) + np.abs(y) <= mu * (1 + 1e-12))
    # ... and no larger circle fits: the diagonal point of the square is at mu / sqrt(2).
    assert np.hypot(mu / 2, mu / 2) == pytest.approx(mu / math.sqrt(2), rel=1e-15)


# ------------------------------------------------------------------ the state format
def test_state_file_round_trip_and_old_files() -> None:
    """friction_margin and mu_range are written when set and read back; an old state has margin
    0 and no interval, and its document is unchanged."""
    old = load_state(EXAMPLES / "pinch.json")
    assert old.friction_margin == 0.0 and all(c.mu_range is None for c in old.contacts)
    assert "friction_margin" not in state_to_dict(old)
    state = squeeze(0.5, margin=0.1, mu_range=(0.4, 0.6))
    doc = state_to_dict(state)
    assert doc["friction_margin"] == 0.1 and doc["contacts"][0]["mu_range"] == [0.4, 0.6]
    assert schema_problem("state", doc) is None
    again = load_state(dump_state(state))
    assert again.friction_margin == 0.1 and again.contacts[0].mu_range == (0.4, 0.6)


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda d: d.update(friction_margin=1.0), r"friction_margin: expected a number in \[0, 1\), got 1.0"),
        (lambda d: d.update(friction_margin=-0.1), r"friction_margin"),
        (
            lambda d: d["contacts"][0].update(mu_range=[0.6, 0.7]),
            r"contacts\[0\]\.mu_range: expected 0 <= mu_lo",
        ),
        (lambda d: d["contacts"][0].update(mu_range=[0.4]), r"contacts\[0\]\.mu_range"),
        (lambda d: d["contacts"][1].update(mu_range=[0.0, 0.1]), r"contacts\[1\]\.mu_range: only F and S"),
    ],
)
def test_bad_friction_fields_name_the_field(edit, match: str) -> None:  # type: ignore[no-untyped-def]
    doc = state_to_dict(squeeze(0.5))
    edit(doc)
    with pytest.raises(StateError, match=match):
        load_state(json.loads(json.dumps(doc)))


def test_too_many_s_intervals_are_refused() -> None:
    ey = np.array([0.0, 1.0])
    contacts = tuple(
        Contact(
            f"s{i}",
            "S",
            [0.0, 0.0],
            [1.0, 0.0],
            [[1.0], [0.0]],
            mu=0.2,
            slide_direction=ey,
            mu_range=(0.1, 0.3),
        )
        for i in range(9)
    )
    state = squeeze(0.5).with_(
        contacts=contacts,
        joint_names=("q",),
        operation_ranges=(OperationRange([[0, 0], [1, 0], [0, 1]]),),
        gravity_torque=[0.0],
    )
    with pytest.raises(ParamError, match="mu_range: expected at most 8 S contacts"):
        interval_corners(state)
