"""Inverse kinematics (mjtvm.grasp.resolve.ik): residual Jacobians by finite differences, convergence, ranges, errors."""

from __future__ import annotations

import copy

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ModelError
from mjtvm.grasp.resolve.ik import IkTarget, geom_contact_target, ik_residual, solve_ik
from mjtvm.grasp.resolve.state import detected_contacts
from mjtvm.paper_hand.hand import HUMANLIKE_FINGER_JOINTS, finger_joint_names, hand_mjcf

R, RC, RT = 0.1, 0.004, 0.005  # sphere, capsule and tip radii of the default hand (m)


@pytest.fixture(scope="module")
def hand() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(hand_mjcf())


@pytest.fixture(scope="module")
def humanlike() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(hand_mjcf(finger_joints=HUMANLIKE_FINGER_JOINTS))


def _finger_q(model: mujoco.MjModel, data: mujoco.MjData, finger: int, q, joints=None) -> None:
    for name, value in zip(finger_joint_names(finger, joints or (("yaw", "pitch"), ("pitch", "yaw"))), q):
        data.qpos[model.joint(name).qposadr[0]] = value


def _point(model, data, body: str, local) -> np.ndarray:
    work = copy.copy(data)
    mujoco.mj_kinematics(model, work)
    b = model.body(body).id
    return work.xpos[b] + work.xmat[b].reshape(3, 3) @ np.asarray(local, float)


# ------------------------------------------------------------ residual Jacobian
@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("variant", ["default", "humanlike"])
def test_residual_jacobian_matches_finite_differences(
    hand: mujoco.MjModel, humanlike: mujoco.MjModel, seed: int, variant: str
) -> None:
    model = hand if variant == "default" else humanlike
    rng = np.random.default_rng(seed)
    data = mujoco.MjData(model)
    data.qpos[:16] = rng.uniform(-1.2, 1.2, 16)
    centre = rng.uniform(-0.1, 0.1, 3) + np.array([0, 0, 0.15])
    last = "link2" if variant == "default" else "link3"
    targets = [
        geom_contact_target(model, "f3_link2", centre + np.array([0.1, 0, 0]), centre, along=0.06),  # 4 rows
        geom_contact_target(model, "f1_tip", centre - np.array([0.1, 0, 0]), centre),  # 3 rows
        IkTarget("free", f"f2_{last}", rng.normal(size=3) * 0.05, [0.1, 0.2, 0.3], [0, 1, 0], centre),
    ]
    dofs = np.arange(16)
    e, jac = ik_residual(model, data, targets, dofs)
    assert e.shape == (11,) and jac.shape == (11, 16)
    h, fd = 1e-6, np.zeros_like(jac)
    for k in range(16):
        plus, minus = copy.copy(data), copy.copy(data)
        plus.qpos[k] += h
        minus.qpos[k] -= h
        fd[:, k] = (
            ik_residual(model, plus, targets, dofs)[0] - ik_residual(model, minus, targets, dofs)[0]
        ) / (2 * h)
    np.testing.assert_allclose(jac, fd, atol=1e-9)


def test_contact_target_geometry(hand: mujoco.MjModel) -> None:
    centre, contact = np.array([0.0, 0, 0.1]), np.array([0.1, 0, 0.1])
    tip = geom_contact_target(hand, "f3_tip", contact, centre)
    np.testing.assert_allclose(tip.point, [0.1, 0, 0])  # the tip centre, in link 2's frame
    np.testing.assert_allclose(
        tip.position, contact + np.array([RT, 0, 0])
    )  # offset by its radius toward the object
    assert tip.tangent_axis is None and tip.body == "f3_link2"
    link = geom_contact_target(hand, "f3_link2", contact, centre, along=0.03)
    np.testing.assert_allclose(link.point, [0.03, 0, 0], atol=1e-15)  # from the joint end
    np.testing.assert_allclose(link.position, contact + np.array([RC, 0, 0]))
    np.testing.assert_allclose(np.abs(link.tangent_axis), [1, 0, 0], atol=1e-15)
    thin = geom_contact_target(hand, "f3_link2", contact, centre, along=0.03, offset=0.0, tangent=False)
    np.testing.assert_allclose(thin.position, contact)
    assert thin.rows == 3 and link.rows == 4


# ------------------------------------------------------------------ convergence
@pytest.mark.parametrize("seed", range(6))
def test_converges_to_reachable_tip_targets(hand: mujoco.MjModel, seed: int) -> None:
    """Targets made by forward kinematics at random angles, solved from other angles."""
    rng = np.random.default_rng(seed)
    goal = mujoco.MjData(hand)
    goal.qpos[:16] = rng.uniform([-1, 0.2, 0.2, -1] * 4, [1, 1.5, 1.5, 1] * 4)
    targets = [
        IkTarget(f"f{f}_tip", f"f{f}_link2", [0.1, 0, 0], _point(hand, goal, f"f{f}_link2", [0.1, 0, 0]))
        for f in range(1, 5)
    ]
    start = mujoco.MjData(hand)
    start.qpos[:16] = goal.qpos[:16] + rng.uniform(-0.3, 0.3, 16)
    before = start.qpos.copy()
    result = solve_ik(hand, start, targets)
    np.testing.assert_array_equal(start.qpos, before)  # the input is not modified
    assert result.converged and result.residuals.max() <= 1e-10 and result.iterations < 30
    assert len(result.joints) == 16 and result.qpos.shape == (hand.nq,)
    solved = mujoco.MjData(hand)
    solved.qpos[:] = result.qpos
    for t in targets:
        np.testing.assert_allclose(_point(hand, solved, t.body, t.point), t.position, atol=1e-10)


def test_tangent_capsule_touches_the_sphere(hand: mujoco.MjModel) -> None:
    """A link placed with the tangency row touches the sphere at the contact: MuJoCo agrees."""
    goal = mujoco.MjData(hand)
    _finger_q(hand, goal, 3, [0.3, 0.4, 1.0, 0.2])
    mujoco.mj_kinematics(hand, goal)
    b = hand.body("f3_link2").id
    rot = goal.xmat[b].reshape(3, 3)
    axis_point = goal.xpos[b] + 0.06 * rot[:, 0]
    normal = rot[:, 2]  # palmar side, perpendicular to the link
    centre = axis_point + (R + RC) * normal
    contact = axis_point + RC * normal
    data = mujoco.MjData(hand)
    _finger_q(hand, data, 3, [0.0, 0.2, 1.3, 0.0])
    data.qpos[-7:] = [*centre, 1, 0, 0, 0]
    result = solve_ik(hand, data, [geom_contact_target(hand, "f3_link2", contact, centre, along=0.06)])
    assert result.converged
    data.qpos[:] = result.qpos
    mujoco.mj_forward(hand, data)
    (found,) = [c for c in detected_contacts(hand, data) if c.geom == "f3_link2"]
    assert abs(found.distance) < 1e-9
    np.testing.assert_allclose(found.position, contact, atol=1e-9)
    np.testing.assert_allclose(found.normal, normal, atol=1e-9)


def test_overdetermined_consistent_targets_converge(hand: mujoco.MjModel) -> None:
    """Case 1's finger 3: 8 residual rows on 4 joints, consistent: exact solution, link 1 flat."""
    centre = np.array([0.075, 0, 0.1])
    data = mujoco.MjData(hand)
    _finger_q(hand, data, 3, [0.1, 0.1, 1.0, 0.1])
    targets = [
        geom_contact_target(hand, "f3_link1", [0.075, 0, 0], centre, along=0.025, offset=0.0),
        geom_contact_target(hand, "f3_link2", [0.171, 0, 0.072], centre, along=0.075, offset=0.0),
    ]
    result = solve_ik(hand, data, targets)
    q = result.qpos[[hand.joint(n).qposadr[0] for n in finger_joint_names(3)]]
    np.testing.assert_allclose(q, [0, 0, np.arctan2(0.072, 0.021), 0], atol=1e-9)


# ---------------------------------------------------------- ranges and failures
def test_unreachable_target_names_target_and_residual(hand: mujoco.MjModel) -> None:
    """Tip 0.5 m from finger 3's base: the straight finger reaches 0.2 m, residual 0.3 m."""
    target = IkTarget("far", "f3_link2", [0.1, 0, 0], [0.55, 0, 0])
    data = mujoco.MjData(hand)
    _finger_q(hand, data, 3, [0.1, 0.3, 0.3, 0.1])
    with pytest.raises(
        ModelError, match=r"IK target 'far': unreachable: residual 0\.3 m above the tolerance"
    ):
        solve_ik(hand, data, [target])
    result = solve_ik(hand, data, [target], strict=False)
    assert not result.converged
    assert result.residuals[0] == pytest.approx(0.3, abs=1e-6)


def test_joint_ranges_and_bounds_are_respected(hand: mujoco.MjModel) -> None:
    """A tip target behind finger 3 needs pitches beyond the given bounds: the solver stops at them."""
    target = IkTarget("behind", "f3_link2", [0.1, 0, 0], [-0.05, 0.0, 0.08])
    data = mujoco.MjData(hand)
    bounds = {"f3_pitch0": (0.0, 0.5), "f3_pitch1": (0.0, 0.5)}
    result = solve_ik(hand, data, [target], bounds=bounds, strict=False)
    assert not result.converged and result.residuals[0] > 0.05
    for name in finger_joint_names(3):
        j = hand.joint(name)
        lo, hi = bounds.get(name, hand.jnt_range[j.id])
        assert lo - 1e-12 <= result.qpos[j.qposadr[0]] <= hi + 1e-12
    assert result.qpos[hand.joint("f3_pitch0").qposadr[0]] == pytest.approx(0.5)  # pressed on its bound
    free = solve_ik(hand, data, [target])  # without the bounds (pitches up to pi) it is reachable
    assert free.converged
    for name in finger_joint_names(3):
        j = hand.joint(name)
        assert hand.jnt_range[j.id][0] <= free.qpos[j.qposadr[0]] <= hand.jnt_range[j.id][1]


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (
            lambda m, d: solve_ik(m, d, [IkTarget("t", "f9_link1", [0, 0, 0], [0, 0, 0])]),
            "body 'f9_link1': not in the model",
        ),
        (
            lambda m, d: solve_ik(
                m, d, [IkTarget("t", "f1_link1", [0, 0, 0], [0, 0, 0])], joints=["f1_knuckle"]
            ),
            "joint 'f1_knuckle': not in the model",
        ),
        (
            lambda m, d: solve_ik(m, d, [IkTarget("t", "f1_link1", [0, 0, 0], [0, 0, 0])], joints=["object"]),
            "joint 'object': is not a hinge or slide joint",
        ),
        (
            lambda m, d: solve_ik(
                m, d, [IkTarget("t", "f1_link1", [0, 0, 0], [0, 0, 0])], bounds={"f1_knuckle": (0, 1)}
            ),
            "joint 'f1_knuckle': not in the model",
        ),
        (
            lambda m, d: solve_ik(
                m, d, [IkTarget("t", "f1_link1", [0, 0, 0], [0, 0, 0])], bounds={"f2_yaw0": (0, 1)}
            ),
            "joint 'f2_yaw0': has a bound but is not among the joints solved for",
        ),
        (
            lambda m, d: solve_ik(
                m, d, [IkTarget("t", "f1_link1", [0, 0, 0], [0, 0, 0])], bounds={"f1_yaw0": (1, 0)}
            ),
            r"joint 'f1_yaw0': empty range",
        ),
        (lambda m, d: solve_ik(m, d, []), "targets: expected at least one IK target"),
        (
            lambda m, d: geom_contact_target(m, "f1_nail", [0, 0, 0], [0, 0, 0.1]),
            "geom 'f1_nail': not in the model",
        ),
        (lambda m, d: geom_contact_target(m, "palm", [0, 0, 0], [0, 0, 0.1]), "expected a sphere"),
        (lambda m, d: geom_contact_target(m, "f1_link2", [0, 0, 0], [0, 0, 0.1]), "needs 0 <= along <= 0.1"),
        (lambda m, d: geom_contact_target(m, "f1_tip", [0, 0, 0.1], [0, 0, 0.1]), "at the sphere centre"),
        (lambda m, d: IkTarget("t", "f1_link1", [0, 0], [0, 0, 0]), "expected 3 finite numbers"),
        (
            lambda m, d: IkTarget("t", "f1_link1", [0, 0, 0], [0, 0, 0], tangent_axis=[1, 0, 0]),
            "tangent_axis and centre go together",
        ),
        (
            lambda m, d: IkTarget(
                "t", "f1_link1", [0, 0, 0], [0, 0, 0], tangent_axis=[2, 0, 0], centre=[0, 0, 0]
            ),
            "unit vector",
        ),
    ],
)
def test_errors(hand: mujoco.MjModel, call, match: str) -> None:
    with pytest.raises(ModelError, match=match):
        call(hand, mujoco.MjData(hand))
