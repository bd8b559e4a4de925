"""Joint damping is a loss, never a holding torque (mjtvm.problem2.assembly, docs/state-format.md
"Damping"): a one-joint finger's alpha in closed form, the equivalence with a range whose
losses are folded (OperationRange.with_losses), the cvxpy transcription, and the property
that more damping never raises an alpha, over random states and every shipped hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mjtvm import load_grasp, tvmmp
from mjtvm.model.contacts import Contact
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.model.transmission import Transmission
from oracles.reference import reference_alpha

MODELS = Path(__file__).resolve().parents[2] / "models"
T, W, MG = 2.0, 10.0, 0.5  # N m, rad/s, N


def _slider(b: float, rng: OperationRange | None = None) -> GraspState:
    """A planar one-joint finger under a point object of weight MG: the joint moves the contact
    straight up at 1 m/s per rad/s (J = [0, 1]^T), the contact below the object's point
    (normal +y into it), RVDS up and down. Its torque holding the weight is MG (eq. 19-20)."""
    contact = Contact(
        name="tip",
        type="F",
        position=np.zeros(2),
        normal=np.array([0.0, 1.0]),
        mu=0.5,
        jacobian=np.array([[0.0], [1.0]]),
    )
    return GraspState(
        space=2,
        object_position=np.zeros(2),
        joint_names=("q",),
        operation_ranges=(rng or OperationRange(np.array([[0.0, 0.0], [T, 0.0], [0.0, W]])),),
        gravity_torque=np.zeros(1),
        contacts=(contact,),
        refs=np.array([[0.0, -MG, 0.0]]),
        rvds=np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]),
        transmission=Transmission(("motor",), np.eye(1), joint_damping=np.array([b])),
    )


@pytest.mark.parametrize("box", ["eliminated", "literal"])
@pytest.mark.parametrize("b", [0.0, 0.05, 0.3])
def test_one_damped_joint_has_the_closed_form_alpha(b: float, box: str) -> None:
    """Range tau/T + qd/W <= 1; the motor gives MG + b alpha at speed alpha, up or down:
    alpha = (1 - MG/T) / (b/T + 1/W) both ways. Damping in the balance would have let the
    downward motion spend the damping on holding (alpha (1 - MG/T)/(1/W - b/T) down)."""
    result = tvmmp(_slider(b), box=box)
    expected = (1.0 - MG / T) / (b / T + 1.0 / W)
    np.testing.assert_allclose(result.alpha, [[expected, expected]], rtol=1e-9)
    assert result.held == (True,) and all(result.certified[0])
    up = result.witnesses[0][0]
    assert up is not None
    np.testing.assert_allclose(up.torques, [MG], rtol=1e-9)  # the holding torque, not MG + b qd
    np.testing.assert_allclose(up.box[0, 1], MG + b * expected, rtol=1e-9)  # what the motor gives


def test_one_damped_joint_in_a_box_range_is_speed_limited_until_the_torque_binds() -> None:
    """Box |tau| <= T, |qd| <= W: alpha = min(W, (T - MG)/b)."""
    box = OperationRange.box(T, W)
    for b in (0.0, 0.1, 0.5):
        expected = W if b == 0.0 else min(W, (T - MG) / b)
        np.testing.assert_allclose(tvmmp(_slider(b, box)).alpha, [[expected, expected]], rtol=1e-9)


@pytest.mark.parametrize("b", [0.02, 0.2])
def test_damping_on_p_identity_equals_the_folded_range(b: float) -> None:
    """For an actuator on its own joint the loss b|qd| is what OperationRange.with_losses folds
    into the range: the two states give the same alphas."""
    s = _slider(b)
    folded = s.with_(operation_ranges=(s.operation_ranges[0].with_losses(damping=b),), transmission=None)
    np.testing.assert_allclose(tvmmp(s).alpha, tvmmp(folded).alpha, rtol=1e-9)


def test_the_reference_transcription_agrees_on_damped_states() -> None:
    s = _slider(0.2)
    a = tvmmp(s).alpha
    for l in range(2):
        status, ref = reference_alpha(s, 0, l, solver="CLARABEL")
        assert status == "optimal" and ref == pytest.approx(a[0, l], rel=1e-6)


def _with_damping(state: GraspState, extra: np.ndarray) -> GraspState:
    """``state`` with ``extra`` N m s/rad more damping on its joints (a transmission P = I with
    one actuator per joint where the state has none: the same LP, entry for entry)."""
    t = state.transmission
    if t is None:
        t = Transmission(state.joint_names, np.eye(state.num_joints))
    base = np.zeros(state.num_joints) if t.joint_damping is None else t.joint_damping
    return state.with_(
        transmission=Transmission(
            t.actuator_names, t.moment, t.constraint_names, t.constraint_jacobian, base + extra
        )
    )


def _alphas(state: GraspState) -> np.ndarray:
    result = tvmmp(state, witnesses=False)
    assert all(c is not False for row in result.certified for c in row)
    return np.where(np.isnan(result.alpha), -1.0, result.alpha)  # infeasible below every alpha


def _assert_never_higher(state: GraspState, rng: np.random.Generator) -> int:
    """Damping raised step by step, componentwise, never raises an alpha; returns how many
    alphas fell (so that a test can tell it changed something)."""
    before = _alphas(state)
    fell = 0
    total = np.zeros(state.num_joints)
    for _ in range(3):
        total = total + rng.uniform(0.0, 0.05, state.num_joints) * (rng.random(state.num_joints) < 0.7)
        after = _alphas(_with_damping(state, total))
        assert np.all(after <= before + 1e-9 * np.maximum(1.0, np.abs(before))), (before, after)
        fell += int(np.sum(after < before - 1e-9))
        before = after
    return fell


def _random_state(rng: np.random.Generator) -> GraspState:
    """A planar two-finger grasp of a disc (two joints per finger, random links), a random
    transmission (one tendon per finger over both joints, or one actuator per joint)."""
    contacts, names = [], []
    angles = (np.pi + rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4))
    for i, th in enumerate(angles):
        p = 0.05 * np.array([np.cos(th), np.sin(th)])
        jac = np.zeros((2, 4))
        for j, base in enumerate(rng.uniform(-0.08, 0.08, (2, 2))):
            arm = p - base
            jac[:, 2 * i + j] = [-arm[1], arm[0]]  # a hinge at base: v = omega x (p - base)
        contacts.append(Contact(f"c{i}", "F", p, -p / np.linalg.norm(p), jac, mu=0.6))
        names += [f"f{i}a", f"f{i}b"]
    tendon = rng.random() < 0.5
    moment = np.array([[1.0, rng.uniform(0.5, 1.5), 0, 0], [0, 0, 1.0, rng.uniform(0.5, 1.5)]])
    if not tendon:
        moment = np.eye(4)
    ranges = tuple(
        OperationRange(np.array([[0, 0], [t, 0], [t, 0.6 * w], [0, w]]))
        for t, w in rng.uniform([0.5, 2.0], [2.0, 8.0], (moment.shape[0], 2))
    )
    return GraspState(
        space=2,
        object_position=np.zeros(2),
        joint_names=tuple(names),
        operation_ranges=ranges,
        gravity_torque=rng.uniform(-0.02, 0.02, 4),
        contacts=tuple(contacts),
        refs=np.array([[0.0, -1.0, 0.0], [0.3, -1.0, 0.01]]),
        rvds=np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1.0]]),
        transmission=Transmission(tuple(f"a{i}" for i in range(len(moment))), moment),
    )


def test_more_damping_never_raises_an_alpha_on_random_states() -> None:
    rng = np.random.default_rng(32)
    fell = sum(_assert_never_higher(_random_state(rng), rng) for _ in range(25))
    assert fell > 20  # the damping bites: alphas fall, not only stay


@pytest.mark.parametrize(
    "grasp",
    sorted(str(p.relative_to(MODELS)) for p in MODELS.glob("*/*.toml")),
)
def test_more_damping_never_raises_an_alpha_on_a_shipped_hand(grasp: str) -> None:
    """Each shipped grasp's state (a Problem 1 grasp with the twelve +- axis twists as RVDS)."""
    state = load_grasp(MODELS / grasp).state()
    if state.rvds is None:
        state = state.with_(rvds=np.vstack([np.eye(6), -np.eye(6)]))
    _assert_never_higher(state, np.random.default_rng(7))
