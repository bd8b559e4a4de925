"""Actuators, transmissions and equality constraints (mjtvm.model.transmission): closed-form
equivalences with one-joint fingers, gauge invariance, the paper's case untouched, the
independent cvxpy transcription, and the mjtvm.state/2 file."""

from __future__ import annotations

import json
from importlib import resources

import numpy as np
import pytest

from mjtvm import StateError, load_state, tvmmp
from mjtvm.formats.state_file import state_to_dict
from mjtvm.model.contacts import Contact
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.model.transmission import Transmission
from oracles.reference import reference_alpha


def pinch() -> GraspState:
    return load_state(resources.files("mjtvm.data").joinpath("examples/pinch.json").read_text())


def _with_columns(state: GraspState, columns: list[list[int]], **changes) -> GraspState:
    """The state with joint j's Jacobian column the sum of the original columns ``columns[j]``
    (and ``changes``)."""
    contacts = tuple(
        Contact(
            name=c.name,
            type=c.type,
            position=c.position,
            normal=c.normal,
            mu=c.mu,
            jacobian=np.column_stack([c.jacobian[:, cols].sum(axis=1) for cols in columns]),
        )
        for c in state.contacts
    )
    return state.with_(contacts=contacts, **changes)


def _along(state: GraspState, columns: list[int]) -> GraspState:
    """The state with the RVDS +- the translation along finger 1's contact velocity of the
    summed Jacobian ``columns``: a motion a one-joint finger 1 can follow."""
    v = state.contacts[0].jacobian[:, columns].sum(axis=1)
    v = v / np.linalg.norm(v)
    return state.with_(rvds=np.array([[*v, 0, 0, 0], [*-v, 0, 0, 0]]))


def _f1_coupled(s: GraspState) -> GraspState:
    """The pinch with finger 1's joints coupled 1:1 (``J_eq = [1, -1]``) and driven by one
    actuator on its first joint (that joint's range); finger 2's joints as they were."""
    r = s.operation_ranges
    return s.with_(
        operation_ranges=(r[0], r[2], r[3]),
        transmission=Transmission(
            ("f1", "f2_pitch0", "f2_pitch1"),
            np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]]),
            ("f1_coupling",),
            np.array([[1.0, -1.0, 0, 0]]),
        ),
    )


def _alphas(state: GraspState) -> np.ndarray:
    r = tvmmp(state)
    assert np.all(r.certified)
    return r.alpha


def test_a_finger_coupled_one_to_one_is_the_one_joint_finger_with_the_summed_column() -> None:
    """q2 = q1 (J_eq = [1, -1]), one actuator on q1: summing the two torque rows, the
    constraint force cancels and u = (j1 + j2)^T f + g1 + g2 -- the one-joint finger whose
    Jacobian column is j1 + j2 and whose gravity torque is g1 + g2."""
    s = _along(pinch(), [0, 1])
    coupled = _f1_coupled(s)
    r, g = s.operation_ranges, s.gravity_torque
    reduced = _with_columns(
        s,
        [[0, 1], [2], [3]],
        joint_names=("f1", "f2_pitch0", "f2_pitch1"),
        operation_ranges=(r[0], r[2], r[3]),
        gravity_torque=np.array([g[0] + g[1], g[2], g[3]]),
    )
    a, b = _alphas(coupled), _alphas(reduced)
    assert np.all(b > 0.1)
    np.testing.assert_allclose(a, b, rtol=1e-9)
    for l in range(len(s.rvds)):
        status, ref = reference_alpha(coupled, 0, l, solver="HIGHS")
        assert status == "optimal" and ref == pytest.approx(a[0, l], rel=1e-7)


def test_a_tendon_on_two_joints_with_one_column_is_the_one_joint_finger() -> None:
    """One tendon with moment [1, 1] on two joints with the same Jacobian column j and the
    same gravity torque g: the passive mode qd1 - qd2 moves nothing, each joint's balance is
    u = j^T f + g, and the actuator's speed qd1 + qd2 drives the contact as one joint of
    column j would."""
    s = _with_columns(_along(pinch(), [0]), [[0], [0], [2], [3]])
    g = s.gravity_torque.copy()
    g[1] = g[0]
    s = s.with_(gravity_torque=g)
    r = s.operation_ranges
    tendon = s.with_(
        operation_ranges=(r[0], r[2], r[3]),
        transmission=Transmission(
            ("tendon", "f2_pitch0", "f2_pitch1"), np.array([[1.0, 1.0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]])
        ),
    )
    reduced = _with_columns(
        s,
        [[0], [2], [3]],
        joint_names=("f1", "f2_pitch0", "f2_pitch1"),
        operation_ranges=(r[0], r[2], r[3]),
        gravity_torque=np.array([g[0], g[2], g[3]]),
    )
    np.testing.assert_allclose(_alphas(tendon), _alphas(reduced), rtol=1e-9)
    # A passive mode that gravity pulls on cannot be held: g1 != g2 with the same column.
    g[1] = g[0] + 0.01
    assert not tvmmp(tendon.with_(gravity_torque=g)).feasible


def test_an_actuator_moment_scaled_by_c_with_its_range_rescaled_gives_the_same_alphas() -> None:
    """s = c P qd, u / c: the same joint torques and speeds (gauge of the moment's unit)."""
    s = pinch()
    r = s.operation_ranges
    moment = np.array([[0.8, 0.3, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0.2], [0, 0, 0, 1.0]])
    base = s.with_(transmission=Transmission(("a", "b", "c", "d"), moment))
    c = np.array([1e-3, 2.0, 7.0, 0.25])
    scaled = s.with_(
        operation_ranges=tuple(op.scaled(torque=1 / k, speed=k) for op, k in zip(r, c, strict=True)),
        transmission=Transmission(("a", "b", "c", "d"), moment * c[:, None]),
    )
    a = _alphas(base)
    assert np.all(a > 0)
    np.testing.assert_allclose(_alphas(scaled), a, rtol=1e-8)
    for l in range(len(s.rvds)):
        status, ref = reference_alpha(base, 0, l, solver="HIGHS")
        assert status == "optimal" and ref == pytest.approx(a[0, l], rel=1e-7)


def test_joint_damping_costs_torque_at_speed() -> None:
    """With damping b the joints need b qd more torque: alpha falls, and the reference agrees."""
    s = pinch()
    plain = s.with_(transmission=Transmission(s.joint_names, np.eye(4)))
    damped = s.with_(transmission=Transmission(s.joint_names, np.eye(4), joint_damping=np.full(4, 0.02)))
    a0, a1 = _alphas(plain), _alphas(damped)
    np.testing.assert_allclose(a0, _alphas(s), rtol=1e-12)  # P = I is the paper's LP
    assert np.all(a1 < a0)
    for l in range(len(s.rvds)):
        status, ref = reference_alpha(damped, 0, l, solver="HIGHS")
        assert status == "optimal" and ref == pytest.approx(a1[0, l], rel=1e-7)


def test_a_state_with_a_transmission_is_written_as_version_2_and_read_back() -> None:
    s = pinch()
    t = Transmission(
        ("a", "b", "c"),
        np.array([[1.0, 0.5, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]]),
        ("tie",),
        np.array([[0.0, 0.0, 1.0, -1.0]]),
        np.array([0.0, 0.01, 0.0, 0.0]),
    )
    state = s.with_(operation_ranges=s.operation_ranges[:3], transmission=t)
    doc = state_to_dict(state)
    assert doc["schema"] == "mjtvm.state/2" and doc["joints"][0] == {"name": "f1_pitch0"}
    back = load_state(json.dumps(doc))
    assert back.transmission is not None
    np.testing.assert_array_equal(back.transmission.moment, t.moment)
    np.testing.assert_array_equal(back.transmission.constraint_jacobian, t.constraint_jacobian)
    np.testing.assert_array_equal(_alphas(back), _alphas(state))
    assert state_to_dict(s)["schema"] == "mjtvm.state/1"  # no transmission: version 1 as before


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d.update(schema="mjtvm.state/1"), r"^transmission: a transmission needs 'mjtvm.state/2'"),
        (
            lambda d: d["transmission"]["actuators"][0].update(moment=[1.0, 0.0]),
            r"^transmission.actuators\[1\].moment: expected 2 numbers \(one per joint\), got 4",
        ),
        (
            lambda d: d["transmission"]["actuators"][0].update(moment=[0.0, 0.0, 0.0, 0.0]),
            r"^transmission.actuators\[0\].moment: expected a non-zero row",
        ),
        (
            lambda d: d["joints"][0].update(operation_range=[[0, 0], [1, 0], [0, 1]]),
            r"^joints\[0\].operation_range: unknown key",
        ),
        (
            lambda d: d["transmission"].update(joint_damping=[-1.0, 0, 0, 0]),
            r"^transmission.joint_damping: expected",
        ),
        (
            lambda d: d["transmission"].update(constraints=[{"name": "c", "jacobian": [0.0, 0.0, 0.0, 0.0]}]),
            r"^transmission.constraints\[0\].jacobian: expected a non-zero row",
        ),
    ],
)
def test_a_bad_transmission_names_the_field(change, message) -> None:
    s = pinch()
    state = s.with_(
        operation_ranges=s.operation_ranges[:2],
        transmission=Transmission(("a", "b"), np.array([[1.0, 1.0, 0, 0], [0, 0, 1.0, 1.0]])),
    )
    doc = state_to_dict(state)
    change(doc)
    with pytest.raises(StateError, match=message):
        load_state(doc)


def test_operation_ranges_count_the_actuators() -> None:
    s = pinch()
    with pytest.raises(StateError, match=r"^joints: expected one operation range per actuator \(1\), got 4"):
        s.with_(transmission=Transmission(("a",), np.ones((1, 4))))
    assert isinstance(s.operation_ranges[0], OperationRange)


def test_a_coupling_that_locks_the_motion_is_named() -> None:
    """Finger 1 coupled 1:1 follows one direction only: the sideways RVDS of the pinch give
    alpha 0, and the diagnosis names its contact together with the coupling."""
    s = pinch()
    coupled = _f1_coupled(s)
    result = tvmmp(coupled, diagnose=True)
    assert np.all(result.alpha == 0.0) and np.all(tvmmp(s).alpha > 0.0)
    assert [d.contacts for d in result.diagnosis] == [("f1_tip",)] * 4
    assert all("with the equality constraints 'f1_coupling'" in d.message for d in result.diagnosis)


def test_round_off_in_the_moment_matrix_leaves_the_answers_certified() -> None:
    """P = I + 1e-15 off the diagonal: the joint speed scale of the certificate comes from each
    joint's strongest actuator, so the tiny arms do not inflate it (they made 3 of 4 alphas
    uncertified when the scale was the fastest s_a / |P_aj|)."""
    s = pinch()
    p = np.eye(4) + 1e-15 * (1.0 - np.eye(4))
    result = tvmmp(s.with_(transmission=Transmission(s.joint_names, p)))
    assert np.all(result.certified) and not result.notes
    np.testing.assert_allclose(result.alpha, _alphas(s), rtol=1e-12)
