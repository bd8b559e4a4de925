"""Why an alpha is 0 or a pair infeasible (``mjtvm.problem2.diagnosis``), on planar one-joint
fingers whose verdicts are derived by hand in each docstring."""

from __future__ import annotations

import json

import jsonschema
import numpy as np
import pytest

from mjtvm import Contact, GraspState, ParamError, default_operation_range, tvmmp
from mjtvm.formats.schema import load_schema
from mjtvm.model.operation_range import OperationRange
from mjtvm.problem2.diagnosis import kinematic_alpha

from ..helpers import G, max_speed

OP = default_operation_range()
# A planar one-joint finger: joint at the origin, link along +x, its gravity torque G_F. The
# object's origin is 30 mm above the link at x = A; a point (a, 0) of the link moves at
# qd (0, a): J = [[0], [a]].
A, LINK_L, LINK_M = 0.05, 0.1, 0.051
G_F = LINK_M * G * LINK_L / 2
UP = [[0.0, 1.0, 0.0]]  # lift straight up
WEIGHT = [[0.0, -1.0, 0.0]]  # mg = 1 N


def link_point(name: str, a: float, ctype: str = "F") -> Contact:
    return Contact(name, ctype, [a, 0.0], [0.0, 1.0], [[0.0], [a]], mu=0.3)


def palm_point(name: str = "palm", ctype: str = "F") -> Contact:
    """A point of the fixed base (no joint moves it: J = 0) under the object."""
    return Contact(name, ctype, [A + 0.02, 0.0], [0.0, 1.0], [[0.0], [0.0]], mu=0.3)


def state(contacts, refs=WEIGHT, rvds=UP, *, g_f=G_F, op=OP) -> GraspState:
    return GraspState(
        2, (A, 0.03), ("q",), (op,), [g_f], tuple(contacts), np.array(refs, float), np.array(rvds, float)
    )


def test_every_alpha_positive_costs_nothing_and_says_nothing() -> None:
    r"""One F-point at A: alpha = A qd_max(A mg + g_f) > 0 (the straight lift of
    test_tvmmp): no diagnosis, and no key in the result."""
    res = tvmmp(state([link_point("tip", A)]), diagnose=True)
    assert res.tvmmp == pytest.approx(A * max_speed(A * 1.0 + G_F), rel=1e-9)
    assert res.diagnosis == () and "diagnosis" not in res.to_dict()


def test_two_sticking_points_on_one_rigid_link_lock_the_lift() -> None:
    r"""F-points at a1 = A and a2 = 0.03 on the same link: eq. 11 asks (0, a_i qd) = (v_x -
    omega r_y, v_y + omega r_x) at both. Lifting straight up (omega = 0, v = (0, alpha))
    needs alpha = a1 qd = a2 qd, so qd = 0 and alpha = 0; each point alone allows
    qd = alpha / a_i. The diagnosis names both, as a minimal set."""
    tip, mid = link_point("tip", A), link_point("mid", 0.03)
    r = np.array(UP[0])
    assert kinematic_alpha(state([tip, mid]), r) == 0.0
    assert kinematic_alpha(state([tip]), r) > 0.0 and kinematic_alpha(state([mid]), r) > 0.0
    res = tvmmp(state([tip, mid]), diagnose=True)
    assert res.alpha[0, 0] == 0.0
    (d,) = res.diagnosis
    assert (d.pair, d.cause, d.contacts, d.joints) == ((0, 0), "contacts", ("tip", "mid"), ())
    assert "'tip' and 'mid' are sticking points moved by the same joints" in d.message
    assert "\n" not in d.message


def test_a_sticking_point_on_the_palm_locks_the_lift_alone() -> None:
    r"""An F-point on the base (J = 0) asks G^T rdot = 0 there: v_y + omega r_x = 0 and
    v_x - omega r_y = 0, so the straight lift has alpha = 0; the finger's F-point alone
    does not lock it: the minimal set is the palm alone."""
    res = tvmmp(state([link_point("tip", A), palm_point()]), diagnose=True)
    assert res.tvmmp == 0.0
    (d,) = res.diagnosis
    assert (d.cause, d.contacts) == ("contacts", ("palm",))
    assert d.message.endswith("'palm' is on a body no joint moves")


@pytest.mark.parametrize(("slide", "free"), [(1.0, True), (-1.0, False)])
def test_a_sliding_point_allows_the_motion_along_its_slide_only(slide: float, free: bool) -> None:
    r"""An S-point at A, the object translating sideways r = (1, 0, 0): its velocity relative
    to the link's point is G^T r - J qd = (1, -A qd); the normal part is 0 with qd = 0 and
    the tangential part (1, 0) must be rho s with rho >= 0 (eq. 13): possible for s = +x,
    not for s = -x."""
    tip = Contact("tip", "S", [A, 0.0], [0.0, 1.0], [[0.0], [A]], mu=0.3, slide_direction=[slide, 0.0])
    alpha = kinematic_alpha(state([tip]), np.array([1.0, 0.0, 0.0]))
    assert (alpha > 0.0) is free


def test_the_kinematic_alpha_needs_a_twist() -> None:
    with pytest.raises(ParamError, match="expected a non-zero finite twist of 3 numbers"):
        kinematic_alpha(state([link_point("tip", A)]), np.zeros(3))


def test_a_detaching_palm_point_does_not_lock_the_lift() -> None:
    """The same palm point as a D-point (eq. 12: the object may leave it): alpha > 0."""
    res = tvmmp(state([link_point("tip", A), palm_point(ctype="D")]), diagnose=True)
    assert res.tvmmp is not None and res.tvmmp > 0.0 and res.diagnosis == ()


def test_a_torque_limit_below_the_gravity_torque_makes_the_pair_infeasible() -> None:
    r"""g_f = 2 T_max: the joint cannot even hold its own link. The one F-point's force is
    (0, mg) (its moment about p_O must vanish), so the torque needed is
    tau = A mg + g_f (eq. 19) > T_max: infeasible, and the diagnosis names the joint with
    that torque and its limit."""
    g_f = 2.0 * OP.max_torque
    res = tvmmp(state([link_point("tip", A)], g_f=g_f), diagnose=True)
    assert not res.feasible
    (d,) = res.diagnosis
    assert (d.pair, d.cause, d.joints) == ((0, -1), "ranges", ("q",))
    assert d.message == (
        f"REFS vertex 0 cannot be balanced: the torque limits of 'q' (needs {A * 1.0 + g_f:.4g} N m, "
        f"has {OP.max_torque:.4g}) bind (eq. 19-20)"
    )


def test_a_range_with_no_speed_at_the_holding_torque_gives_alpha_0_from_the_ranges() -> None:
    r"""A triangular range (0, 0), (T, 0), (0, S) with T = A mg + g_f, the holding torque:
    the joint can hold but has speed S (1 - tau / T) = 0 left, so alpha = 0 although the
    kinematics allow the lift: the cause is the joint's range."""
    op = OperationRange(np.array([[0.0, 0.0], [A * 1.0 + G_F, 0.0], [0.0, 20.0]]))
    res = tvmmp(state([link_point("tip", A)], op=op), diagnose=True)
    assert res.alpha[0, 0] == 0.0
    (d,) = res.diagnosis
    assert (d.pair, d.cause, d.joints, d.contacts) == ((0, 0), "ranges", ("q",), ())
    assert "the operation ranges of joint 'q' bind" in d.message


def test_a_wrench_no_contact_force_can_balance() -> None:
    """A frictionless point pushes along its normal (0, 1) only: a sideways REFS force
    (1, -1) cannot be balanced whatever the torques (eq. 22)."""
    res = tvmmp(state([link_point("tip", A, "L")], refs=[[1.0, -1.0, 0.0]]), diagnose=True)
    (d,) = res.diagnosis
    assert (d.pair, d.cause, d.joints) == ((0, -1), "balance", ())


def test_the_diagnosis_is_in_the_result_document_and_its_schema() -> None:
    res = tvmmp(state([link_point("tip", A), link_point("mid", 0.03)]), diagnose=True)
    doc = json.loads(json.dumps(res.to_dict()))
    jsonschema.Draft202012Validator(load_schema("result")).validate(doc)
    assert doc["diagnosis"][0]["contacts"] == ["tip", "mid"] and doc["diagnosis"][0]["cause"] == "contacts"
    assert "diagnosis" not in tvmmp(state([link_point("tip", A), link_point("mid", 0.03)])).to_dict()


# ------------------------------------------------------------------ which way, and what relieves it
SIN60, COS60 = np.sqrt(3.0) / 2.0, 0.5


def _generators_power(d, contact: Contact, state_: GraspState) -> np.ndarray:
    """The power of each of the contact's force generators' wrenches along the escape twist."""
    from mjtvm.model.contacts import force_generators
    from mjtvm.problem2.assembly import grasp_map_transpose

    gt = grasp_map_transpose(contact.position, state_.object_position)
    return np.array(d.direction) @ (gt.T @ force_generators(contact))


def test_a_tilted_support_names_the_weight_and_the_friction_that_would_hold_it() -> None:
    r"""A point of the base (J = 0) right under the object's origin, its normal tilted 60 deg
    from vertical, mu = 0.3: its cone (half-angle atan 0.3 = 16.7 deg) does not hold the
    vertical force (0, mg) that the weight asks (whose moment about p_O is 0 there), whatever
    the torques: cause balance. A coefficient mu >= tan 60 deg = 1.7321 holds it (the cone's
    edge n + mu t is then vertical): the relief is 'palm', mu >= 1.74 (the bisection's feasible
    end, rounded up). The escape twist: the weight does positive power along it, and the
    contact's generators none against it (the Farkas bound on their columns, J = 0)."""
    palm = Contact("palm", "F", [A, 0.0], [SIN60, COS60], [[0.0], [0.0]], mu=0.3)
    st = state([palm], g_f=0.0)
    res = tvmmp(st, diagnose=True)
    assert not res.feasible
    (d,) = res.diagnosis
    assert (d.pair, d.cause, d.relief) == ((0, -1), "balance", (("palm", "mu >= 1.74"),))
    assert len(d.direction) == 3 and np.linalg.norm(d.direction) == pytest.approx(1.0)
    assert np.dot(d.direction, WEIGHT[0]) > 0.0  # the weight pushes the object that way
    assert np.all(_generators_power(d, palm, st) >= -1e-9)
    assert "a net force along" in d.message and "balanced with 'palm' mu >= 1.74" in d.message
    ok = st.with_(contacts=(Contact("palm", "F", [A, 0.0], [SIN60, COS60], [[0.0], [0.0]], mu=1.74),))
    assert tvmmp(ok).feasible  # the relief, checked: and just below tan 60 it is not
    low = st.with_(contacts=(Contact("palm", "F", [A, 0.0], [SIN60, COS60], [[0.0], [0.0]], mu=1.73),))
    assert not tvmmp(low).feasible


def test_a_finger_pushing_sideways_under_gravity_cannot_hold_and_says_so() -> None:
    r"""One F-point at A whose normal (1, 0) points sideways: its force's x component n_f
    must vanish (the REFS has none), so with any friction its tangential force mu n_f is 0 too:
    the weight (0, -1) is unbalanced whatever the torques and the coefficient. The escape
    twist has the weight's side (positive power of the weight along it, a downward force
    part); no single change of friction or type relieves it, and the message says to move
    or add a contact."""
    tip = Contact("tip", "F", [A, 0.0], [1.0, 0.0], [[0.0], [A]], mu=0.3)
    res = tvmmp(state([tip]), diagnose=True)
    (d,) = res.diagnosis
    assert (d.pair, d.cause, d.relief) == ((0, -1), "balance", ())
    assert np.dot(d.direction, WEIGHT[0]) > 0.0 and d.direction[1] < 0.0
    assert "no contact's normal opposes that direction" in d.message
    doc = json.loads(json.dumps(res.to_dict()))
    jsonschema.Draft202012Validator(load_schema("result")).validate(doc)
    assert doc["diagnosis"][0]["relief"] == [] and len(doc["diagnosis"][0]["direction"]) == 3


def test_a_frictionless_finger_is_relieved_by_sticking() -> None:
    r"""An L-point (frictionless) under the object, normal tilted 10 deg: its force along the
    normal alone cannot be vertical, so the weight is unbalanced; as an F-point with the
    state's largest coefficient (none: 1) the cone (45 deg) holds the vertical force: relief
    'tip', type F, mu 1."""
    n = [np.sin(np.radians(10.0)), np.cos(np.radians(10.0))]
    tip = Contact("tip", "L", [A, 0.0], n, [[0.0], [A]])
    (d,) = tvmmp(state([tip]), diagnose=True).diagnosis
    assert (d.cause, d.relief) == ("balance", (("tip", "type F, mu 1"),))
