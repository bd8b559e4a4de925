"""Yoshikawa's hand-object manipulability and the kinematic velocity polytope against closed
forms (one-joint fingers pushing a planar object) and Monte-Carlo membership LPs."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from mjtvm import Contact, GraspState, OperationRange, Transmission
from mjtvm.measures import classic_measures
from mjtvm.measures.kinematics import contact_kinematics, kinematic_polytope, manipulability

L = (0.3, 0.5, 0.7, 0.2)  # lever arms of the fingers' joints (m)
S = (2.0, 3.0, 5.0, 4.0)  # largest joint speeds (rad/s)
RHO = 0.5  # torque scale (m)
# Contacts (position, inward normal): rows n^T G^T of [v_x, v_y, omega] are (-1, 0, 0),
# (0, -1, 0) and (0, -1, 1) (n . (v + omega x r) with omega x r = omega (-r_y, r_x)): det 1.
GEOMETRY = [((1.0, 0.0), (-1.0, 0.0)), ((0.0, 1.0), (0.0, -1.0)), ((-1.0, 1.0), (0.0, -1.0))]


def _range(speed: float) -> OperationRange:
    return OperationRange(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, speed], [0.0, speed]]))


def pushers(
    joints: int = 3, contacts: int = 3, kind: str = "L", transmission: Transmission | None = None
) -> GraspState:
    """One-joint fingers pushing along the contact normals: joint i moves contact i's point by
    L_i qd_i along n_i; with 4 joints, joint 3 moves contact 2 too (by L_3 qd_3)."""
    cs = []
    for i, (p, n) in enumerate(GEOMETRY[:contacts]):
        jac = np.zeros((2, joints))
        jac[:, i] = L[i] * np.array(n)
        if i == 2 and joints == 4:
            jac[:, 3] = L[3] * np.array(n)
        cs.append(Contact(f"c{i}", kind, p, n, jac, mu=0.5))  # type: ignore[arg-type]
    ranges = tuple(
        _range(S[i]) for i in range(joints if transmission is None else len(transmission.actuator_names))
    )
    return GraspState(
        space=2,
        object_position=np.zeros(2),
        joint_names=tuple(f"j{i}" for i in range(joints)),
        operation_ranges=ranges,
        gravity_torque=np.zeros(joints),
        contacts=tuple(cs),
        refs=np.zeros((1, 3)),
        transmission=transmission,
    )


def test_one_joint_fingers_manipulability_in_closed_form() -> None:
    """B t = A qd with A = diag(L), det B = 1 / rho in scaled twists [v; rho omega]:
    K = B^-1 A, w = |det K| = L0 L1 L2 rho."""
    w, determined = manipulability(pushers(), RHO)
    assert determined
    assert w == pytest.approx(L[0] * L[1] * L[2] * RHO, rel=1e-12)


def test_redundant_finger_manipulability_in_closed_form() -> None:
    """A fourth joint moving contact 2 too: every qd is consistent, K = B^-1 A (3 x 4),
    det(K K^T) = det(A A^T) / det(B)^2 = L0^2 L1^2 (L2^2 + L3^2) rho^2."""
    w, _ = manipulability(pushers(joints=4), RHO)
    assert w == pytest.approx(L[0] * L[1] * np.hypot(L[2], L[3]) * RHO, rel=1e-12)


def test_coupled_joints_manipulability_in_closed_form() -> None:
    """J_eq: qd_2 = qd_3. In the orthonormal basis of the consistent speeds,
    qd = (z0, z1, z2 / sqrt 2, z2 / sqrt 2): w = L0 L1 (L2 + L3) / sqrt(2) rho."""
    t = Transmission(
        ("a0", "a1", "a2", "a3"),
        np.eye(4),
        ("couple",),
        np.array([[0.0, 0.0, 1.0, -1.0]]),
    )
    w, _ = manipulability(pushers(joints=4, transmission=t), RHO)
    assert w == pytest.approx(L[0] * L[1] * (L[2] + L[3]) / np.sqrt(2.0) * RHO, rel=1e-12)


def test_undetermined_twist_and_too_few_joints() -> None:
    """Two contacts leave the object free to move with the hand at rest: w = 0, not
    determined; the polytope is unbounded."""
    assert manipulability(pushers(contacts=2), RHO) == (0.0, False)
    vol, _, _ = kinematic_polytope(pushers(contacts=2), RHO)
    assert vol == float("inf")


def test_velocity_parallelepiped_in_closed_form() -> None:
    """|qd_i| <= S_i: the twists K [-S, S]^3 form a parallelepiped of volume
    8 S0 S1 S2 |det K| = 8 S0 S1 S2 L0 L1 L2 rho."""
    vol, dim, _ = kinematic_polytope(pushers(), RHO)
    assert dim == 3
    assert vol == pytest.approx(8 * S[0] * S[1] * S[2] * L[0] * L[1] * L[2] * RHO, rel=1e-9)
    m = classic_measures(pushers(), torque_scale=RHO)
    assert m.velocity_volume == pytest.approx(vol, rel=1e-12) and m.velocity_dimension == 3


def test_velocity_prism_in_closed_form_and_by_monte_carlo() -> None:
    """Four joints: B t ranges over [-L0 S0, L0 S0] x [-L1 S1, L1 S1] x the segment of
    half-width L2 S2 + L3 S3 (a zonotope whose only non-zero 3 x 3 minors pair a column of
    contact 2 with the other two): volume 8 rho L0 S0 L1 S1 (L2 S2 + L3 S3). Checked again
    by the membership LP (exists |qd| <= S with A qd = B t) of uniform samples."""
    state = pushers(joints=4)
    vol, dim, verts = kinematic_polytope(state, RHO)
    assert dim == 3
    expected = 8 * RHO * L[0] * S[0] * L[1] * S[1] * (L[2] * S[2] + L[3] * S[3])
    assert vol == pytest.approx(expected, rel=1e-9)
    a, b = contact_kinematics(state, RHO)
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    rng = np.random.default_rng(3)
    n = 400
    samples = lo + (hi - lo) * rng.random((n, 3))
    bounds = [(-s, s) for s in S]
    inside = sum(
        linprog(np.zeros(4), A_eq=a, b_eq=b @ t, bounds=bounds, method="highs").status == 0 for t in samples
    )
    box = float(np.prod(hi - lo))
    p = vol / box
    assert abs(inside / n - p) <= 4.0 * np.sqrt(p * (1 - p) / n)


def test_velocity_polytope_through_a_transmission() -> None:
    """Actuator a2 drives joints 2 and 3 (s = qd_2 + qd_3, |s| <= S2) and J_eq keeps
    qd_2 = qd_3: contact 2 moves at (L2 + L3) s / 2, a box of volume
    8 rho L0 S0 L1 S1 (L2 + L3) S2 / 2."""
    p = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 1.0]])
    t = Transmission(("a0", "a1", "a2"), p, ("couple",), np.array([[0.0, 0.0, 1.0, -1.0]]))
    vol, dim, _ = kinematic_polytope(pushers(joints=4, transmission=t), RHO)
    assert dim == 3
    assert vol == pytest.approx(8 * RHO * L[0] * S[0] * L[1] * S[1] * (L[2] + L[3]) * S[2] / 2, rel=1e-9)


def test_f_contacts_no_joint_can_follow_tangentially_lock_the_object() -> None:
    """The same pushers as F contacts add tangential rows that no joint can meet: the
    consistent motions shrink (no qd moves the object tangentially at the contacts)."""
    w_f, determined = manipulability(pushers(kind="F"), RHO)
    assert determined and w_f == 0.0


def _spatial_fingers(seed: int) -> GraspState:
    """Three 3-joint fingers (random Jacobians) on F contacts at 120 degrees on a sphere of
    radius 0.04 m: B (9 x 6) has full column rank, Q = {qd : A qd in range(B)} is 6-dimensional."""
    rng = np.random.default_rng(seed)
    cs = []
    for k in range(3):
        th = 2.0 * np.pi * k / 3.0
        p = 0.04 * np.array([np.cos(th), np.sin(th), 0.3 * (k - 1)])
        jac = np.zeros((3, 9))
        jac[:, 3 * k : 3 * k + 3] = 0.05 * rng.normal(size=(3, 3))
        cs.append(Contact(f"c{k}", "F", p, -p / np.linalg.norm(p), jac, mu=0.5))
    return GraspState(
        space=3,
        object_position=np.zeros(3),
        joint_names=tuple(f"j{i}" for i in range(9)),
        operation_ranges=tuple(_range(4.0) for _ in range(9)),
        gravity_torque=np.zeros(9),
        contacts=tuple(cs),
        refs=np.zeros((1, 6)),
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_spatial_manipulability_by_the_projector_form(seed: int) -> None:
    """Independently: the consistent joint speeds are the null space of (I - B B^+) A (scipy),
    K = B^+ A on them, w = sqrt(det(K N (K N)^T)) with N orthonormal."""
    from scipy.linalg import null_space

    state = _spatial_fingers(seed)
    rho = 0.04
    a, b = contact_kinematics(state, rho)
    b_pinv = np.linalg.pinv(b)
    n = null_space((np.eye(b.shape[0]) - b @ b_pinv) @ a)
    assert n.shape[1] == 6
    k = b_pinv @ a @ n
    expected = np.sqrt(np.linalg.det(k @ k.T))
    w, determined = manipulability(state, rho)
    assert determined
    assert w == pytest.approx(expected, rel=1e-8)
    # The twist's angular part scales by rho: w scales by rho^3 in space.
    w2, _ = manipulability(state, 2 * rho)
    assert w2 == pytest.approx(8 * w, rel=1e-8)


def test_the_shipped_pinch_is_no_force_closure_and_leaves_the_spin_free() -> None:
    """Two point contacts cannot resist a torque about the line through them (rank 5), and
    the object spins about it with the hand at rest: the twist is not determined and the
    velocity polytope is unbounded."""
    from importlib import resources

    from mjtvm import load_state

    state = load_state(resources.files("mjtvm.data").joinpath("examples/pinch.json"))
    m = classic_measures(state)
    assert not m.force_closure and m.grasp_rank == 5 and m.epsilon_l1 == 0.0 and m.epsilon_linf == 0.0
    assert not m.twist_determined and m.manipulability == 0.0
    assert m.velocity_volume == float("inf")


def test_a_d_point_halves_the_polytope_and_leaves_the_manipulability() -> None:
    """A D-point of the fixed base at (-1, 0), normal (1, 0) into the object: eq. (12) reads
    -n^T (v + omega x r) <= 0, i.e. v_x >= 0; the first pusher gives v_x = -L0 qd_0, so only
    qd_0 <= 0 remains: half the parallelepiped. Yoshikawa's measure uses the equalities only."""
    base = pushers()
    d_point = Contact("base", "D", [-1.0, 0.0], [1.0, 0.0], np.zeros((2, 3)))
    state = base.with_(contacts=(*base.contacts, d_point))
    vol, _, verts = kinematic_polytope(state, RHO)
    full, _, _ = kinematic_polytope(base, RHO)
    assert vol == pytest.approx(full / 2.0, rel=1e-9)
    assert verts[:, 0].min() == pytest.approx(0.0, abs=1e-12)
    assert manipulability(state, RHO) == manipulability(base, RHO)


def test_s_contacts_constrain_the_manipulability_by_their_normal_as_l_contacts() -> None:
    """An S-point's slip is free (a variable rho >= 0 of eq. 13): only its normal row is an
    equality, so Yoshikawa's measure of the pushers as S contacts is that of L contacts."""
    base = pushers()
    sliding = base.with_(
        contacts=tuple(
            Contact(
                c.name,
                "S",
                c.position,
                c.normal,
                c.jacobian,
                mu=0.3,
                slide_direction=[-c.normal[1], c.normal[0]],
            )
            for c in base.contacts
        )
    )
    assert manipulability(sliding, RHO)[0] == pytest.approx(manipulability(base, RHO)[0], rel=1e-12)


def test_the_velocity_status_tells_the_nulls_apart() -> None:
    """The pinch's object moves with the hand at rest (an unbounded velocity polytope: inf,
    null in JSON), a skipped polytope is nan (null too): the status says which."""
    from importlib import resources

    from mjtvm import load_state
    from mjtvm.measures import classic_measures

    pinch = load_state(resources.files("mjtvm.data").joinpath("examples/pinch.json").read_text())
    full, skipped = classic_measures(pinch), classic_measures(pinch, polytope=False)
    assert (full.velocity_status, full.to_dict()["velocity_volume"]) == ("unbounded", None)
    assert (skipped.velocity_status, skipped.to_dict()["velocity_volume"]) == ("skipped", None)
