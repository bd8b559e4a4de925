"""The test hands in models (issue 14): MJCF written the way public hands are written.

Checks that need MuJoCo only: each model loads as a complete scene, its grasp keyframe puts the
chosen fingertips on the object (``mj_geomDistance`` within 0.1 mm) and nothing else of the hand
near it, and the model keeps the conventions of public MJCF hands that mjtvm must cope with
(primitive geoms, unnamed collision geoms, ``<position>`` actuators, joint ranges, inertials).
The grasp files are parsed as TOML and their names checked against the model.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import pytest

import mjtvm
from mjtvm.grasp.resolve.file import load_grasp
from oracles.reference import reference_tvmmp
from tests.support.finite_diff import contact_jacobians_fd

MODELS = Path(__file__).resolve().parents[3] / "models"
_OBJ = mujoco.mjtObj

#: A fingertip meant to touch the object: its surface distance at the keyframe (m).
TOUCH = 1e-4
#: Every other hand geom: at least this far from the object, the table and the other fingers (m).
CLEAR = 2e-3


@dataclass(frozen=True)
class Hand:
    xml: Path
    grasp: Path
    hinges: int
    tips: tuple[str, ...]  # bodies whose one collision geom touches the object at the keyframe


HANDS = {
    "allegro": Hand(
        MODELS / "allegro" / "allegro_right.xml",
        MODELS / "allegro" / "allegro-sphere.toml",
        16,
        ("ff_tip", "mf_tip", "rf_tip", "th_tip"),
    ),
    "leap": Hand(
        MODELS / "leap_hand" / "leap_right.xml",
        MODELS / "leap_hand" / "leap_hand-sphere.toml",
        16,
        ("if_tip", "mf_tip", "rf_tip", "th_tip"),
    ),
    "gripper3": Hand(
        MODELS / "gripper3" / "gripper3.xml",
        MODELS / "gripper3" / "gripper3-box.toml",
        9,
        ("f1_distal", "f2_distal", "fm_distal"),
    ),
}


@pytest.fixture(params=list(HANDS), scope="module")
def hand(request: pytest.FixtureRequest) -> tuple[Hand, mujoco.MjModel]:
    spec = HANDS[request.param]
    return spec, mujoco.MjModel.from_xml_path(str(spec.xml))


def _object_bodies(model: mujoco.MjModel) -> set[int]:
    root = mujoco.mj_name2id(model, _OBJ.mjOBJ_BODY, "object")
    assert root > 0, "every test hand has a body named 'object'"
    inside = {root}
    for b in range(root + 1, model.nbody):
        if int(model.body_parentid[b]) in inside:
            inside.add(b)
    return inside


def _hand_collision_geoms(model: mujoco.MjModel) -> list[int]:
    inside = _object_bodies(model)
    return [
        g
        for g in range(model.ngeom)
        if (model.geom_contype[g] or model.geom_conaffinity[g])
        and int(model.geom_bodyid[g]) not in inside
        and int(model.geom_bodyid[g]) != 0
    ]


def _at_keyframe(model: mujoco.MjModel) -> mujoco.MjData:
    data = mujoco.MjData(model)
    key = mujoco.mj_name2id(model, _OBJ.mjOBJ_KEY, "grasp")
    assert key >= 0, "the model has a keyframe named 'grasp'"
    mujoco.mj_resetDataKeyframe(model, data, key)
    mujoco.mj_forward(model, data)
    return data


def _distance(model: mujoco.MjModel, data: mujoco.MjData, g1: int, g2: int) -> float:
    return float(mujoco.mj_geomDistance(model, data, g1, g2, 1.0, None))


def test_joints_object_and_inertials(hand: tuple[Hand, mujoco.MjModel]) -> None:
    spec, model = hand
    types = [int(t) for t in model.jnt_type]
    assert types.count(int(mujoco.mjtJoint.mjJNT_HINGE)) == spec.hinges
    assert types.count(int(mujoco.mjtJoint.mjJNT_FREE)) == 1
    free = types.index(int(mujoco.mjtJoint.mjJNT_FREE))
    assert int(model.jnt_bodyid[free]) in _object_bodies(model)
    hinges = [j for j, t in enumerate(types) if t == int(mujoco.mjtJoint.mjJNT_HINGE)]
    assert all(model.jnt_limited[j] for j in hinges), "every finger joint has a range"
    assert all(model.jnt_range[j, 0] < model.jnt_range[j, 1] for j in hinges)
    # Explicit inertials: every moving body has a mass (the geoms carry none).
    moving = {int(model.jnt_bodyid[j]) for j in hinges}
    assert all(model.body_mass[b] > 0 for b in moving)


def test_primitive_geoms_only(hand: tuple[Hand, mujoco.MjModel]) -> None:
    _, model = hand
    assert model.nmesh == 0
    primitives = {
        int(mujoco.mjtGeom.mjGEOM_PLANE),
        int(mujoco.mjtGeom.mjGEOM_SPHERE),
        int(mujoco.mjtGeom.mjGEOM_CAPSULE),
        int(mujoco.mjtGeom.mjGEOM_ELLIPSOID),
        int(mujoco.mjtGeom.mjGEOM_CYLINDER),
        int(mujoco.mjtGeom.mjGEOM_BOX),
    }
    assert {int(t) for t in model.geom_type} <= primitives


def test_collision_geoms_are_unnamed_and_visual_geoms_do_not_collide(
    hand: tuple[Hand, mujoco.MjModel],
) -> None:
    _, model = hand
    geoms = _hand_collision_geoms(model)
    assert geoms
    assert [mujoco.mj_id2name(model, _OBJ.mjOBJ_GEOM, g) for g in geoms] == [None] * len(geoms)
    visual = [g for g in range(model.ngeom) if int(model.geom_group[g]) == 2]
    assert visual, "a visual class (group 2) as in public models"
    assert all(model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0 for g in visual)


def test_actuators_are_position_servos_one_per_joint(hand: tuple[Hand, mujoco.MjModel]) -> None:
    spec, model = hand
    assert model.nu == spec.hinges
    for a in range(model.nu):
        assert int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT)
        assert int(model.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_FIXED)
        assert int(model.actuator_biastype[a]) == int(mujoco.mjtBias.mjBIAS_AFFINE)
        kp = model.actuator_gainprm[a, 0]
        assert kp > 0 and model.actuator_biasprm[a, 1] == -kp  # <position kp=...>
        assert model.actuator_ctrllimited[a] and model.actuator_forcelimited[a]
    driven = sorted(int(model.actuator_trnid[a, 0]) for a in range(model.nu))
    assert len(set(driven)) == model.nu


def test_keyframe_puts_the_tips_on_the_object(hand: tuple[Hand, mujoco.MjModel]) -> None:
    spec, model = hand
    data = _at_keyframe(model)
    obj = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) in _object_bodies(model)]
    assert len(obj) == 1
    geoms = _hand_collision_geoms(model)
    tips = []
    for name in spec.tips:
        body = mujoco.mj_name2id(model, _OBJ.mjOBJ_BODY, name)
        own = [g for g in geoms if int(model.geom_bodyid[g]) == body]
        assert len(own) == 1, name
        tips.append(own[0])
        assert abs(_distance(model, data, own[0], obj[0])) <= TOUCH, name
    others = [g for g in geoms if g not in tips]
    assert min(_distance(model, data, g, obj[0]) for g in others) >= CLEAR
    # Within the joint ranges, the object's quaternion a unit one.
    for j in range(model.njnt):
        if int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE):
            q = data.qpos[model.jnt_qposadr[j]]
            assert model.jnt_range[j, 0] <= q <= model.jnt_range[j, 1]


def test_keyframe_has_no_other_contacts(hand: tuple[Hand, mujoco.MjModel]) -> None:
    """No self-collision, nothing of the hand on the table; the object only on tips and table."""
    spec, model = hand
    data = _at_keyframe(model)
    inside = _object_bodies(model)
    tip_bodies = {mujoco.mj_name2id(model, _OBJ.mjOBJ_BODY, name) for name in spec.tips}
    for c in data.contact[: data.ncon]:
        bodies = {int(model.geom_bodyid[c.geom1]), int(model.geom_bodyid[c.geom2])}
        assert bodies & inside, f"a contact without the object: {bodies}"
        assert (bodies - inside) <= tip_bodies | {0}
    # And nothing of the hand near the table (the world's geoms).
    world = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) == 0]
    for w in world:
        assert min(_distance(model, data, g, w) for g in _hand_collision_geoms(model)) >= CLEAR


def test_grasp_file_names_exist_in_the_model(hand: tuple[Hand, mujoco.MjModel]) -> None:
    spec, model = hand
    doc = tomllib.loads(spec.grasp.read_text(encoding="utf-8"))
    assert doc["schema"] == "mjtvm.grasp/1"
    assert (spec.grasp.parent / doc["model"]).resolve() == spec.xml.resolve()
    # Top-level keys stay top-level (a key written after [refs] would land inside it).
    assert {"mu", "rvds", "contact_tolerance"} <= set(doc) and "rvds" not in doc["refs"]
    assert mujoco.mj_name2id(model, _OBJ.mjOBJ_BODY, doc["object"]["body"]) >= 0
    assert mujoco.mj_name2id(model, _OBJ.mjOBJ_KEY, doc["configuration"]["keyframe"]) >= 0
    for contact in doc["contacts"]:
        kind, name = ("body", contact["body"]) if "body" in contact else ("geom", contact["geom"])
        obj = _OBJ.mjOBJ_BODY if kind == "body" else _OBJ.mjOBJ_GEOM
        assert mujoco.mj_name2id(model, obj, name) >= 0, name
        assert contact["type"] in {"F", "L", "S", "D"}
    assert {c["body"] for c in doc["contacts"] if "body" in c} == set(spec.tips)
    for key, entry in doc["ranges"].items():
        if key != "*":
            assert mujoco.mj_name2id(model, _OBJ.mjOBJ_JOINT, key) >= 0, key
        if "actuator" in entry:
            assert mujoco.mj_name2id(model, _OBJ.mjOBJ_ACTUATOR, entry["actuator"]) >= 0
            assert entry["speed_limit"] > 0
    rvds = np.array(doc["rvds"], dtype=float)
    assert rvds.shape[1] == 6 and np.all(np.abs(np.linalg.norm(rvds, axis=1) - 1.0) < 1e-12)


# ---------------------------------------------------------------------- through the grasp loader
def test_grasp_jacobians_match_finite_differences(hand: tuple[Hand, mujoco.MjModel]) -> None:
    """Each contact's (3, M) Jacobian = d(finger-fixed contact point)/dq, central differences."""
    spec, _ = hand
    grasp = load_grasp(spec.grasp)
    state = grasp.state()
    fd = contact_jacobians_fd(grasp.model, grasp.data.qpos, state)
    for contact in state.contacts:
        np.testing.assert_allclose(contact.jacobian, fd[contact.name], atol=1e-8, err_msg=contact.name)


def test_grasp_alphas_match_the_cvxpy_reference(hand: tuple[Hand, mujoco.MjModel]) -> None:
    spec, _ = hand
    state = load_grasp(spec.grasp).state()
    result = mjtvm.tvmmp(state)
    alpha, _status = reference_tvmmp(state)
    np.testing.assert_allclose(np.asarray(result.alpha, dtype=float), alpha, rtol=1e-6, atol=1e-8)
    assert result.tvmmp is not None and result.tvmmp > 0  # every grasp holds and moves its object
    # Every alpha certified (the check of `mjtvm solve`'s `certified`), none flagged.
    assert all(c for row in result.certified for c in row)


# ---------------------------------------------------------------------- lifts of the test hands
@pytest.mark.parametrize(("name", "travel"), [("allegro-ik", 0.04), ("gripper3-box", 0.03)])
def test_lift_keeps_the_f_points_on_the_object(name: str, travel: float) -> None:
    """The grasp file's lift (Allegro: 4 cm along -x; gripper: 3 cm up): every F-point stays on
    its object-fixed point within 1e-8 m, every L finger on the surface, and lift states solve."""
    from mjtvm.lift.states import lift_state
    from mjtvm.lift.trajectory import scripted_lift

    lift = scripted_lift(name, num_states=4)
    assert lift.s[-1] == pytest.approx(travel, abs=1e-12)
    model = lift.scenario.model
    data = mujoco.MjData(model)
    ob = model.body(lift.scenario.object_body).id
    start: dict[str, np.ndarray] = {}
    for i in range(lift.num_states):
        data.qpos[:] = lift.qpos[i]
        mujoco.mj_kinematics(model, data)
        rot, pos = data.xmat[ob].reshape(3, 3), data.xpos[ob]
        for g, role, p in zip(lift.geoms, lift.roles, lift.points[i], strict=True):
            local = rot.T @ (p - pos)  # the contact point in the object's frame
            if role == "F":
                start.setdefault(g, local)
                assert np.linalg.norm(local - start[g]) < 1e-8, (name, i, g)
        assert np.all(lift.residual[i] < 1e-8)
        state = lift_state(lift, i)
        assert {c.name.split("#")[0] for c in state.contacts if c.type != "D"} == set(lift.geoms)
