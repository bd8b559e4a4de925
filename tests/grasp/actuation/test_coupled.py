"""Grasp files of hands with coupled joints: the Shadow hand's tendon-driven distal
joints and the Robotiq 2F-85's linkages. Their transmissions, their operation ranges keyed by
actuator (values derived by hand from the MJCF), the joints a linkage adds, and the errors."""

from __future__ import annotations

import copy
import csv
import json
import subprocess
import sys
import tomllib
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pytest

from mjtvm import OperationRange, tvmmp
from mjtvm.formats.state_file import parse_state, state_to_dict
from mjtvm.grasp.actuation.ranges import actuator_ranges
from mjtvm.grasp.actuation.transmission import equality_residual, model_transmission
from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.resolve.file import load_grasp
from mjtvm.grasp.resolve.ik import IkTarget, solve_ik
from oracles.reference import reference_tvmmp

MODELS = Path(__file__).resolve().parents[3] / "models"
SHADOW = MODELS / "shadow_hand" / "shadow_hand-sphere.toml"  # the sum tendon alone: not held
SHADOW_COUPLED = MODELS / "shadow_hand" / "shadow_hand_coupled-sphere.toml"  # J1 = J2 too
F85 = MODELS / "robotiq_2f85" / "robotiq_2f85-sphere.toml"


def _f85_without_horizon(folder: Path) -> Path:
    """The 2F-85 grasp with a travel horizon of 0 (only joints on a limit held): its couplers
    reach their stop after 0.99999 mm of lift, inside the default 1 mm horizon, which makes its
    alpha along the lift 0 (docs/own-hand.md); the speed checks below are of the lift itself."""
    text = F85.read_text(encoding="utf-8").replace(
        'model = "robotiq_2f85.xml"',
        f"model = {json.dumps(str(F85.parent / 'robotiq_2f85.xml'))}\njoint_limits = {{ horizon = 0.0 }}",
    )
    out = folder / "f85-no-horizon.toml"
    out.write_text(text, encoding="utf-8")
    return out


def _doc(path: Path) -> dict[str, Any]:
    doc = tomllib.loads(path.read_text(encoding="utf-8"))
    doc["model"] = str(path.parent / doc["model"])
    return doc


def test_shadow_grasp_is_driven_by_its_actuators() -> None:
    """13 joints, 11 actuators (two on the tendons J2 + J1), no constraint; each range the box
    |u| <= forcerange - frictionloss (1 - 0.01 N m; the thumb base 3 - 0.01, THJ4 2 - 0.01),
    |s| <= 2 rad/s; damping 0.05 N m s/rad on every joint in the transmission."""
    grasp = load_grasp(SHADOW)
    t = grasp.transmission
    assert t is not None
    assert len(grasp.joints) == 13 and len(t.actuator_names) == 11 and t.constraint_names == ()
    assert set(grasp.operation_ranges) == set(t.actuator_names)
    torque = {name: 0.99 for name in t.actuator_names} | {"rh_A_THJ5": 2.99, "rh_A_THJ4": 1.99}
    for name, rng in grasp.operation_ranges.items():
        np.testing.assert_allclose(
            rng.vertices, [[0, 0], [torque[name], 0], [torque[name], 2.0], [0, 2.0]], rtol=1e-15
        )
    np.testing.assert_array_equal(t.joint_damping, np.full(13, 0.05))
    assert [c.split("#")[0] for c in grasp.contact_types] == ["ff_distal", "mf_distal", "th_distal"]


def test_f85_grasp_has_one_actuator_and_the_linkage_rows() -> None:
    grasp = load_grasp(F85)
    t = grasp.transmission
    assert t is not None
    assert t.actuator_names == ("fingers_actuator",)
    np.testing.assert_array_equal(
        grasp.operation_ranges["fingers_actuator"].vertices, [[0, 0], [5, 0], [5, 1.25], [0, 1.25]]
    )
    assert len(t.constraint_names) == 5
    assert np.max(np.abs(t.constraint_residual)) < 1e-15  # the file's joint values close the linkage


def test_f85_default_joints_follow_the_linkage() -> None:
    """Without a joints list the contacts' chains give the spring links and followers; the
    connects and the driver coupling add the couplers and drivers: all eight, in model order."""
    doc = _doc(F85)
    del doc["joints"]
    grasp = load_grasp(doc)
    assert grasp.joints == tuple(_doc(F85)["joints"])


def test_a_joint_left_out_of_a_linkage_is_named() -> None:
    doc = _doc(F85)
    doc["joints"] = [j for j in doc["joints"] if j != "left_coupler_joint"]
    with pytest.raises(
        GraspError,
        match=r"joints: equality 'left_linkage': constrains state joints together with 'left_coupler_joint'",
    ):
        load_grasp(doc)


def test_actuator_ranges_errors_name_the_actuator() -> None:
    doc = _doc(F85)
    doc["ranges"] = {"right_driver_joint": {"actuator": True, "speed_limit": 1.0}}
    with pytest.raises(
        GraspError,
        match=r"ranges\.fingers_actuator: no operation range for this actuator \(the hand has coupled joints",
    ):
        load_grasp(doc)
    doc["ranges"] = {"fingers_actuator": {"actuator": "other", "speed_limit": 1.0}}
    with pytest.raises(
        GraspError, match=r"ranges\.fingers_actuator: actuator 'fingers_actuator': names actuator 'other'"
    ):
        load_grasp(doc)
    doc["ranges"] = {"*": {"dcmotor": True}}
    with pytest.raises(GraspError, match=r"ranges\.\*: actuator 'fingers_actuator': .*is not a <dcmotor>"):
        load_grasp(doc)


def test_actuator_polygon_and_datasheet_ranges() -> None:
    """A polygon is taken as given (actuator units); a datasheet behind its gear ratio is the
    range at the tendon (MuJoCo gear 1): the maxon RE 25 at 100:1 gives 100 x 26.3 mN m
    continuous (the friction loss of the drivers is 0 in the model)."""
    doc = _doc(F85)
    doc["ranges"] = {"fingers_actuator": {"polygon": [[0, 0], [2, 0], [0, 3]]}}
    np.testing.assert_array_equal(
        load_grasp(doc).operation_ranges["fingers_actuator"].vertices, [[0, 0], [2, 0], [0, 3]]
    )
    doc["ranges"] = {"fingers_actuator": {"datasheet": "maxon_re25_20w", "gear_ratio": 100}}
    rng = load_grasp(doc).operation_ranges["fingers_actuator"]
    assert float(np.max(rng.vertices[:, 0])) == pytest.approx(100 * 0.0263, rel=0.05)


def test_joint_losses_ignore_drops_damping_and_friction() -> None:
    doc = _doc(SHADOW)
    doc["joint_losses"] = "ignore"
    grasp = load_grasp(doc)
    assert grasp.transmission is not None
    np.testing.assert_array_equal(grasp.transmission.joint_damping, np.zeros(13))
    assert float(np.max(grasp.operation_ranges["rh_A_FFJ0"].vertices[:, 0])) == 1.0


def test_independent_hands_have_no_transmission() -> None:
    """The paper's hands, the Allegro and the gripper3 keep per-joint ranges, unchanged."""
    for name in ("allegro/allegro-sphere.toml", "gripper3/gripper3-box.toml", "paper_hand/case1.toml"):
        grasp = load_grasp(MODELS / name)
        assert grasp.transmission is None
        assert set(grasp.operation_ranges) == set(grasp.joints)


def test_shipped_documents_are_unchanged_by_loading() -> None:
    doc = _doc(F85)
    before = copy.deepcopy(doc)
    load_grasp(doc)
    assert doc == before


# ----------------------------------------------------------------- states (mjtvm.state/2)
@pytest.fixture(scope="module", params=["shadow", "f85"])
def coupled(request: pytest.FixtureRequest) -> tuple[Any, Any]:
    grasp = load_grasp(SHADOW_COUPLED if request.param == "shadow" else F85)
    return grasp, grasp.state()


def _moved(grasp: Any, qd: np.ndarray, h: float) -> mujoco.MjData:
    data = mujoco.MjData(grasp.model)
    data.qpos[:] = grasp.data.qpos
    for name, v in zip(grasp.joints, qd, strict=True):
        data.qpos[grasp.model.joint(name).qposadr[0]] += h * v
    mujoco.mj_forward(grasp.model, data)
    return data


def test_state_carries_the_transmission(coupled: tuple[Any, Any]) -> None:
    grasp, state = coupled
    t = state.transmission
    assert t is not None and t.actuator_names == grasp.transmission.actuator_names
    np.testing.assert_array_equal(t.moment, grasp.transmission.moment)
    assert len(state.operation_ranges) == len(t.actuator_names)
    doc = state_to_dict(state)
    assert doc["schema"] == "mjtvm.state/2"
    again = parse_state(json.loads(json.dumps(doc)))
    assert again.transmission is not None
    np.testing.assert_array_equal(again.transmission.moment, t.moment)


def test_contact_jacobians_and_actuator_speeds_against_finite_differences(coupled: tuple[Any, Any]) -> None:
    """J qd is the rate of the contact point fixed to its body, and P qd the rate of MuJoCo's
    actuator lengths (central differences of positions, h = 1e-6), for random joint speeds."""
    grasp, state = coupled
    model = grasp.model
    h = 1e-6
    ids = list(grasp.transmission.actuator_ids)
    rng = np.random.default_rng(7)
    for _ in range(3):
        qd = rng.normal(size=state.num_joints)
        plus, minus = _moved(grasp, qd, h), _moved(grasp, qd, -h)
        for c in state.contacts:
            g = int(model.geom(c.name.split("#")[0]).id)
            b = int(model.geom_bodyid[g])
            local = grasp.data.xmat[b].reshape(3, 3).T @ (c.position - grasp.data.xpos[b])
            points = [d.xpos[b] + d.xmat[b].reshape(3, 3) @ local for d in (plus, minus)]
            np.testing.assert_allclose(c.jacobian @ qd, (points[0] - points[1]) / (2 * h), atol=1e-8)
        fd = (plus.actuator_length[ids] - minus.actuator_length[ids]) / (2 * h)
        np.testing.assert_allclose(state.actuator_speeds(qd), fd, atol=1e-8)


def test_bias_torque_includes_the_springs() -> None:
    """The 2F-85's spring links: gravity_torque = qfrc_bias - qfrc_passive at rest, whose
    passive part is the spring's stiffness x (q - springref) = 0.05 x (q - 2.62) N m."""
    grasp = load_grasp(F85)
    state = grasp.state()
    model, data = grasp.model, grasp.data
    for side in ("right", "left"):
        j = model.joint(f"{side}_spring_link_joint")
        k = grasp.joints.index(j.name)
        q = float(data.qpos[j.qposadr[0]])
        spring = -0.05 * (q - 2.62)
        gravity = float(data.qfrc_bias[j.dofadr[0]])
        assert state.gravity_torque[k] == pytest.approx(gravity - spring, abs=1e-12)


def test_alphas_against_the_cvxpy_reference(coupled: tuple[Any, Any]) -> None:
    """Every alpha of Problem 2 equals the independent cvxpy transcription (extended to
    actuators and constraints), and every one is certified."""
    _, state = coupled
    result = tvmmp(state)
    ref, status = reference_tvmmp(state)
    assert all(s == "optimal" for row in status for s in row)
    np.testing.assert_allclose(result.alpha, ref, rtol=1e-6, atol=1e-9)
    assert np.all(result.certified) and result.tvmmp is not None
    if state.num_joints == 8:  # the 2F-85: along the lift its couplers reach their stop (horizon)
        assert result.alpha[0, 0] == 0.0 and result.alpha[0, 1] > 0.0
    else:
        assert result.tvmmp > 0.0


def test_coupled_shadow_adds_the_two_equalities() -> None:
    """The coupled Shadow is the sum-tendon hand plus J1 = J2 on both fingers: the same 11
    actuators and 13 joints, two constraint rows e_J1 - e_J2, closed at the grasp."""
    grasp = load_grasp(SHADOW_COUPLED)
    t = grasp.transmission
    assert t is not None and len(t.actuator_names) == 11 and len(grasp.joints) == 13
    assert t.constraint_names == ("rh_FFJ1_FFJ2", "rh_MFJ1_MFJ2")
    ff1, ff2 = grasp.joints.index("rh_FFJ1"), grasp.joints.index("rh_FFJ2")
    np.testing.assert_allclose(t.constraint_jacobian[0, [ff1, ff2]], [1.0, -1.0], atol=1e-12)
    assert np.max(np.abs(t.constraint_residual)) < 1e-9


def test_cli_solve_says_the_sum_tendon_shadow_cannot_hold() -> None:
    """The public models' transmission (the sum tendon alone): exit 0, no TVMMP, held false,
    and one stderr line naming the free motions J2 - J1 (docs/own-hand.md)."""
    exe = Path(sys.executable).with_name("mjtvm")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "mjtvm.cli"]
    proc = subprocess.run([*cmd, "solve", str(SHADOW)], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["tvmmp"] is None and doc["held"] == [False] and doc["diagnosis"][0]["cause"] == "unheld"
    (line,) = [ln for ln in proc.stderr.splitlines() if "cannot be held" in ln]
    assert "(rh_FFJ2 +0.707, rh_FFJ1 -0.707) needs" in line and "(rh_MFJ2 +0.707, rh_MFJ1 -0.707)" in line


@pytest.mark.parametrize("grasp", [SHADOW_COUPLED, F85])
def test_cli_export_solve_tvms(tmp_path: Path, grasp: Path) -> None:
    """The commands a user runs, as subprocesses: export-state, solve (the grasp file and the
    exported mjtvm.state/2 file), tvms: exit 0."""
    exe = Path(sys.executable).with_name("mjtvm")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "mjtvm.cli"]
    state_file = tmp_path / "state.json"
    for words in (["export-state", str(grasp)], ["solve", str(grasp)], ["tvms", str(grasp)]):
        proc = subprocess.run([*cmd, *words], capture_output=True, text=True, check=False, timeout=600)
        assert proc.returncode == 0, proc.stderr
        if words[0] == "export-state":
            state_file.write_text(proc.stdout, encoding="utf-8")
    proc = subprocess.run([*cmd, "solve", str(state_file)], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    if grasp == F85:  # 0 within the default 1 mm horizon, its limit the cause; > 0 within 0.9 mm
        doc = json.loads(proc.stdout)
        assert doc["tvmmp"] == 0.0 and doc["diagnosis"][0]["cause"] == "limits"
        words = ["solve", str(state_file), "--limit-horizon", "0.0009"]
        proc = subprocess.run([*cmd, *words], capture_output=True, text=True, check=False)
        assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["tvmmp"] > 0


def test_ik_keeps_the_linkage_closed() -> None:
    """The IK moves the 2F-85's pads 1 mm down with the sphere and keeps every equality closed
    (residual rows in its least squares): constraint residuals below its tolerance."""
    grasp = load_grasp(F85)
    model, data = grasp.model, grasp.data
    targets = []
    for side in ("right", "left"):
        b = int(model.body(f"{side}_pad").id)
        g = int(model.geom(f"{side}_pad2").id)
        p = data.geom_xpos[g] + data.geom_xmat[g].reshape(3, 3) @ np.array([0.0, -0.004, 0.0])
        local = data.xmat[b].reshape(3, 3).T @ (p - data.xpos[b])
        targets.append(IkTarget(name=side, body=f"{side}_pad", point=local, position=p - [0, 0, 1e-3]))
    result = solve_ik(model, data, targets, joints=list(grasp.joints), tolerance=1e-10)
    moved = mujoco.MjData(model)
    moved.qpos[:] = result.qpos
    residual, _ = equality_residual(model, moved, [int(model.joint(j).dofadr[0]) for j in grasp.joints])
    assert len(residual) == 5 and np.max(np.abs(residual)) <= 1e-10  # x rows: zero over the dofs
    assert np.max(np.abs(result.qpos - data.qpos)) > 1e-3  # it moved


@pytest.mark.parametrize("grasp", [SHADOW_COUPLED, F85])
def test_cli_replay_and_verify(tmp_path: Path, grasp: Path) -> None:
    """A short replay runs (exit 0, one row per state); so does a short verify, which drives the
    actuators through the transmission (docs/physics-check.md): one row per state and RVDS vertex.
    The 2F-85 (speed edge binding, box motor 10 % past it, twist tolerance 10 %): alpha_sim /
    alpha_kl between 1 and 1.3 (measured 1.11 to 1.24, central and vertex witness alike), the check at 0.9 alpha_kl passes. The
    Shadow hand's state 0 does not hold at rest on the least forces; ``--hold-drive auto`` (the
    default) holds it with the squeeze (docs/physics-check.md, "The squeeze hold"), its state 1
    on the least forces: every pair held, each row naming its drive."""
    exe = Path(sys.executable).with_name("mjtvm")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "mjtvm.cli"]
    f85 = grasp == F85
    if f85:
        grasp = _f85_without_horizon(tmp_path)
    out = tmp_path / "replay"
    words = ["replay", "--grasp", str(grasp), "--states", "3", "--no-sweeps", "--no-plots", "--quiet"]
    proc = subprocess.run([*cmd, *words, "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    rows = (out / "lift.csv").read_text(encoding="utf-8").splitlines()
    assert len(rows) == 1 + 3
    words = [
        "verify",
        "--grasp",
        str(grasp),
        "--states",
        "2",
        "--contacts",
        "L",
        "--reading",
        "physical",
        "--dynamics",
    ]
    proc = subprocess.run(
        [*cmd, *words, "--quiet", "--no-plots", "--out", str(tmp_path / "v")],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    with (tmp_path / "v" / "verify.csv").open(encoding="utf-8") as f:
        found = list(csv.DictReader(f))
    nrvds = len(tomllib.loads(grasp.read_text(encoding="utf-8"))["rvds"])
    assert len(found) == 2 * nrvds
    assert all(r["status"] == "optimal" and float(r["alpha_lp"]) > 0 for r in found)
    if f85:
        # The box's speed edge binds; a rollout fails 1 % past it (docs/physics-check.md), and
        # the speed loop's overshoot leaves alpha_sim a few per cent below alpha_kl.
        assert all(0.9 <= float(r["ratio"]) <= 1.05 and r["pass_check"] == "True" for r in found)
        assert all(r["verdict"] == "speed edge at actuator fingers_actuator" for r in found)
    held = [r for r in found if r["held"] == "True"]
    if f85:
        assert held == found
    else:
        assert held == found and "does not hold at rest" not in proc.stderr
        assert [r["hold_drive"] for r in found] == ["squeeze"] * nrvds + ["least"] * nrvds
    # --dynamics: the dynamic alpha of each pair held, its limit named per actuator (docs/dynamics.md)
    prefix = "fingers_actuator" if f85 else "rh_A_"
    assert all(float(r["alpha_dyn"]) > 0 and r["dyn_joint"].startswith(prefix) for r in held), held


def test_datasheet_range_through_a_mujoco_gear() -> None:
    """MuJoCo's moment includes the actuator's gear g: a datasheet range at the tendon (torque
    T, speed w) is (T / g, g w) in the actuator's units. Here g = 2 on a fixed tendon a + b:
    the RE 25 behind 10:1 gives 263 mN m and 9560 rpm / 10 at the tendon."""
    model = mujoco.MjModel.from_xml_string(
        """<mujoco><worldbody><body><joint name="a"/><geom size=".1" mass="1"/>
        <body pos="0 0 .2"><joint name="b"/><geom size=".1" mass="1"/></body></body></worldbody>
        <tendon><fixed name="t"><joint joint="a" coef="1"/><joint joint="b" coef="1"/></fixed></tendon>
        <actuator><motor name="m" tendon="t" gear="2"/></actuator></mujoco>"""
    )
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    t = model_transmission(model, data, [0, 1])
    np.testing.assert_array_equal(t.moment, [[2.0, 2.0]])
    entry = {"source": "datasheet", "datasheet": "maxon_re25_20w", "gear_ratio": 10.0}
    at_tendon = OperationRange.from_datasheet(
        no_load_speed_rpm=9560.0,
        nominal_speed_rpm=8330.0,
        nominal_torque_mNm=26.3,
        max_permissible_speed_rpm=14000.0,
        gear_ratio=10.0,
    )
    ranges, _ = actuator_ranges(model, ("m",), t.moment, (0, 1), {"m": entry}, base=None, file="f")
    np.testing.assert_allclose(ranges["m"].vertices, at_tendon.vertices * [0.5, 2.0], rtol=1e-15)


def test_a_range_keyed_by_the_wrong_kind_of_name_is_refused() -> None:
    """Operation ranges by joint on a hand whose joints are each their own actuator's, by
    actuator on a coupled hand: a key the path never reads is an error, not a range silently
    left out (here a joint's range given on the 2F-85, whose ranges belong to its actuator)."""
    from dataclasses import replace

    from mjtvm.errors import ModelError

    grasp = load_grasp(F85)
    joint = grasp.state().joint_names[0]
    ranges = {**grasp.operation_ranges, joint: OperationRange([[0, 0], [1, 0], [1, 1], [0, 1]])}
    with pytest.raises(ModelError, match=rf"^operation_ranges\['{joint}'\]: names no actuator driving"):
        replace(grasp, operation_ranges=ranges).state()


SHADOW_5F = MODELS / "shadow_hand" / "shadow_right.xml"
SHADOW_5F_GRASP = MODELS / "shadow_hand" / "shadow_hand_5f_coupled-sphere.toml"


def test_five_finger_shadow_hand_keeps_the_three_finger_transcription() -> None:
    """22 hinge joints (FF, MF, RF 4 each; LF and TH 5), 18 actuators, the four sum tendons;
    every joint, body and actuator the three-finger file has is the same in the full hand."""
    full = mujoco.MjModel.from_xml_path(str(SHADOW_5F))
    three = mujoco.MjModel.from_xml_path(str(MODELS / "shadow_hand" / "shadow_right_3f.xml"))
    hinge = int(mujoco.mjtJoint.mjJNT_HINGE)
    assert full.njnt == 22 and all(int(t) == hinge for t in full.jnt_type)
    assert (full.nu, full.ntendon, full.neq) == (18, 4, 0)
    for j in range(three.njnt):
        k = full.joint(three.joint(j).name).id
        for field in ("jnt_axis", "jnt_pos", "jnt_range", "dof_damping", "dof_armature", "dof_frictionloss"):
            a, b = getattr(three, field), getattr(full, field)
            np.testing.assert_array_equal(b[k], a[j], err_msg=f"{field} {three.joint(j).name}")
    for b in range(1, three.nbody):
        k = full.body(three.body(b).name).id
        for field in ("body_pos", "body_quat", "body_mass", "body_inertia", "body_ipos"):
            np.testing.assert_array_equal(getattr(full, field)[k], getattr(three, field)[b])
    for a in range(three.nu):
        k = full.actuator(three.actuator(a).name).id
        for field in ("actuator_gainprm", "actuator_ctrlrange", "actuator_forcerange"):
            np.testing.assert_array_equal(getattr(full, field)[k], getattr(three, field)[a])
    coupled = mujoco.MjModel.from_xml_path(str(SHADOW_5F.with_name("shadow_right_coupled.xml")))
    assert coupled.njnt == 22 and coupled.neq == 4


def test_five_finger_shadow_grasp_solves_its_36_lps() -> None:
    """Five fingertip F contacts, 6 REFS x 6 RVDS: every LP optimal, the grasp held, and no
    contact of the hand with itself at the IK's posture."""
    from mjtvm.grasp.contacts.report import contact_warnings

    grasp = load_grasp(SHADOW_5F_GRASP)
    t = grasp.transmission
    assert t is not None
    assert len(grasp.joints) == 22 and len(t.actuator_names) == 18 and len(t.constraint_names) == 4
    assert [c.split("#")[0] for c in grasp.contact_types] == [
        "ff_distal", "mf_distal", "rf_distal", "lf_distal", "th_distal",
    ]  # fmt: skip
    assert contact_warnings(grasp) == []
    res = tvmmp(grasp.state(), witnesses=False)
    assert res.timings.num_lps == 36 and res.feasible
    assert np.asarray(res.status).shape == (6, 6) and {str(s) for s in np.ravel(res.status)} == {"optimal"}
    assert res.tvmmp is not None and 0.05 < res.tvmmp < 0.07 and all(res.held)  # 0.0596 m/s
