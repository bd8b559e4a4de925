"""Holding at rest and the motions a transmission leaves unheld (mjtvm.problem2.holding): a planar
two-joint finger on a sum tendon in closed form, the hold verdict of Problem 2, and the two
shipped Shadow hands (the public models' sum tendon alone; J1 = J2 coupled)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mjtvm import load_grasp, tvmmp
from mjtvm.model.contacts import Contact
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.model.transmission import Transmission
from mjtvm.problem2.holding import free_motions, unheld_motions
from oracles.reference import reference_alpha

MODELS = Path(__file__).resolve().parents[2] / "models"
MG = 2.0  # N


def _tendon_finger(b1: float, b2: float, coupled: bool = False) -> GraspState:
    """A planar finger with two joints on one sum tendon (P = [1, 1]) under a point object of
    weight MG: the contact below the object's point, normal +y; the joints move the contact's
    y by b1 and b2 m/s per rad/s (and its x by +0.01 and -0.01). The object balance fixes the contact
    force at (0, MG), so the joint torques J^T f = MG (b1, b2), and along the tendon's free
    motion v = (1, -1)/sqrt(2) the hand gives no torque: holding needs MG |b1 - b2| / sqrt(2)
    there. ``coupled`` adds the equality q1 = q2 (J_eq = [1, -1]), which holds that motion."""
    contact = Contact(
        name="tip",
        type="F",
        position=np.zeros(2),
        normal=np.array([0.0, 1.0]),
        mu=0.5,
        jacobian=np.array([[0.01, -0.01], [b1, b2]]),
    )
    transmission = Transmission(
        ("tendon",),
        np.array([[1.0, 1.0]]),
        ("tie",) if coupled else (),
        np.array([[1.0, -1.0]]) if coupled else None,
    )
    return GraspState(
        space=2,
        object_position=np.zeros(2),
        joint_names=("j2", "j1"),
        operation_ranges=(OperationRange.box(5.0, 4.0),),
        gravity_torque=np.zeros(2),
        contacts=(contact,),
        refs=np.array([[0.0, -MG, 0.0]]),
        rvds=np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]),
        transmission=transmission,
    )


def test_the_sum_tendon_leaves_one_motion_free() -> None:
    free = free_motions(_tendon_finger(0.04, 0.01))
    np.testing.assert_allclose(free, [[np.sqrt(0.5), -np.sqrt(0.5)]], atol=1e-15)
    assert free_motions(_tendon_finger(0.04, 0.01, coupled=True)).shape == (0, 2)


def test_a_free_motion_the_weight_needs_held_is_named_with_its_torque() -> None:
    state = _tendon_finger(0.04, 0.01)
    unheld = unheld_motions(state, 0)
    assert unheld is not None and unheld.joints == (("j2", "j1"),)
    np.testing.assert_allclose(np.abs(unheld.torque), [MG * 0.03 / np.sqrt(2)], rtol=1e-8)
    result = tvmmp(state, diagnose=True)
    assert result.held == (False,) and not result.feasible and result.tvmmp is None
    assert all(result.certified[0])  # the infeasible verdict is Farkas-certified
    (d,) = result.diagnosis
    assert d.cause == "unheld" and d.joints == ("j2", "j1")
    assert d.message.startswith("REFS vertex 0 cannot be held at rest")
    assert "(j2 +0.707, j1 -0.707) needs 0.0424 N m" in d.message
    for l in range(2):  # the independent transcription: infeasible too
        assert reference_alpha(state, 0, l, solver="HIGHS")[0] == "infeasible"


def test_the_same_finger_is_held_when_the_contact_needs_no_torque_along_it() -> None:
    """b1 = b2: the contact force's moments about the two joints are equal, so the tendon
    alone holds it; nothing is reported. Up or down, J qd = (0, +-alpha) gives
    qd1 = qd2 = alpha / (b1 + b2) and the tendon's speed 2 alpha / (b1 + b2) <= 4 rad/s:
    alpha = 2 (b1 + b2) = 0.08."""
    state = _tendon_finger(0.02, 0.02)
    assert unheld_motions(state, 0) is None
    result = tvmmp(state, diagnose=True)
    assert result.held == (True,) and result.diagnosis == ()
    np.testing.assert_allclose(result.alpha, [[0.08, 0.08]], rtol=1e-9)


def test_the_equality_holds_what_the_tendon_leaves_free() -> None:
    """Coupled q1 = q2: the constraint force supplies the torque difference, so the weight is
    held; qd1 = qd2 = alpha / (b1 + b2), the tendon's speed 2 alpha / 0.05 <= 4: alpha = 0.1."""
    state = _tendon_finger(0.04, 0.01, coupled=True)
    assert unheld_motions(state, 0) is None
    result = tvmmp(state, diagnose=True)
    assert result.held == (True,) and result.diagnosis == ()
    np.testing.assert_allclose(result.alpha, [[0.1, 0.1]], rtol=1e-9)
    for l in range(2):
        status, ref = reference_alpha(state, 0, l, solver="HIGHS")
        assert status == "optimal" and ref == pytest.approx(0.1, rel=1e-7)


def test_the_public_shadow_model_cannot_hold_its_grasp_and_says_why() -> None:
    state = load_grasp(MODELS / "shadow_hand" / "shadow_hand-sphere.toml").state()
    result = tvmmp(state, diagnose=True)
    assert result.held == (False,) and result.tvmmp is None
    (d,) = result.diagnosis
    assert d.cause == "unheld"
    assert d.joints == ("rh_FFJ2", "rh_FFJ1", "rh_MFJ2", "rh_MFJ1")
    unheld = unheld_motions(state, 0)
    assert unheld is not None
    np.testing.assert_allclose(np.abs(unheld.motions[0, [2, 3]]), np.sqrt(0.5), rtol=1e-12)
    np.testing.assert_allclose(np.abs(unheld.motions[1, [6, 7]]), np.sqrt(0.5), rtol=1e-12)
    assert np.count_nonzero(unheld.motions) == 4


def test_the_coupled_shadow_model_holds_the_same_grasp() -> None:
    state = load_grasp(MODELS / "shadow_hand" / "shadow_hand_coupled-sphere.toml").state()
    assert state.transmission is not None and state.transmission.num_constraints == 2
    assert free_motions(state).shape[0] == 0
    result = tvmmp(state)
    assert result.held == (True,) and result.tvmmp is not None and result.tvmmp > 0.01
    assert all(c for row in result.certified for c in row)


@pytest.mark.parametrize("grasp", ["allegro/allegro-ik.toml", "robotiq_2f85/robotiq_2f85-sphere.toml"])
def test_hands_that_hold_report_it(grasp: str) -> None:
    result = tvmmp(load_grasp(MODELS / grasp).state())
    assert result.held == (True,) and result.feasible


def test_a_nearly_balanced_refs_vertex_is_decided_by_the_hold_test_at_rest() -> None:
    """Case 2, state 25 of the lift, gear 25:1, with an inertial torque offset of the dynamic
    alpha (``mjtvm verify --gears``): the first LP, travel-horizon rows included, leaves both
    backends undecided (HiGHS "Unknown", Clarabel out of iterations). The same hold test at
    rest without the horizon (equivalent at qd = 0) is infeasible and certified, as the cvxpy
    reference finds on the original state."""
    from mjtvm import load_state
    from mjtvm.model.limits import with_limit_horizon
    from oracles.reference import reference_tvmmp

    state = load_state(Path(__file__).parent / "data" / "undecided-hold.json")
    assert state.joint_limits is not None and state.joint_limits.horizon == pytest.approx(1e-3)
    res = tvmmp(state, diagnose=False)
    assert res.feasible is False and res.held == (False,)
    assert res.status == (("infeasible",),) and res.certified == ((True,),)
    assert "hold test at rest without the travel horizon" in res.notes[0][1]
    assert tvmmp(with_limit_horizon(state, 0.0), diagnose=False).status == (("infeasible",),)
    _, status = reference_tvmmp(state, solver="CLARABEL")
    assert status == (("infeasible",),)
