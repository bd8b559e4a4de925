"""Grasp files (``mjtvm.grasp/1``): loading, contact detection within a tolerance, operation
range sources, IK configurations, and one error naming the field for every way a file can be wrong."""

from __future__ import annotations

import copy
import json
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mjtvm.formats.state_file import state_to_dict
from mjtvm.grasp.document.document import GraspError, read_grasp_document
from mjtvm.grasp.resolve.file import load_grasp, shipped_grasps
from mjtvm.model.operation_range import default_operation_range
from tests.support.documents import format_toml

CASE2 = shipped_grasps()["case2"]
MODEL = str(CASE2.parent / "four_finger_hand.xml")


def _doc(**changes: Any) -> dict[str, Any]:
    """Case 2's grasp document with an absolute model path and ``changes`` applied."""
    doc = tomllib.loads(CASE2.read_text(encoding="utf-8"))
    doc["model"] = MODEL
    for key, value in changes.items():
        doc[key] = value
    return doc


def _write(tmp_path: Path, doc: dict[str, Any], suffix: str = ".toml") -> Path:
    path = tmp_path / f"grasp{suffix}"
    path.write_text(format_toml(doc) if suffix == ".toml" else json.dumps(doc), encoding="utf-8")
    return path


def test_toml_and_json_files_give_the_same_state(tmp_path: Path) -> None:
    doc = _doc()
    a = state_to_dict(load_grasp(_write(tmp_path, doc)).state())
    b = state_to_dict(load_grasp(_write(tmp_path, doc, ".json")).state())
    c = state_to_dict(load_grasp("case2").state())
    assert a == b == c


def test_case2_contacts_found_as_expected() -> None:
    grasp = load_grasp("case2")
    rows = grasp.contact_report()
    assert [r["selection"] for r in rows] == [
        f"geom {g!r}" for g in ("palm", "f1_tip", "f2_tip", "f3_tip", "f4_tip")
    ]
    assert all(r["found"] and abs(r["distance"]) < 1e-12 for r in rows)
    assert grasp.joints == tuple(
        f"f{i}_{j}" for i in range(1, 5) for j in ("yaw0", "pitch0", "pitch1", "yaw1")
    )
    np.testing.assert_array_equal(grasp.refs, [[0, 0, -1, 0, 0, 0]])


def test_contact_tolerance_counts_a_small_gap_as_touching() -> None:
    """Object 0.05 mm higher: the fingertips' gaps are at most 0.05 mm; found within 0.1 mm, not within 0.01 mm."""
    lifted = _doc(object={"body": "object", "position": [0.0, 0.0, 0.10005]}, ignore=[{"geom": "palm"}])
    lifted["contacts"] = [c for c in lifted["contacts"] if c["geom"] != "palm"]
    state = load_grasp(lifted).state()
    assert [c.name for c in state.contacts] == ["f1_tip", "f2_tip", "f3_tip", "f4_tip"]
    tight = load_grasp({**lifted, "contact_tolerance": 1e-5})
    with pytest.raises(
        GraspError,
        match=r"contacts\[\d\]: geom 'f\d_tip' does not touch the object: nearest "
        r"distance 0\.0\d+ mm > contact_tolerance 0\.01 mm",
    ):
        tight.state()


def test_unnamed_geoms_are_keyed_by_body_and_index(tmp_path: Path) -> None:
    """The palm of the paper's hand is the world body's first geom: select it by geom_id and by label."""
    grasp = load_grasp("case2")
    palm = grasp.model.geom("palm").id
    by_id = _doc()
    by_id["contacts"][0] = {"geom_id": int(palm), "type": "D"}
    assert state_to_dict(load_grasp(by_id).state()) == state_to_dict(grasp.state())
    by_body = _doc()
    by_body["contacts"][1] = {"body": "f1_link2", "type": "F"}
    names = [c.name for c in load_grasp(by_body).state().contacts]
    assert names == ["palm", "f1_tip", "f2_tip", "f3_tip", "f4_tip"]  # the deepest geom of f1_link2


def test_operation_range_sources() -> None:
    """dcmotor (the model's), datasheet (the RE25 behind 1/40: the same range), actuator box, polygon."""
    dc = load_grasp("case2").operation_ranges["f1_yaw0"]
    sheet = load_grasp(_doc(ranges={"*": {"datasheet": "maxon_re25_20w"}}))
    np.testing.assert_allclose(sheet.operation_ranges["f1_yaw0"].vertices, dc.vertices, atol=1e-8)
    np.testing.assert_allclose(dc.vertices, default_operation_range().vertices, atol=1e-8)
    assert sheet.motors["f1_yaw0"] is not None and sheet.motors["f1_yaw0"].gear == 40
    geared = load_grasp(_doc(ranges={"*": {"datasheet": "maxon_re25_20w", "gear_ratio": 20}}))
    assert geared.operation_ranges["f2_yaw0"].vertices[:, 1].max() == pytest.approx(2 * 25.03, rel=1e-3)
    ranges = {
        "*": {"dcmotor": True},
        "f1_*": {"polygon": [[0, 0], [0.5, 0], [0.5, 3], [0, 4]]},
        "f2_yaw0": {"actuator": True, "speed_limit": 6.0},
    }
    mixed = load_grasp(_doc(ranges=ranges))
    np.testing.assert_array_equal(
        mixed.operation_ranges["f1_pitch1"].vertices, [[0, 0], [0.5, 0], [0.5, 3], [0, 4]]
    )
    box = mixed.operation_ranges["f2_yaw0"].vertices  # gear 40 x saturation 26.3 mN m, 6 rad/s
    np.testing.assert_allclose(box, [[0, 0], [1.052, 0], [1.052, 6.0], [0, 6.0]], atol=1e-9)
    assert isinstance(mixed.motors["f2_yaw0"], str) and mixed.motors["f3_yaw0"] is None
    mixed.state()  # a state with three sources solves


def test_ik_configuration_reaches_the_same_grasp() -> None:
    """IK targets at the fingertips' contacts, from a perturbed start: the same contacts within 1e-6 m."""
    grasp = load_grasp("case2")
    points = {c.name: c.position for c in grasp.state().contacts}
    start = {k: v + 0.05 for k, v in _doc()["configuration"]["qpos"].items()}
    targets = [{"geom": g, "point": points[g].tolist()} for g in ("f1_tip", "f2_tip", "f3_tip", "f4_tip")]
    doc = _doc(configuration={"ik": {"targets": targets, "start": start, "bounds": _doc()["lift"]["bounds"]}})
    solved = load_grasp(doc).state()
    for c in solved.contacts:
        assert np.linalg.norm(c.position - points[c.name]) < 1e-6, c.name


# ------------------------------------------------------------------ errors
def _contacts(*changes: tuple[int, dict[str, Any]]) -> list[dict[str, Any]]:
    contacts = copy.deepcopy(_doc()["contacts"])
    for i, value in changes:
        contacts[i] = value
    return contacts


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        (
            {"object": {"body": "objekt"}},
            r"object\.body: 'objekt' is not a body of the model \(other than the world\) \(did you mean 'object'\?\)",
        ),
        (
            {"contacts": _contacts((1, {"geom": "f1_tipp", "type": "F"}))},
            r"contacts\[1\]\.geom: 'f1_tipp' is not a geom of the model \(did you mean 'f1_tip'\?\)",
        ),
        (
            {"contacts": _contacts((1, {"body": "f9_link2", "type": "F"}))},
            r"contacts\[1\]\.body: 'f9_link2' is not a body",
        ),
        (
            {"contacts": _contacts((1, {"geom_id": 999, "type": "F"}))},
            r"contacts\[1\]\.geom_id: expected a geom id in \[0, ",
        ),
        (
            {"contacts": _contacts((1, {"geom": "object", "type": "F"}))},
            r"contacts\[1\]: geom 'object' belongs to the object",
        ),
        (
            {"contacts": _contacts((1, {"geom": "f1_tip", "type": "X"}))},
            r"contacts\[1\]\.type: expected one of F, L, S, D, got 'X'",
        ),
        (
            {"contacts": _contacts((1, {"geom": "f1_tip", "body": "f1_link2", "type": "F"}))},
            r"contacts\[1\]: expected exactly one of geom, body, geom_id, got 2",
        ),
        (
            {"contacts": _contacts((2, {"geom": "f2_tip", "type": "S"}))},
            r"contacts\[2\]\.slide: required for the S contact",
        ),
        (
            {"contacts": _contacts((1, {"geom": "f1_tip", "type": "F", "slide": [1, 0, 0]}))},
            r"contacts\[1\]\.slide: only an S contact has a slide direction",
        ),
        (
            {"contacts": _contacts((1, {"geom": "f2_tip", "type": "F"}))},
            r"contacts\[2\]: geom 'f2_tip' is already selected",
        ),
        (
            {"contacts": _contacts()[:-1]},
            r"contacts: geom 'f4_tip' touches the object \(distance .* mm\) but no contact selects it",
        ),
        (
            {"contacts": [*_contacts(), {"geom": "f2_link1", "type": "L"}]},
            r"contacts\[5\]: geom 'f2_link1' does not touch the object: nearest distance [\d.]+ mm > contact_tolerance 0\.1 mm",
        ),
        ({"joints": ["f1_yaw0", "f1_knuckle"]}, r"joints\[1\]: 'f1_knuckle' is not a joint of the model"),
        ({"joints": ["object"]}, r"joints\[0\]: joint 'object' is not a hinge or slide joint"),
        (
            {"configuration": {"qpos": {"f1_yaw": 0.1}}},
            r"configuration\.qpos\.f1_yaw: 'f1_yaw' is not a joint of the model \(did you mean 'f1_yaw\d'\?\)",
        ),
        (
            {"configuration": {"keyframe": "home"}},
            r"configuration\.keyframe: 'home' is not a keyframe of the model \(has: none\)",
        ),
        (
            {"configuration": {"keyframe": "home", "qpos": {}}},
            r"configuration: expected exactly one of keyframe, qpos, ik, got 2",
        ),
        (
            {"ranges": {"f1_*": {"dcmotor": True}}},
            r"ranges\.f2_yaw0: no operation range for this joint: add \[ranges\.\"f2_yaw0\"\] \(or a glob pattern, or \"\*\"\)",
        ),
        ({"ranges": {"*": {"actuator": True}}}, r"ranges\.\*\.speed_limit: required with actuator"),
        (
            {"ranges": {"*": {"dcmotor": "f1_m0"}}},
            r"ranges\.\*: joint 'f1_yaw0': actuator 'f1_m0' is not in the model",
        ),
        (
            {"ranges": {"*": {"datasheet": "maxon_re99"}}},
            r"ranges\.\*: joint 'f1_yaw0': no shipped datasheet 'maxon_re99'",
        ),
        (
            {"ranges": {"*": {"polygon": [[0, 0], [1, 0], [0, -1]]}}},
            r"ranges\.\*: joint 'f1_yaw0': polygon: ",
        ),
        (
            {"ranges": {"*": {"datasheet": "maxon_re25_20w", "polygon": [[0, 0]]}}},
            r"ranges\.\*: expected exactly one of",
        ),
        ({"mu": -0.3}, r"mu: expected a number >= 0, got -0\.3"),
        ({"rvds": [[1, 0, 0]]}, r"rvds\[0\]: expected a list of 6 numbers"),
        ({"refs": {"weight": False, "mg": 2.0}}, r"refs\.mg: given with weight = false"),
        ({"friction_edges": 2}, r"friction_edges: expected an integer in \[3, 256\], got 2"),
        ({"contact_tolerance": 0.5}, r"contact_tolerance: expected at most 0\.01 m"),
        ({"schema": "mjtvm.state/1"}, r"schema: expected 'mjtvm\.grasp/1', got 'mjtvm\.state/1'"),
        ({"frobnicate": 1}, r"frobnicate: unknown key \(allowed: "),
        ({"model": "/nonexistent/hand.xml"}, r"model: no such file: '/nonexistent/hand\.xml'"),
        ({"lift": {"direction": [0, 0, 0]}}, r"lift\.direction: expected a non-zero direction"),
        ({"lift": {"bounds": {"f9_yaw0": [0, 1]}}}, r"lift\.bounds\.f9_yaw0: 'f9_yaw0' is not a joint"),
    ],
)
def test_every_wrong_field_is_named(changes: dict[str, Any], match: str) -> None:
    with pytest.raises(GraspError, match=match):
        load_grasp(_doc(**changes)).state()


_SPHERE = {"shape": "sphere", "size": [0.03], "mass": 0.1}


@pytest.mark.parametrize(
    ("changes", "line"),
    [
        (
            {"object": {"body": "f1_tip", **_SPHERE}},
            "grasp: object.body: 'f1_tip' is already a geom of the model: the added object's body, geom and free "
            "joint take this name; choose another",
        ),
        (
            {"object": {"body": "f1_yaw0", **_SPHERE}},
            "grasp: object.body: 'f1_yaw0' is already a joint of the model: the added object's body, geom and free "
            "joint take this name; choose another",
        ),
        (
            {"name": "\ud800"},
            "grasp: name: expected a string of valid Unicode text, got a lone surrogate '\\ud800' in '\\ud800'",
        ),
        (
            {"contacts": _contacts((1, {"geom": "f1_\udc80", "type": "F"}))},
            "grasp: contacts[1].geom: expected a string of valid Unicode text, got a lone surrogate '\\udc80' in "
            "'f1_\\udc80'",
        ),
        (
            {"ranges": {"f\ud800*": {"dcmotor": True}}},
            "grasp: ranges.'f\\ud800*': expected a key of valid Unicode text, got a lone surrogate '\\ud800' in "
            "'f\\ud800*'",
        ),
        (
            {"object": {"body": "ob\x00ject"}},
            "grasp: object.body: expected a string without NUL characters, got 'ob\\x00ject'",
        ),
        ({"fro\nbnicate": 1}, "grasp: 'fro\\nbnicate': unknown key (allowed: "),
        (
            {"lift": {"bounds": {"f1\nyaw0": [0, 1]}}},
            "grasp: lift.bounds.'f1\\nyaw0': 'f1\\nyaw0' is not a joint",
        ),
    ],
)
def test_names_and_keys_stay_on_one_line(changes: dict[str, Any], line: str) -> None:
    """An added object named like a geom or joint, a lone surrogate or NUL in a string or key, a
    key with a newline: one error naming the field, on one line (``repr`` of the name)."""
    with pytest.raises(GraspError) as info:
        load_grasp(_doc(**changes)).state()
    message = str(info.value)
    assert message.startswith(line), message
    assert message.isprintable()  # no newline, no lone surrogate: one line that any stream encodes


@pytest.mark.parametrize(
    ("changes", "line"),
    [
        ({"name": "\ud800"}, "name: expected a string of valid Unicode text, got a lone surrogate '\\ud800'"),
        ({"fro\nbnicate": 1}, "'fro\\nbnicate': unknown key (allowed: "),
        ({"object": {"body": "f1_tip", **_SPHERE}}, "object.body: 'f1_tip' is already a geom of the model"),
    ],
)
def test_grasp_file_errors_are_one_line_on_the_command_line(
    changes: dict[str, Any], line: str, tmp_path: Path
) -> None:
    """The same errors from a JSON grasp file through ``mjtvm export-state``: exit 2, one line."""
    import subprocess
    import sys

    path = _write(tmp_path, _doc(**changes), ".json")
    proc = subprocess.run(
        [sys.executable, "-m", "mjtvm.cli", "export-state", str(path)], capture_output=True, check=False
    )
    assert proc.returncode == 2
    assert proc.stdout == b""
    err = proc.stderr.decode("utf-8")
    assert err.startswith(f"error: {path}: {line}") and err.count("\n") == 1, err


def test_a_datasheet_file_is_read_up_to_a_bound(tmp_path: Path) -> None:
    """A datasheet path that is a device (or a huge file) is refused after 64 MiB, not read forever."""
    zero = tmp_path / "zero.json"
    zero.symlink_to("/dev/zero")
    with pytest.raises(GraspError) as info:
        load_grasp(_doc(ranges={"*": {"datasheet": str(zero)}}))
    assert str(info.value) == (
        f"grasp: ranges.*: joint 'f1_yaw0': datasheet {str(zero)!r}: larger than 67108864 bytes: not a datasheet"
    )
    folder = tmp_path / "folder.json"
    folder.mkdir()
    with pytest.raises(
        GraspError, match=r"ranges\.\*: joint 'f1_yaw0': cannot read datasheet .*: Is a directory$"
    ):
        load_grasp(_doc(ranges={"*": {"datasheet": str(folder)}}))


def test_unreachable_ik_target_names_the_target() -> None:
    targets = [
        {"geom": "f1_tip", "point": [0.5, 0.0, 0.1]}
    ]  # 0.6 m from finger 1's base, which reaches 0.2 m
    doc = _doc(configuration={"ik": {"targets": targets}}, contacts=[{"geom": "f1_tip", "type": "F"}])
    with pytest.raises(
        GraspError,
        match=r"configuration\.ik\.targets\[0\]: unreachable: residual [\d.]+ mm after \d+ iterations",
    ):
        load_grasp(doc)
    with pytest.raises(GraspError, match=r"configuration\.ik\.targets\[0\]\.site: 'f1_site' is not a site"):
        load_grasp(_doc(configuration={"ik": {"targets": [{"site": "f1_site", "point": [0, 0, 0]}]}}))


def test_file_level_errors(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("schema = \n", encoding="utf-8")
    with pytest.raises(GraspError, match=r"bad\.toml: malformed TOML"):
        read_grasp_document(bad)
    latin = tmp_path / "latin.json"
    latin.write_bytes(b'{"name": "caf\xe9"}')
    with pytest.raises(GraspError, match=r"not UTF-8 text: byte 0xe9 at offset 13"):
        read_grasp_document(latin)
    with pytest.raises(GraspError, match=r"expected a \.toml or \.json file, got '\.yaml'"):
        read_grasp_document(tmp_path / "x.yaml")
    with pytest.raises(GraspError, match=r"cannot read the grasp file"):
        read_grasp_document(tmp_path / "missing.toml")
    with pytest.raises(GraspError, match=r"case9: no such grasp file, and not a shipped grasp \(shipped: "):
        load_grasp("case9")
    relative = _doc(model="four_finger_hand.xml")
    path = _write(tmp_path, relative)
    with pytest.raises(GraspError, match=r"model: no such file: '.*/four_finger_hand\.xml'"):
        load_grasp(path)  # relative to the grasp file, not to the working directory
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody><body><geom type='sphere'/></body></mujoco>", encoding="utf-8")
    with pytest.raises(GraspError, match=r"model: MuJoCo cannot load"):
        load_grasp(_doc(model=str(broken)))


# ------------------------------------------------------------------ a hand file without an object
PINCHER = """<mujoco model="pincher">
  <compiler angle="radian"/>
  <default>
    <default class="pincher">
      <joint axis="0 1 0" range="-1.6 1.6" damping="0.1"/>
      <position kp="5" forcerange="-0.8 0.8" ctrlrange="-1.6 1.6"/>
      <default class="visual"><geom contype="0" conaffinity="0" group="2"/></default>
      <default class="collision"><geom group="3"/></default>
    </default>
  </default>
  <worldbody>
    <geom class="visual" type="box" size="0.1 0.05 0.005" pos="0 0 -0.005"/>
    <body name="left" pos="-0.08 0 0" childclass="pincher">
      <joint name="l0"/>
      <geom class="collision" type="capsule" fromto="0 0 0 0 0 0.08" size="0.008" mass="0.05"/>
      <body name="left_tip" pos="0 0 0.08">
        <joint name="l1"/>
        <geom class="collision" type="capsule" fromto="0 0 0 0 0 0.06" size="0.008" mass="0.04"/>
        <geom class="collision" type="box" pos="0 0 0.066" size="0.006 0.01 0.006" mass="0.01"/>
      </body>
    </body>
    <body name="right" pos="0.08 0 0" childclass="pincher">
      <joint name="r0"/>
      <geom class="collision" type="capsule" fromto="0 0 0 0 0 0.08" size="0.008" mass="0.05"/>
      <body name="right_tip" pos="0 0 0.08">
        <joint name="r1"/>
        <geom class="collision" type="capsule" fromto="0 0 0 0 0 0.06" size="0.008" mass="0.04"/>
        <geom class="collision" type="ellipsoid" pos="0 0 0.066" size="0.006 0.01 0.008" mass="0.01"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position class="pincher" joint="l0"/><position class="pincher" joint="l1"/>
    <position class="pincher" joint="r0"/><position class="pincher" joint="r1"/>
  </actuator>
</mujoco>
"""


def pincher_grasp(tmp_path: Path) -> dict[str, Any]:
    (tmp_path / "pincher.xml").write_text(PINCHER, encoding="utf-8")
    return {
        "schema": "mjtvm.grasp/1",
        "model": "pincher.xml",
        "object": {
            "body": "can",
            "shape": "cylinder",
            "size": [0.03, 0.04],
            "mass": 0.1,
            "position": [0, 0, 0.12],
        },
        "configuration": {
            "ik": {
                "targets": [
                    {"geom": "left_tip/geom1", "point": [-0.03, 0.0, 0.12]},
                    {"geom": "right_tip/geom1", "point": [0.03, 0.0, 0.12]},
                ],
                "start": {"l0": 0.3, "l1": 0.5, "r0": -0.3, "r1": -0.5},
            }
        },
        "mu": 0.8,
        "contacts": [{"body": "left_tip", "type": "F"}, {"body": "right_tip", "type": "F"}],
        "rvds": [[0, 0, 1, 0, 0, 0], [0, 0, -1, 0, 0, 0], [1, 0, 0, 0, 0, 0]],
        "ranges": {"*": {"actuator": True, "speed_limit": 5.0}},
    }


def test_a_hand_file_without_object_box_and_ellipsoid_tips(tmp_path: Path) -> None:
    """The grasp adds a cylinder to a hand-only MJCF (position servos, unnamed geoms) and the IK
    brings a box tip and an ellipsoid tip onto its sides; the state has two F contacts on them."""
    path = _write(tmp_path, pincher_grasp(tmp_path))
    grasp = load_grasp(path)
    assert grasp.model.nq == 4 + 7  # the object's free joint added
    state = grasp.state()
    assert [c.name for c in state.contacts] == ["left_tip/geom1", "right_tip/geom1"]
    # into the can, from the left and the right (exact normals at contact points that the
    # iterative collision, run to 1e-12 m, places within about 1 um of the tangency)
    np.testing.assert_allclose(state.contacts[0].normal, [1, 0, 0], atol=1e-4)
    np.testing.assert_allclose(state.contacts[1].normal, [-1, 0, 0], atol=1e-4)
    for c in state.contacts:
        assert abs(c.position[2] - 0.12) < 1e-6
    np.testing.assert_allclose(state.refs, [[0, 0, -0.1 * 9.81, 0, 0, 0]], rtol=1e-12)
    assert grasp.joints == ("l0", "l1", "r0", "r1")
    # the box gear x forcerange by the speed limit, less the joint's damping 0.1 N m s/rad:
    # (0.8, 5) -> (0.8 - 0.1 x 5, 5) = (0.3, 5) (OperationRange.with_losses)
    np.testing.assert_allclose(grasp.operation_ranges["l0"].vertices, [[0, 0], [0.8, 0], [0.3, 5], [0, 5]])
    raw = load_grasp(_write(tmp_path, {**pincher_grasp(tmp_path), "joint_losses": "ignore"}))
    np.testing.assert_allclose(raw.operation_ranges["l0"].vertices, [[0, 0], [0.8, 0], [0.8, 5], [0, 5]])
    # No TVMMP here: two point contacts cannot resist a moment about the line through them, and
    # MuJoCo's contact points are 1e-11 m off the plane of the fingers, so the weight has a
    # 1e-13 N m moment about that line: infeasible in exact arithmetic (the scale-invariant
    # LPs say so; an unscaled solver accepts it within its tolerance).
    assert grasp.spec().compile().nq == grasp.model.nq


def test_added_object_and_supports_errors(tmp_path: Path) -> None:
    doc = pincher_grasp(tmp_path)
    doc["object"] = {"body": "left", "shape": "sphere", "size": [0.03], "mass": 0.1}
    with pytest.raises(GraspError, match=r"object\.body: 'left' is already a body of the model: drop shape"):
        load_grasp(_write(tmp_path, doc))
    doc["object"] = {"body": "can", "shape": "cone", "size": [0.03], "mass": 0.1}
    with pytest.raises(
        GraspError, match=r"object\.shape: expected one of sphere, capsule, ellipsoid, cylinder, box"
    ):
        load_grasp(_write(tmp_path, doc))
    doc["object"] = {"body": "can", "shape": "box", "size": [0.03], "mass": 0.1}
    with pytest.raises(GraspError, match=r"object\.size: expected 3 numbers \(MuJoCo's size of a box, m\)"):
        load_grasp(_write(tmp_path, doc))
    doc = pincher_grasp(tmp_path)
    doc["supports"] = [
        {"name": "table", "shape": "plane", "size": [0.2, 0.2, 0.01], "position": [0, 0, 0.06]}
    ]
    doc["contacts"].append({"geom": "table", "type": "D"})
    with pytest.raises(
        GraspError, match=r"contacts\[2\]: geom 'table' does not touch the object: nearest distance 20 mm"
    ):
        load_grasp(_write(tmp_path, doc)).state()
    doc["supports"][0]["position"] = [0, 0, 0.08]  # the can's bottom face
    state = load_grasp(_write(tmp_path, doc)).state()
    # a flat face on a plane: MuJoCo gives several contact points, all D (one per finger body for F)
    assert [c.type for c in state.contacts] == ["D"] * (len(state.contacts) - 2) + ["F", "F"]
    assert {c.name.split("#")[0] for c in state.contacts if c.type == "D"} == {"table"}


@pytest.mark.parametrize(
    ("equality", "name"),
    [
        ('<joint name="mirror" joint1="l0" joint2="r0"/>', "mirror"),
        ('<connect name="bar" body1="left_tip" body2="right_tip" anchor="0 0 0.03"/>', "bar"),
    ],
)
def test_a_violated_equality_is_refused(tmp_path: Path, equality: str, name: str) -> None:
    """A joint coupling or a closed chain that joint values given in the file do not satisfy (a
    connect's second anchor is where the bodies were at qpos0): refused naming the constraint
    and its residual, never solved as if it held."""
    doc = pincher_grasp(tmp_path)
    doc["configuration"] = {"qpos": {"l0": 0.3, "l1": 0.5, "r0": -0.3, "r1": -0.5}}
    (tmp_path / "pincher.xml").write_text(
        PINCHER.replace("</mujoco>", f"<equality>{equality}</equality></mujoco>")
    )
    with pytest.raises(
        GraspError,
        match=rf"configuration: equality '{name}': is violated by [0-9.]+ \(m or rad\) at the configuration",
    ):
        load_grasp(_write(tmp_path, doc))


def test_contact_preload_reaches_the_state() -> None:
    """A contact's ``preload`` (N) becomes its state contacts' minimum normal force; refused on D."""
    contacts = _doc()["contacts"]
    li = next(i for i, c in enumerate(contacts) if c["type"] == "L")
    contacts[li] = {**contacts[li], "preload": 0.25}
    grasp = load_grasp(_doc(contacts=contacts))
    label = next(iter(grasp.selections[li][1]))
    assert dict(grasp.preloads) == {label: 0.25}
    pre = {c.name.split("#")[0]: c.preload for c in grasp.state().contacts}
    assert pre[label] == 0.25 and sum(pre.values()) == 0.25
    assert {c.name.split("#")[0]: c.preload for c in grasp.state(preloads={label: 0.5}).contacts}[
        label
    ] == 0.5
    di = next((i for i, c in enumerate(contacts) if c["type"] == "D"), None)
    bad = copy.deepcopy(contacts)
    bad[li] = {**bad[li], "preload": -1.0}
    with pytest.raises(GraspError, match=rf"contacts\[{li}\]\.preload"):
        load_grasp(_doc(contacts=bad))
    if di is not None:
        bad = copy.deepcopy(contacts)
        bad[di] = {**bad[di], "preload": 1.0}
        with pytest.raises(GraspError, match="D contact carries no force"):
            load_grasp(_doc(contacts=bad))
