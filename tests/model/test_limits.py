"""Joint position limits (mjtvm.model.limits, docs/joint-limits.md): hand-derived alphas of a
planar finger on and near its limit, Problem 1's one-sided speeds, the travel speed, the state
format's round trip and refusals, and tvmmp against the cvxpy reference on random limits."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize

from mjtvm.errors import StateError
from mjtvm.formats.state_file import load_state, parse_state, state_to_dict
from mjtvm.model.contacts import Contact
from mjtvm.model.limits import JointLimits, travel_speed
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.polytopes.lifted import lifted_polytope
from mjtvm.problem2.assembly import assemble
from mjtvm.problem2.tvmmp import tvmmp
from oracles.reference import reference_tvmmp
from tests.support.perturb import random_case

# Torque up to 1 N m at every speed up to 2 rad/s: no torque is needed (REFS 0), so each
# joint may turn at 2 rad/s either way.
BOX = OperationRange([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.0, 2.0]])
UP, DOWN = [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]


def finger(joints: int, limits: JointLimits | None) -> GraspState:
    """A planar finger pushing an object up through one L-contact at p_O, normal +y: each
    joint moves the contact by 0.1 m/s per rad/s along y (J = [0.1, ..., 0.1] in y), so
    ``v_y = 0.1 sum qd`` (eq. 8) and, without limits, alpha = 0.1 * 2 * joints."""
    jac = np.zeros((2, joints))
    jac[1] = 0.1
    return GraspState(
        space=2,
        object_position=[0.0, 0.0],
        joint_names=tuple(f"j{i}" for i in range(joints)),
        operation_ranges=(BOX,) * joints,
        gravity_torque=np.zeros(joints),
        contacts=(Contact("tip", "L", [0.0, 0.0], [0.0, 1.0], jac),),
        refs=[[0.0, 0.0, 0.0]],
        rvds=[UP, DOWN],
        joint_limits=limits,
    )


def alphas(state: GraspState) -> list[float]:
    result = tvmmp(state, witnesses=False)
    assert all(all(row) for row in result.certified)
    return [float(a) for a in result.alpha[0]]


def test_one_joint_on_its_limit_is_one_sided() -> None:
    """One joint, qd = 10 alpha up and -10 alpha down, |qd| <= 2: alpha 0.2 both ways. On its
    upper limit (q = hi) it cannot turn up: alpha up 0, down still 0.2; on its lower limit the
    reverse; within the tolerance (1e-3 rad) as on it, 2e-3 away free again (horizon 0)."""
    assert alphas(finger(1, None)) == pytest.approx([0.2, 0.2], rel=1e-12)
    on_upper = JointLimits([1.0], [-1.0], [1.0], horizon=0.0)
    assert alphas(finger(1, on_upper)) == pytest.approx([0.0, 0.2], rel=1e-12, abs=1e-15)
    on_lower = JointLimits([-1.0], [-1.0], [1.0], horizon=0.0)
    assert alphas(finger(1, on_lower)) == pytest.approx([0.2, 0.0], rel=1e-12, abs=1e-15)
    within = JointLimits([1.0 - 9e-4], [-1.0], [1.0], horizon=0.0)
    assert alphas(finger(1, within)) == pytest.approx([0.0, 0.2], rel=1e-12, abs=1e-15)
    beyond = JointLimits([1.0 + 1e-3], [-1.0], [1.0], horizon=0.0)  # a soft limit overshot
    assert alphas(finger(1, beyond)) == pytest.approx([0.0, 0.2], rel=1e-12, abs=1e-15)
    off = JointLimits([1.0 - 2e-3], [-1.0], [1.0], horizon=0.0)
    assert alphas(finger(1, off)) == pytest.approx([0.2, 0.2], rel=1e-12)


def test_horizon_closed_form() -> None:
    """Two joints, 0.1 (qd1 + qd2) = alpha up. Joint 1 sigma = 0.025 rad below its upper limit
    with H = 0.01 m of travel at s = |v| = 1 per unit alpha: qd1 <= (sigma / H) alpha, so
    alpha <= 0.1 (2.5 alpha + 2): alpha = 0.2 / (1 - 0.25) = 4/15 (joint 2 at 2 rad/s, joint 1
    at 2/3). Down: the lower limit is 1.975 rad away (qd1 >= -197.5 alpha): 0.4 as without
    limits. With H = 0 the joint is free (0.4 up); on its limit joint 2 alone (0.2 up)."""
    assert alphas(finger(2, None)) == pytest.approx([0.4, 0.4], rel=1e-12)
    near = JointLimits([0.975, 0.0], [-1.0, -1.0], [1.0, 1.0], horizon=0.01)
    assert alphas(finger(2, near)) == pytest.approx([4.0 / 15.0, 0.4], rel=1e-9)
    assert alphas(finger(2, near.with_options(horizon=0.0))) == pytest.approx([0.4, 0.4], rel=1e-12)
    on = JointLimits([1.0, 0.0], [-1.0, -1.0], [1.0, 1.0], horizon=0.01)
    assert alphas(finger(2, on)) == pytest.approx([0.2, 0.4], rel=1e-12)
    # H = 0.1 m: joint 2 (1 rad from either limit) also gets qd2 <= 10 alpha, not binding at
    # 2 rad/s; joint 1 qd1 <= 0.25 alpha: alpha = 0.2 / (1 - 0.025) up; down 0.4.
    assert alphas(finger(2, near.with_options(horizon=0.1))) == pytest.approx([0.2 / 0.975, 0.4], rel=1e-9)
    # H = 1 m: the joints' whole ranges move the contact 0.1 (0.025 + 1) = 0.1025 m up and
    # 0.1 (1.975 + 1) = 0.2975 m down, both short of 1 m: no speed lasts the horizon, alpha 0.
    assert alphas(finger(2, near.with_options(horizon=1.0))) == pytest.approx([0.0, 0.0], abs=1e-15)


def test_problem1_takes_the_on_limit_rows_only() -> None:
    """Problem 1 (lifted polytope, free twist): the on-limit joint's speed is one-sided, so v_y
    spans [-0.2, 0] instead of [-0.2, 0.2]; the horizon rows are Problem 2's alone."""
    on = JointLimits([1.0], [-1.0], [1.0])
    state = finger(1, on)
    assert assemble(state).A.shape[0] == assemble(finger(1, None)).A.shape[0] + 1
    near = finger(2, JointLimits([0.975, 0.0], [-1.0, -1.0], [1.0, 1.0], horizon=0.01))
    assert assemble(near).A.shape[0] == assemble(finger(2, None)).A.shape[0]
    assert assemble(near, horizon=True).A.shape[0] == assemble(finger(2, None)).A.shape[0] + 4
    for st, expected in ((state, (-0.2, 0.0)), (finger(1, None), (-0.2, 0.2))):
        lp = lifted_polytope(st, rvds_cone=False)
        vy = lp.twist_cols.start + 1
        got = []
        for sign in (1.0, -1.0):
            c = np.zeros(lp.A.shape[1])
            c[vy] = sign
            a = lp.A.toarray()
            fin_u, fin_l = np.isfinite(lp.row_upper), np.isfinite(lp.row_lower)
            res = scipy.optimize.linprog(
                c,
                A_ub=np.vstack([a[fin_u], -a[fin_l]]),
                b_ub=np.concatenate([lp.row_upper[fin_u], -lp.row_lower[fin_l]]),
                bounds=list(zip(lp.col_lower, lp.col_upper)),
                method="highs",
            )
            assert res.status == 0
            got.append(sign * res.fun)
        assert got == pytest.approx(expected, abs=1e-12)


def test_travel_speed() -> None:
    """|v| for a translation; for a rotation the contact farthest from the axis (0.05 m at
    1 rad/s: 0.05 m/s); for both, the fastest point."""
    jac = np.array([[0.0], [0.1]])
    st = finger(1, None).with_(
        contacts=(
            Contact("a", "L", [0.05, 0.0], [0.0, 1.0], jac),
            Contact("b", "L", [-0.02, 0.0], [0.0, 1.0], jac),
        )
    )
    assert travel_speed(st, np.array([0.0, 0.0, 1.0])) == pytest.approx(0.05, rel=1e-15)
    assert travel_speed(st, np.array([3.0, 4.0, 0.0])) == pytest.approx(5.0, rel=1e-15)
    # v_y = 1 plus 10 rad/s about z: the contact at x = 0.05 moves at 1 + 10 * 0.05 = 1.5 m/s
    assert travel_speed(st, np.array([0.0, 1.0, 10.0])) == pytest.approx(1.5, rel=1e-15)


def test_travel_speed_spatial_is_numpy_cross_exactly() -> None:
    """In space: 2 rad/s about z moves a contact 0.05 m off the axis (0.03, 0.04, 0.5) at
    0.1 m/s; and on random twists the speed is bit for bit the one from ``np.cross``."""
    from types import SimpleNamespace

    def contacts(points):  # type: ignore[no-untyped-def]
        return tuple(SimpleNamespace(position=p) for p in points)

    st = SimpleNamespace(dim=3, contacts=contacts([[0.03, 0.04, 0.5]]), object_position=np.zeros(3))
    assert travel_speed(st, np.array([0.0, 0.0, 0.0, 0.0, 0.0, 2.0])) == pytest.approx(0.1, rel=1e-15)
    rng = np.random.default_rng(7)
    for _ in range(50):
        pts = rng.standard_normal((5, 3))
        centre = rng.standard_normal(3)
        st = SimpleNamespace(dim=3, contacts=contacts(pts), object_position=centre)
        r = rng.standard_normal(6) * 10.0 ** rng.integers(-6, 6, size=6)
        u = r[:3] + np.cross(r[3:], pts - centre)
        want = max(float(np.sqrt(r[:3] @ r[:3])), float(np.sqrt(np.max(np.einsum("ij,ij->i", u, u)))))
        assert travel_speed(st, r) == want


def test_state_format_round_trip_and_refusals() -> None:
    lim = JointLimits([0.975, 0.0], [-1.0, -np.inf], [1.0, np.inf], tolerance=2e-3, horizon=0.01)
    state = finger(2, lim)
    doc = state_to_dict(state)
    assert doc["joints"][0]["position"] == 0.975 and doc["joints"][0]["range"] == [-1.0, 1.0]
    assert "range" not in doc["joints"][1]
    assert doc["joint_limits"] == {"tolerance": 2e-3, "horizon": 0.01}
    back = load_state(doc)
    assert back.joint_limits is not None
    assert back.joint_limits.tolerance == 2e-3 and back.joint_limits.horizon == 0.01
    np.testing.assert_array_equal(back.joint_limits.upper, [1.0, np.inf])
    assert alphas(back) == alphas(state)
    assert "joint_limits" not in state_to_dict(finger(2, None))
    bad = state_to_dict(state)
    del bad["joints"][0]["range"]
    with pytest.raises(StateError, match=r"joints\[0\]\.range: required with the joint's position"):
        parse_state(bad)
    bad = state_to_dict(state)
    bad["joints"][0]["range"] = [1.0, -1.0]
    with pytest.raises(
        StateError, match=r"joints\[0\]\.range: expected \[lower, upper\] with lower <= upper"
    ):
        load_state(bad)
    bad = state_to_dict(state)
    bad["joint_limits"]["horizon"] = -1.0
    with pytest.raises(StateError, match=r"joint_limits\.horizon"):
        load_state(bad)
    bad = state_to_dict(finger(2, None))
    bad["joint_limits"] = {"horizon": 0.01}
    with pytest.raises(StateError, match="joint_limits: needs at least one joint with a position"):
        load_state(bad)


def _random_limits(state: GraspState, rng: np.random.Generator) -> GraspState:
    """Limits [-1, 1] on every joint, each on its upper or lower limit, within the horizon of
    either, or far from both; a horizon of 0, 1 mm or 1 cm."""
    m = state.num_joints
    kind = rng.choice(4, size=m, p=[0.1, 0.1, 0.3, 0.5])
    pos = np.where(
        kind == 0, 1.0, np.where(kind == 1, -1.0, np.where(kind == 2, 1.0 - rng.uniform(0, 0.05, m), 0.0))
    )
    horizon = float(rng.choice([0.0, 1e-3, 1e-2]))
    return state.with_(joint_limits=JointLimits(pos, -np.ones(m), np.ones(m), horizon=horizon))


@pytest.mark.parametrize("seed", range(8))
def test_random_limits_against_the_reference(seed: int) -> None:
    """tvmmp's limit rows against reference.py's own transcription (cvxpy HiGHS): every alpha
    within 1e-6 relative (or 1e-9 of the largest), the same statuses."""
    _, base = random_case(200 + seed)
    state = _random_limits(base, np.random.default_rng(seed))
    ref_alpha, ref_status = reference_tvmmp(state, solver="HIGHS")
    result = tvmmp(state, witnesses=False)
    assert tuple(tuple(s) for s in result.status) == ref_status
    ok = np.isfinite(ref_alpha)
    floor = 1e-9 * float(np.max(np.abs(ref_alpha[ok]), initial=1.0))
    err = np.abs(result.alpha[ok] - ref_alpha[ok])
    assert np.all(err <= np.maximum(1e-6 * np.abs(ref_alpha[ok]), floor)), (result.alpha, ref_alpha)
