"""A hand on a free or mocap base, posed by ``configuration.qpos`` or ``configuration.base``.

The test hands are the shipped three-finger gripper (``models/gripper3``) with its palm and
its table put on one body ``base``: a body on a free joint, or a mocap body. At the identity
pose the grasp state is the shipped grasp's; moved rigidly with its object (and gravity, and
the friction pyramids' tangents, which the state fixes by the world axes), its Jacobians,
normals and points are the moved ones and its alphas are unchanged when the RVDS is expressed
in the moved frame.
"""

from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pytest
from numpy.typing import NDArray

import mjtvm
from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.resolve.file import load_grasp
from mjtvm.grasp.resolve.loaded import Grasp
from mjtvm.model.contacts import Contact, tangent_basis
from mjtvm.model.state import GraspState

GRIPPER = Path(__file__).resolve().parents[3] / "models" / "gripper3"
HINGES = [f"{f}j{i}" for f in ("f1", "f2", "fm") for i in (1, 2, 3)]
KEY = [0.0970617, 0.4752573, 0.5061607, 0.0970617, 0.4752573, 0.5061607, 0.0092417, 0.6041089, 0.6829294]
OBJECT = [0.0, 0.0, 0.03, 1.0, 0.0, 0.0, 0.0]  # the keyframe's object pose

# A rigid motion: a turn of 0.7 rad about a skew axis, then a shift (m).
AXIS = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
ANGLE = 0.7
SHIFT = np.array([0.3, -0.1, 0.25])


def _quat_mul(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, a, b)
    return out


QUAT = np.concatenate([[np.cos(ANGLE / 2)], np.sin(ANGLE / 2) * AXIS])
ROT = np.zeros(9)
mujoco.mju_quat2Mat(ROT, QUAT)
R = ROT.reshape(3, 3)


def _numbers(values: Any) -> str:
    return " ".join(repr(float(v)) for v in values)


def based_gripper(kind: str, folder: Path, *, moved: bool = False) -> Path:
    """gripper3.xml with the palm on a body ``base`` (``kind``: ``free`` or ``mocap``), written
    into ``folder``; the free base's keyframe starts with its pose. ``moved``: the table (a world
    geom) and gravity turned and shifted by the rigid motion (``R``, ``SHIFT``)."""
    text = (GRIPPER / "gripper3.xml").read_text(encoding="utf-8")
    head = (
        '<body name="base"><freejoint name="base"/>' if kind == "free" else '<body name="base" mocap="true">'
    )
    edits = [
        ("    <!-- Pointing down", f"    {head}\n    <!-- Pointing down"),
        ("    <!-- The object: a 0.2 kg box", "    </body>\n    <!-- The object: a 0.2 kg box"),
    ]
    if kind == "free":
        edits.append(('<key name="grasp" qpos="', '<key name="grasp" qpos="0 0 0 1 0 0 0 '))
    if moved:
        table = R @ np.array([0.0, 0.0, -0.01]) + SHIFT
        edits += [
            ("<option ", f'<option gravity="{_numbers(R @ np.array([0.0, 0.0, -9.81]))}" '),
            (
                'size="0.3 0.3 0.01" pos="0 0 -0.01"',
                f'size="0.3 0.3 0.01" pos="{_numbers(table)}" quat="{_numbers(QUAT)}"',
            ),
        ]
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    path = folder / f"gripper3_{kind}.xml"
    path.write_text(text, encoding="utf-8")
    return path


def _doc(model: Path, configuration: dict[str, Any], obj: list[float] | None = None) -> dict[str, Any]:
    doc = tomllib.loads((GRIPPER / "gripper3-box.toml").read_text(encoding="utf-8"))
    doc["model"] = str(model)
    doc["configuration"] = configuration
    if obj is not None:
        doc["object"] = {"body": "object", "position": obj[:3], "quaternion": obj[3:]}
    return doc


@pytest.fixture(scope="module")
def shipped() -> Grasp:
    return load_grasp(GRIPPER / "gripper3-box.toml")


def _assert_same_state(a: GraspState, b: GraspState) -> None:
    assert a.joint_names == b.joint_names
    np.testing.assert_allclose(b.gravity_torque, a.gravity_torque, rtol=0, atol=1e-12)
    np.testing.assert_allclose(b.refs, a.refs, rtol=0, atol=1e-12)
    assert [c.name for c in a.contacts] == [c.name for c in b.contacts]
    for ca, cb in zip(a.contacts, b.contacts, strict=True):
        np.testing.assert_allclose(cb.jacobian, ca.jacobian, rtol=0, atol=1e-12)
        np.testing.assert_allclose(cb.normal, ca.normal, rtol=0, atol=1e-12)
        np.testing.assert_allclose(cb.position, ca.position, rtol=0, atol=1e-12)


def _alphas(state: GraspState) -> NDArray[np.float64]:
    return np.asarray(mjtvm.tvmmp(state).alpha, dtype=float)


@pytest.mark.parametrize(
    ("kind", "configuration"),
    [
        ("free", {"qpos": {**dict(zip(HINGES, KEY, strict=True)), "base": [0, 0, 0, 1, 0, 0, 0]}}),
        ("free", {"keyframe": "grasp"}),
        ("free", {"keyframe": "grasp", "base": {"body": "base", "position": [0, 0, 0]}}),
        ("mocap", {"keyframe": "grasp"}),
        (
            "mocap",
            {"qpos": dict(zip(HINGES, KEY, strict=True)), "base": {"body": "base", "position": [0, 0, 0]}},
        ),
    ],
)
def test_a_based_hand_at_the_identity_is_the_fixed_hand(
    shipped: Grasp, tmp_path: Path, kind: str, configuration: dict[str, Any]
) -> None:
    grasp = load_grasp(_doc(based_gripper(kind, tmp_path), configuration, OBJECT))
    _assert_same_state(shipped.state(), grasp.state())
    np.testing.assert_allclose(_alphas(grasp.state()), _alphas(shipped.state()), rtol=0, atol=1e-12)


def _moved_configuration(kind: str, how: str) -> dict[str, Any]:
    pose = [*SHIFT.tolist(), *QUAT.tolist()]
    if how == "qpos":
        return {"qpos": {**dict(zip(HINGES, KEY, strict=True)), "base": pose}}
    return {"keyframe": "grasp", "base": {"body": "base", "position": pose[:3], "quaternion": pose[3:]}}


def _moved_object() -> list[float]:
    return [*(R @ np.array(OBJECT[:3]) + SHIFT).tolist(), *_quat_mul(QUAT, np.array(OBJECT[3:])).tolist()]


def _matched(moved: GraspState, reference: GraspState) -> list[tuple[Contact, Contact]]:
    """Each contact of ``moved`` with the contact of ``reference`` whose moved point is nearest."""
    assert len(moved.contacts) == len(reference.contacts)
    out = []
    for c in moved.contacts:
        gaps = [np.linalg.norm(R @ r.position + SHIFT - c.position) for r in reference.contacts]
        assert sorted(gaps)[1] > 1e-3  # one clear match
        out.append((c, reference.contacts[int(np.argmin(gaps))]))
    order = {id(r): i for i, r in enumerate(reference.contacts)}
    return sorted(out, key=lambda pair: order[id(pair[1])])


def _with_tangents(
    state: GraspState, pairs: list[tuple[Contact, Contact]], rotation: NDArray[np.float64]
) -> GraspState:
    """``state``'s contacts of ``pairs``, in the reference's order, each with its pyramid tangent
    the reference's default tangent rotated."""
    return state.with_(
        contacts=tuple(replace(c, tangent=rotation @ tangent_basis(ref.normal)[0]) for c, ref in pairs)
    )


@pytest.mark.parametrize(("kind", "how"), [("free", "qpos"), ("free", "base"), ("mocap", "base")])
def test_moving_hand_and_object_together_moves_the_state_and_keeps_the_alphas(
    shipped: Grasp, tmp_path: Path, kind: str, how: str
) -> None:
    grasp = load_grasp(
        _doc(based_gripper(kind, tmp_path, moved=True), _moved_configuration(kind, how), _moved_object())
    )
    reference = shipped.state()
    rvds = np.asarray(shipped.rvds, dtype=float)
    moved = grasp.state(rvds=np.hstack([rvds[:, :3] @ R.T, rvds[:, 3:] @ R.T]))
    # the hand did not move relative to its base: the same joints at the keyframe's values
    adr = [int(grasp.model.jnt_qposadr[grasp.model.joint(j).id]) for j in HINGES]
    np.testing.assert_array_equal(grasp.data.qpos[adr], KEY)
    np.testing.assert_allclose(moved.object_position, R @ reference.object_position + SHIFT, atol=1e-12)
    np.testing.assert_allclose(moved.refs[:, :3], reference.refs[:, :3] @ R.T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(moved.refs[:, 3:], reference.refs[:, 3:] @ R.T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(moved.gravity_torque, reference.gravity_torque, rtol=0, atol=1e-12)
    # MuJoCo's box-box manifold lists the box's four corners on the table in another order
    pairs = _matched(moved, reference)
    for cm, cr in pairs:
        assert cm.name.split("#")[0] == cr.name.split("#")[0]
        np.testing.assert_allclose(cm.jacobian, R @ cr.jacobian, rtol=0, atol=1e-12)
        np.testing.assert_allclose(cm.normal, R @ cr.normal, rtol=0, atol=1e-12)
        np.testing.assert_allclose(cm.position, R @ cr.position + SHIFT, rtol=0, atol=1e-12)
    alphas = _alphas(_with_tangents(reference, [(c, c) for c in reference.contacts], np.eye(3)))
    assert np.count_nonzero(alphas > 0.1) >= 3  # the grasp moves its box: the test compares real motions
    # the LPs' coefficients are the rotated ones, equal up to round-off: measured 1.8e-12 relative
    np.testing.assert_allclose(_alphas(_with_tangents(moved, pairs, R)), alphas, rtol=1e-11, atol=0)


@pytest.mark.parametrize("how", ["base", "keyframe"])
def test_a_posed_mocap_base_is_the_pose_of_every_later_mjdata(tmp_path: Path, how: str) -> None:
    """The lift's states and a replay make their own mjData from the model and the qpos."""
    base = {"body": "base", "position": SHIFT.tolist(), "quaternion": QUAT.tolist()}
    xml = based_gripper("mocap", tmp_path, moved=True)
    if how == "keyframe":  # the pose in the keyframe's mpos and mquat instead
        text = xml.read_text(encoding="utf-8").replace(
            '<key name="grasp" ', f'<key name="grasp" mpos="{_numbers(SHIFT)}" mquat="{_numbers(QUAT)}" '
        )
        xml.write_text(text, encoding="utf-8")
    configuration = {"keyframe": "grasp", **({"base": base} if how == "base" else {})}
    grasp = load_grasp(_doc(xml, configuration, _moved_object()))
    np.testing.assert_allclose(grasp.data.xpos[grasp.model.body("base").id], SHIFT, rtol=0, atol=1e-15)
    later = mujoco.MjData(grasp.model)
    later.qpos[:] = grasp.data.qpos
    mujoco.mj_forward(grasp.model, later)
    np.testing.assert_array_equal(later.xpos, grasp.data.xpos)
    np.testing.assert_array_equal(later.xquat, grasp.data.xquat)


def _ik(base: dict[str, Any] | None) -> dict[str, Any]:
    opened = [q - 0.05 for q in KEY]  # each finger a little open: IK closes it onto the box
    tips = [{"geom": f"{f}_distal/geom1"} for f in ("f1", "f2", "fm")]
    ik = {"ik": {"targets": tips, "start": dict(zip(HINGES, opened, strict=True)), "tolerance": 1e-7}}
    return ik if base is None else {**ik, "base": base}


@pytest.mark.parametrize("kind", ["free", "mocap"])
def test_ik_solves_the_fingers_of_a_posed_base_and_leaves_the_base(tmp_path: Path, kind: str) -> None:
    fixed = load_grasp(_doc(GRIPPER / "gripper3.xml", _ik(None), OBJECT))
    base = {"body": "base", "position": SHIFT.tolist(), "quaternion": QUAT.tolist()}
    grasp = load_grasp(_doc(based_gripper(kind, tmp_path, moved=True), _ik(base), _moved_object()))
    adr = [int(grasp.model.jnt_qposadr[grasp.model.joint(j).id]) for j in HINGES]
    ref = [int(fixed.model.jnt_qposadr[fixed.model.joint(j).id]) for j in HINGES]
    assert np.max(np.abs(fixed.data.qpos[ref] - (np.array(KEY) - 0.05))) > 0.01  # the IK moved the fingers
    np.testing.assert_allclose(grasp.data.qpos[adr], fixed.data.qpos[ref], rtol=0, atol=1e-9)
    b = grasp.model.body("base").id
    np.testing.assert_allclose(grasp.data.xpos[b], SHIFT, rtol=0, atol=1e-15)
    np.testing.assert_allclose(grasp.data.xquat[b], QUAT, rtol=0, atol=1e-15)


def _errors_doc(model: Path, configuration: dict[str, Any]) -> dict[str, Any]:
    return _doc(model, configuration, OBJECT)


POSE = [0, 0, 0, 1, 0, 0, 0]


@pytest.mark.parametrize(
    ("kind", "configuration", "match"),
    [
        (
            "free",
            {"qpos": {"base": 0.1}},
            r"configuration\.qpos\.base: joint 'base' is a free joint: expected its 7 numbers "
            r"\[x, y, z, qw, qx, qy, qz\].*configuration\.base.*configuration\.keyframe",
        ),
        (
            "free",
            {"qpos": {"base": [0, 0, 0, 1, 0, 0]}},
            r"configuration\.qpos\.base: expected a free joint's 7 numbers .*got a list of 6",
        ),
        (
            "free",
            {"qpos": {"base": [0, 0, 0, 1, 0, 0, 1]}},
            r"configuration\.qpos\.base: expected a unit quaternion \(w, x, y, z\) in numbers 4 to 7, got norm 1\.41421",
        ),
        (
            "free",
            {"qpos": {"f1j1": POSE}},
            r"configuration\.qpos\.f1j1: joint 'f1j1' is a hinge or slide joint: expected one number, got a list",
        ),
        (
            "free",
            {"qpos": {"bsae": POSE}},
            r"configuration\.qpos\.bsae: 'bsae' is not a joint of the model \(did you mean 'base'\?\)",
        ),
        (
            "free",
            {"ik": {"targets": [{"geom": "f1_distal/geom1"}], "start": {"base": 0.0}}},
            r"configuration\.ik\.start\.base: joint 'base' is a free joint: .*configuration\.base",
        ),
        (
            "mocap",
            {"keyframe": "grasp", "base": {"body": "bsae", "position": [0, 0, 0]}},
            r"configuration\.base\.body: 'bsae' is not a body of the model \(did you mean 'base'\?\)",
        ),
        (
            "mocap",
            {"keyframe": "grasp", "base": {"body": "palm", "position": [0, 0, 0]}},
            r"configuration\.base\.body: body 'palm' is neither a mocap body nor on a free joint: .*"
            r"configuration\.qpos.*configuration\.keyframe",
        ),
        (
            "mocap",
            {"keyframe": "grasp", "base": {"body": "base"}},
            r"configuration\.base: expected position, quaternion or both",
        ),
        (
            "mocap",
            {"keyframe": "grasp", "base": {"body": "base", "quaternion": [1, 0, 0, 0.1]}},
            r"configuration\.base\.quaternion: expected a unit quaternion \(w, x, y, z\), got norm 1\.00499",
        ),
        (
            "mocap",
            {"keyframe": "grasp", "base": {"body": "base", "position": [0, 0]}},
            r"configuration\.base\.position: expected a list of 3 numbers, got a list of 2",
        ),
    ],
)
def test_a_base_or_free_joint_given_wrong_is_one_line_naming_the_field(
    tmp_path: Path, kind: str, configuration: dict[str, Any], match: str
) -> None:
    with pytest.raises(GraspError, match=match) as info:
        load_grasp(_errors_doc(based_gripper(kind, tmp_path), configuration))
    assert "\n" not in str(info.value)


def test_a_free_joint_given_one_number_is_exit_2_and_one_line_on_the_command_line(tmp_path: Path) -> None:
    import json
    import subprocess
    import sys

    path = tmp_path / "based.json"
    doc = _errors_doc(based_gripper("free", tmp_path), {"qpos": {"base": 0.1}})
    path.write_text(json.dumps(doc), encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, "-m", "mjtvm.cli", "export-state", str(path)], capture_output=True, check=False
    )
    assert proc.returncode == 2 and proc.stdout == b""
    err = proc.stderr.decode("utf-8")
    assert err.startswith(f"error: {path}: configuration.qpos.base: joint 'base' is a free joint"), err
    assert err.count("\n") == 1, err


def test_a_ball_joint_in_qpos_points_to_the_keyframe(tmp_path: Path) -> None:
    path = based_gripper("free", tmp_path)
    text = path.read_text(encoding="utf-8").replace(
        '<freejoint name="base"/>', '<joint name="base" type="ball"/>'
    )
    path.write_text(text.replace('qpos="0 0 0 1 0 0 0 ', 'qpos="1 0 0 0 '), encoding="utf-8")
    with pytest.raises(
        GraspError, match=r"configuration\.qpos\.base: joint 'base' is a ball joint: set it from a keyframe"
    ):
        load_grasp(_errors_doc(path, {"qpos": {"base": 0.1}}))


@pytest.mark.parametrize(("kind", "what"), [("free", "on a free joint"), ("mocap", "a mocap body")])
def test_the_physics_check_refuses_a_hand_on_a_floating_base(tmp_path: Path, kind: str, what: str) -> None:
    """The rollouts rebuild the model from its file and hold no base: a free base would fall
    and a mocap pose be lost, so alpha_sim would be another hand's."""
    from mjtvm.errors import ModelError
    from mjtvm.physics.check import motor_model

    grasp = load_grasp(_doc(based_gripper(kind, tmp_path), {"keyframe": "grasp"}, OBJECT))
    with pytest.raises(
        ModelError, match=rf"^body 'base': the hand's base is {what}: the physics check is for fixed-base"
    ):
        motor_model(grasp)
