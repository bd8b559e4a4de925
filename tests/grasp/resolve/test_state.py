"""Grasp-state extraction from MuJoCo (mjtvm.grasp.resolve.state): contacts, Jacobians, gravity torques, errors."""

from __future__ import annotations

import copy

import mujoco
import numpy as np
import pytest
from scipy.optimize import least_squares

from mjtvm.errors import ModelError
from mjtvm.formats.state_file import dump_state, load_state
from mjtvm.grasp.resolve.state import detected_contacts, grasp_state, object_weight
from mjtvm.model.operation_range import default_operation_range
from mjtvm.paper_hand.hand import finger_joint_names, hand_mjcf

from ...helpers import G

M, L, RC, R = 0.051, 0.1, 0.004, 0.1  # link mass, link length, capsule radius, ball radius
JOINTS = ("yaw0", "pitch0", "pitch1", "yaw1")
MOTOR = (
    'gear="40" nominal="24 0.2044130081 1001.120859" saturation="0.0263 0 0" input="vel ff" '
    'controller="0 0 0.0005 0 0 24"'
)
FINGER_XML = f"""
<mujoco>
  <option gravity="0 0 -{G}"/>
  <default><geom contype="2" conaffinity="0"/></default>
  <worldbody>
    <geom name="palm" type="plane" size=".5 .5 .01"/>
    <body name="link1" pos="0 0 0.05">
      <joint name="yaw0" axis="0 0 1"/>
      <joint name="pitch0" axis="0 -1 0"/>
      <inertial pos="0.05 0 0" mass="{M}" diaginertia="1e-7 4e-5 4e-5"/>
      <geom name="link1" type="capsule" fromto="0 0 0 0.1 0 0" size="{RC}"/>
      <body name="link2" pos="0.1 0 0">
        <joint name="pitch1" axis="0 -1 0"/>
        <joint name="yaw1" axis="0 0 1"/>
        <inertial pos="0.05 0 0" mass="{M}" diaginertia="1e-7 4e-5 4e-5"/>
        <geom name="link2" type="capsule" fromto="0 0 0 0.1 0 0" size="{RC}"/>
      </body>
    </body>
    <body name="ball" pos="0 0 1">
      <freejoint name="ball"/>
      <geom name="ball" type="sphere" size="{R}" mass="0.2" contype="1" conaffinity="2"/>
    </body>
  </worldbody>
  <actuator>
    {"".join(f'<dcmotor joint="{j}" {MOTOR}/>' for j in JOINTS)}
  </actuator>
</mujoco>
"""
TYPES = {"link1": "F", "link2": "F", "palm": "D"}


@pytest.fixture(scope="module")
def finger() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(FINGER_XML)


@pytest.fixture(scope="module")
def hand() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(hand_mjcf())


def _pose(model: mujoco.MjModel, q: np.ndarray, *, s: float = 0.06, depth: float = 1e-3) -> mujoco.MjData:
    """Finger at q, ball touching link 2 on its palmar side at arclength s (penetration depth)."""
    data = mujoco.MjData(model)
    data.qpos[:4] = q
    mujoco.mj_kinematics(model, data)
    b = model.body("link2").id
    rot = data.xmat[b].reshape(3, 3)
    centre = data.xpos[b] + s * rot[:, 0] + (R + RC - depth) * rot[:, 2]
    data.qpos[4:] = [*centre, 1, 0, 0, 0]
    return data


def _fd_jacobian(model, data, body: int, point, joints, h: float = 1e-6) -> np.ndarray:
    """Finite differences of the point fixed to `body`, one joint at a time."""
    work = copy.copy(data)
    mujoco.mj_kinematics(model, work)
    local = work.xmat[body].reshape(3, 3).T @ (point - work.xpos[body])
    cols = []
    for name in joints:
        adr = model.joint(name).qposadr[0]
        ends = []
        for step in (h, -h):
            work.qpos[:] = data.qpos
            work.qpos[adr] += step
            mujoco.mj_kinematics(model, work)
            ends.append(work.xpos[body] + work.xmat[body].reshape(3, 3) @ local)
        cols.append((ends[0] - ends[1]) / (2 * h))
    return np.array(cols).T


def _check_jacobians(model, data, state) -> None:
    for c in state.contacts:
        body = model.geom(c.name.split("#")[0]).bodyid[0]
        if body == 0:
            assert not np.any(c.jacobian)  # palm / world: all zeros
            continue
        fd = _fd_jacobian(model, data, body, c.position, state.joint_names)
        np.testing.assert_allclose(c.jacobian, fd, atol=1e-8)


def _check_geometry(state, centre, radius, slack) -> None:
    for c in state.contacts:
        to_centre = centre - c.position
        assert np.linalg.norm(c.normal) == pytest.approx(1.0)
        np.testing.assert_allclose(c.normal, to_centre / np.linalg.norm(to_centre), atol=1e-9)
        assert abs(np.linalg.norm(to_centre) - radius) <= slack


# ---------------------------------------------------------------- gravity torque
def test_gravity_torque_straight_horizontal_finger(finger: mujoco.MjModel) -> None:
    """Straight horizontal finger: base pitch m g (l/2 + 3l/2) = 2 m g l, second pitch m g l/2."""
    state = grasp_state(finger, _pose(finger, np.zeros(4)), contact_types=TYPES, mu=0.3, object_body="ball")
    np.testing.assert_allclose(state.gravity_torque, [0, 2 * M * G * L, M * G * L / 2, 0], atol=1e-12)


@pytest.mark.parametrize(("yaw0", "t1", "t2"), [(0.3, 0.4, 0.5), (-0.7, 1.2, 0.9), (0.1, -0.2, 2.0)])
def test_gravity_torque_bent_finger(finger: mujoco.MjModel, yaw0: float, t1: float, t2: float) -> None:
    state = grasp_state(
        finger, _pose(finger, np.array([yaw0, t1, t2, 0])), contact_types=TYPES, mu=0.3, object_body="ball"
    )
    c1, c12 = np.cos(t1), np.cos(t1 + t2)
    by_hand = [0, M * G * (1.5 * L * c1 + L / 2 * c12), M * G * L / 2 * c12, 0]
    np.testing.assert_allclose(state.gravity_torque, by_hand, atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_gravity_torque_is_the_potential_gradient(finger: mujoco.MjModel, seed: int) -> None:
    q = np.random.default_rng(seed).uniform([-1, 0, 0, -1], [1, 1.5, 1.5, 1])
    data = _pose(finger, q)
    state = grasp_state(finger, data, contact_types=TYPES, mu=0.3, object_body="ball")
    work, h, grad = copy.copy(data), 1e-6, []
    for k in range(4):
        energy = []
        for step in (h, -h):
            work.qpos[:] = data.qpos
            work.qpos[k] += step
            mujoco.mj_kinematics(finger, work)
            energy.append(M * G * (work.xipos[1][2] + work.xipos[2][2]))
        grad.append((energy[0] - energy[1]) / (2 * h))
    np.testing.assert_allclose(state.gravity_torque, grad, atol=1e-8)


def test_gravity_torque_holds_the_finger_still(finger: mujoco.MjModel) -> None:
    """Sign check: applying +g_f with nothing else acting leaves the finger at rest."""
    data = _pose(finger, np.array([0.2, 0.6, 0.8, 0.3]))
    state = grasp_state(finger, data, contact_types=TYPES, mu=0.3, object_body="ball")
    free = copy.copy(data)
    free.qpos[4:7] = [5, 5, 5]  # ball far away: no contact forces
    free.qfrc_applied[:4] = state.gravity_torque
    mujoco.mj_forward(finger, free)
    np.testing.assert_allclose(free.qacc[:4], 0, atol=1e-9)
    free.qfrc_applied[:4] = 0
    mujoco.mj_forward(finger, free)
    assert np.abs(free.qacc[:4]).max() > 1  # without it the finger falls


# ------------------------------------------------------------ contacts, Jacobian
@pytest.mark.parametrize("seed", range(6))
def test_jacobian_and_contact_geometry_random_poses(finger: mujoco.MjModel, seed: int) -> None:
    rng = np.random.default_rng(seed)
    while True:  # a pose where the ball barely penetrates anything (link 1 or the palm)
        q = rng.uniform([-1.5, 0, -0.5, -1.5], [1.5, 1.5, 2.0, 1.5])
        data = _pose(finger, q, s=rng.uniform(0.01, 0.09))
        mujoco.mj_forward(finger, data)
        if all(c.distance > -1.5e-3 for c in detected_contacts(finger, data, object_body="ball")):
            break
    state = grasp_state(finger, data, contact_types=TYPES, mu=0.3, object_body="ball")
    assert "link2" in [c.name for c in state.contacts]
    assert state.joint_names == JOINTS
    _check_jacobians(finger, data, state)
    _check_geometry(state, data.qpos[4:7], R, RC)
    np.testing.assert_allclose(state.object_position, data.qpos[4:7])


def test_contact_point_and_normal_by_hand(finger: mujoco.MjModel) -> None:
    """Horizontal finger, ball centred above link 2 at x = 0.16: contact straight below the centre."""
    data = _pose(finger, np.zeros(4), s=0.06, depth=2e-3)
    state = grasp_state(finger, data, contact_types=TYPES, mu=0.3, object_body="ball")
    (c,) = state.contacts
    np.testing.assert_allclose(c.normal, [0, 0, 1], atol=1e-12)  # into the ball, away from the finger
    np.testing.assert_allclose(c.position, [0.16, 0, 0.05 + RC - 1e-3], atol=1e-12)  # mid-penetration
    np.testing.assert_allclose(c.jacobian[:, 1], [-(RC - 1e-3), 0, 0.16], atol=1e-12)  # base pitch lifts it
    np.testing.assert_allclose(c.jacobian[:, 0], [0, 0.16, 0], atol=1e-12)  # base yaw swings it
    assert c.type == "F" and c.mu == 0.3


def test_defaults_refs_ranges_and_data_untouched(finger: mujoco.MjModel) -> None:
    data = _pose(finger, np.array([0.1, 0.5, 0.7, 0.2]))
    data.qvel[:] = 3.0
    before = (data.qpos.copy(), data.qvel.copy())
    state = grasp_state(finger, data, contact_types=TYPES, mu=0.3, object_body="ball")
    np.testing.assert_array_equal(data.qpos, before[0])
    np.testing.assert_array_equal(data.qvel, before[1])
    np.testing.assert_allclose(state.refs, [[0, 0, -0.2 * G, 0, 0, 0]], atol=1e-12)
    for rng in state.operation_ranges:
        np.testing.assert_allclose(rng.vertices, default_operation_range().vertices, rtol=1e-8)
    still = grasp_state(finger, _pose(finger, data.qpos[:4]), contact_types=TYPES, mu=0.3, object_body="ball")
    np.testing.assert_allclose(state.gravity_torque, still.gravity_torque)  # velocities are ignored


def test_options_pass_through(finger: mujoco.MjModel) -> None:
    data = _pose(finger, np.array([0.1, 0.5, 0.7, 0.2]))
    rvds = [[1, 1, 1, 0, 0, 0], [1, -1, 1, 0, 0, 0]]
    state = grasp_state(
        finger,
        data,
        contact_types={"link2": "S"},
        mu={"link2": 0.4},
        object_body="ball",
        refs=[[0, 0, -2, 0, 0, 0], [0, 0, -1, 0, 0, 0]],
        rvds=rvds,
        slide_directions={"link2": [1, 0, 0]},
        joints=["pitch1", "pitch0"],
        operation_ranges={"pitch0": [[0, 0], [2, 0], [0, 10]]},
        friction_edges=8,
    )
    full = grasp_state(finger, data, contact_types=TYPES, mu=0.3, object_body="ball")
    assert state.joint_names == ("pitch1", "pitch0")
    np.testing.assert_allclose(state.contacts[0].jacobian, full.contacts[0].jacobian[:, [2, 1]])
    np.testing.assert_allclose(state.gravity_torque, full.gravity_torque[[2, 1]])
    np.testing.assert_allclose(state.operation_ranges[1].vertices, [[0, 0], [2, 0], [0, 10]])
    assert state.contacts[0].type == "S" and state.contacts[0].mu == 0.4
    np.testing.assert_allclose(state.contacts[0].slide_direction, [1, 0, 0])
    np.testing.assert_allclose(state.rvds, rvds)
    assert state.refs.shape == (2, 6) and state.friction_edges == 8


def test_object_weight_moment_about_origin() -> None:
    xml = """<mujoco><worldbody><body name="o" pos="0 0 1"><freejoint/>
      <geom type="sphere" size=".1" pos="0.2 0 0" mass="2"/></body></worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    w = object_weight(model, data, object_body="o")
    np.testing.assert_allclose(w, [0, 0, -2 * 9.81, 0, 0.2 * 2 * 9.81, 0], atol=1e-12)  # r x F


# ------------------------------------------------------------- the paper's hand
def _place(model, data, finger: int, s: float, target, q0, *, tangent_to=None) -> None:
    """Inverse kinematics: the point at arclength s on the last link of `finger` at `target`."""
    names = finger_joint_names(finger)
    adr = np.array([model.joint(n).qposadr[0] for n in names])
    lo, hi = np.array([model.jnt_range[model.joint(n).id] for n in names]).T
    lo[1] = 0.0  # keep link 1 above the palm
    body = model.body(f"f{finger}_link2").id

    def residual(q):
        data.qpos[adr] = q
        mujoco.mj_kinematics(model, data)
        rot = data.xmat[body].reshape(3, 3)
        out = data.xpos[body] + s * rot[:, 0] - target
        return out if tangent_to is None else np.r_[out, rot[:, 0] @ (target - tangent_to)]

    sol = least_squares(residual, q0, bounds=(lo, hi), xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.abs(sol.fun).max() < 1e-9
    residual(sol.x)


def _case1(model):
    centre = np.array([0.075, 0, 0.1])
    data = mujoco.MjData(model)
    data.qpos[-7:] = [*centre, 1, 0, 0, 0]
    _place(model, data, 3, 0.075, np.array([0.171, 0, 0.072]), [0, 0, 1.2, 0], tangent_to=centre)
    _place(model, data, 1, 0.1, np.array([-0.022, 0, 0.074]), [0.3, 2.0, 0.5, 0])
    return data, centre


def _case2(model):
    centre = np.array([0.0, 0, 0.1])
    data = mujoco.MjData(model)
    data.qpos[-7:] = [*centre, 1, 0, 0, 0]
    printed = {
        1: [-0.077, -0.038, 0.086],
        2: [0.033, 0.083, 0.14],
        3: [0.097, 0, 0.074],
        4: [0.033, -0.083, 0.14],
    }
    guesses = {1: [0.3, 0.6, 2.2, 0], 2: [0, 0.9, 1.5, 0], 3: [0, 0.3, 2.2, 0], 4: [0, 0.9, 1.5, 0]}
    for f, p in printed.items():
        p = np.array(p)
        _place(model, data, f, 0.1, centre + R * (p - centre) / np.linalg.norm(p - centre), guesses[f])
    return data, centre


def test_case1_state(hand: mujoco.MjModel) -> None:
    data, centre = _case1(hand)
    types = {"f1_tip": "F", "f1_link2": "F", "f3_link1": "F", "f3_link2": "F", "f3_tip": "F", "palm": "D"}
    state = grasp_state(hand, data, contact_types=types, mu=0.3)
    names = [c.name for c in state.contacts]
    assert names == ["palm", "f1_tip", "f3_link1", "f3_link2"]
    positions = {c.name: c.position for c in state.contacts}
    for name, paper in [
        ("palm", [0.075, 0, 0]),
        ("f3_link1", [0.075, 0, 0]),
        ("f3_link2", [0.171, 0, 0.072]),
    ]:
        assert np.linalg.norm(positions[name] - paper) <= 0.005  # within a few mm of the paper's point
    assert np.linalg.norm(positions["f1_tip"] - [-0.022, 0, 0.074]) <= 0.005
    assert state.num_joints == 16 and state.joint_names[:4] == (
        "f1_yaw0",
        "f1_pitch0",
        "f1_pitch1",
        "f1_yaw1",
    )
    np.testing.assert_allclose(state.refs, [[0, 0, -1, 0, 0, 0]], atol=1e-12)  # mg = 1 N
    f3 = [state.joint_names.index(n) for n in finger_joint_names(3)]
    t2 = np.arctan2(0.072, 0.021)  # finger 3: link 1 flat, link 2 raised by t2
    by_hand = [0, M * G * (1.5 * L + L / 2 * np.cos(t2)), M * G * L / 2 * np.cos(t2), 0]
    np.testing.assert_allclose(state.gravity_torque[f3], by_hand, atol=1e-8)  # IK solved to ~1e-9
    _check_jacobians(hand, data, state)
    _check_geometry(state, centre, R, 0.005)
    again = load_state(dump_state(state))
    np.testing.assert_allclose(again.contacts[2].jacobian, state.contacts[2].jacobian)


def test_case2_state_and_one_contact_per_body(hand: mujoco.MjModel) -> None:
    data, centre = _case2(hand)
    types = {"palm": "D", **{f"f{i}_{g}": "F" for i in range(1, 5) for g in ("link2", "tip")}}
    state = grasp_state(hand, data, contact_types=types, mu=0.3)
    assert [c.name for c in state.contacts] == ["palm", "f1_tip", "f2_tip", "f3_tip", "f4_tip"]
    _check_jacobians(hand, data, state)
    _check_geometry(state, centre, R, 0.005)
    every = grasp_state(hand, data, contact_types=types, mu=0.3, one_contact_per_body=False)
    assert {c.name for c in every.contacts} > {c.name for c in state.contacts}  # link 2 penetrates too
    _check_jacobians(hand, data, every)


# ------------------------------------------------------------------- ModelError
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"object_body": "cup"}, "body 'cup': not in the model"),
        ({"joints": ["pitch0", "knuckle"]}, "joint 'knuckle': not in the model"),
        ({"joints": ["ball"]}, "joint 'ball': is not a hinge or slide joint"),
        (
            {"contact_types": {**TYPES, "thumb": "F"}},
            "geom 'thumb': named in contact_types but not in the model",
        ),
        ({"contact_types": {"link2": "X"}}, r"contact_types\['link2'\]"),
        (
            {"contact_types": {"palm": "D"}},
            "geom 'link2': touches the object but has no entry in contact_types",
        ),
        ({"mu": {"link1": 0.3}}, "geom 'link2': its F contact needs a friction coefficient"),
        ({"mu": {"nail": 0.3}}, "geom 'nail': named in mu"),
        ({"contact_types": {"link2": "S"}}, "geom 'link2': its S contact needs an entry in slide_directions"),
        ({"slide_directions": {"nail": [1, 0, 0]}}, "geom 'nail': named in slide_directions"),
        ({"operation_ranges": {"knuckle": [[0, 0], [1, 0], [0, 1]]}}, "joint 'knuckle': not in the model"),
    ],
)
def test_model_errors(finger: mujoco.MjModel, kwargs: dict, match: str) -> None:
    args = {"contact_types": TYPES, "mu": 0.3, "object_body": "ball", **kwargs}
    with pytest.raises(ModelError, match=match):
        grasp_state(finger, _pose(finger, np.array([0.1, 0.5, 0.7, 0.2])), **args)


def test_no_contact_with_the_fingers(finger: mujoco.MjModel) -> None:
    data = mujoco.MjData(finger)
    data.qpos[4:7] = [0.5, 0.5, 0.5]  # floating, touching nothing
    with pytest.raises(ModelError, match="no contact between the object and the fingers"):
        grasp_state(finger, data, contact_types=TYPES, mu=0.3, object_body="ball")
    data.qpos[4:7] = [-0.3, 0, R]  # resting on the palm only
    with pytest.raises(
        ModelError, match=r"no contact between the object and the fingers \(touching: \['palm'\]"
    ):
        grasp_state(finger, data, contact_types=TYPES, mu=0.3, object_body="ball")


def test_joint_without_actuator() -> None:
    xml = FINGER_XML.replace('<dcmotor joint="yaw1"', '<dcmotor joint="yaw0"', 1)
    xml = xml.replace(f'<dcmotor joint="yaw0" {MOTOR}/>', "", 1)  # yaw0 keeps one motor, yaw1 none
    model = mujoco.MjModel.from_xml_string(xml)
    data = _pose(model, np.array([0.1, 0.5, 0.7, 0.2]))
    with pytest.raises(ModelError, match="joint 'yaw1': no actuator drives it"):
        grasp_state(model, data, contact_types=TYPES, mu=0.3, object_body="ball")
    state = grasp_state(
        model,
        data,
        contact_types=TYPES,
        mu=0.3,
        object_body="ball",
        operation_ranges={"yaw1": default_operation_range()},
    )
    assert state.num_joints == 4


def test_detected_contacts_unknown_body(finger: mujoco.MjModel) -> None:
    with pytest.raises(ModelError, match="body 'object': not in the model"):
        detected_contacts(finger, mujoco.MjData(finger))
