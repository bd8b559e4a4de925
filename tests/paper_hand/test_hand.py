"""The generated hand model (mjtvm.paper_hand.hand): structure, committed files, dcmotor -> operation range."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.actuator import operation_range_from_actuator
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.model.operation_range import default_operation_range, load_motor_data
from mjtvm.paper_hand.hand import HUMANLIKE_FINGER_JOINTS, finger_joint_names, hand_mjcf, model_files

from ..helpers import Q_MAX, Q_NOM, RPM, T_MAX, G

ROOT = Path(__file__).resolve().parents[2]


def _names(model: mujoco.MjModel, kind: mujoco.mjtObj, count: int) -> list[str]:
    return [mujoco.mj_id2name(model, kind, i) for i in range(count)]


@pytest.fixture(scope="module")
def hand() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(hand_mjcf())


# ------------------------------------------------------------------ structure
def test_default_hand_names_and_actuators(hand: mujoco.MjModel) -> None:
    joints = _names(hand, mujoco.mjtObj.mjOBJ_JOINT, hand.njnt)
    expected = [f"f{i}_{j}" for i in range(1, 5) for j in ("yaw0", "pitch0", "pitch1", "yaw1")]
    assert joints == [*expected, "object"]
    geoms = set(_names(hand, mujoco.mjtObj.mjOBJ_GEOM, hand.ngeom))
    assert geoms == {"palm", "object"} | {f"f{i}_{g}" for i in range(1, 5) for g in ("link1", "link2", "tip")}
    assert hand.nactuator == 16
    assert _names(hand, mujoco.mjtObj.mjOBJ_ACTUATOR, hand.nactuator) == expected
    assert set(hand.actuator_gaintype) == {int(mujoco.mjtGain.mjGAIN_DCMOTOR)}
    for a in range(hand.nactuator):  # each actuator drives the joint of its name
        assert hand.actuator_trnid[a, 0] == a
    assert finger_joint_names(2) == ["f2_yaw0", "f2_pitch0", "f2_pitch1", "f2_yaw1"]


def test_humanlike_hand() -> None:
    model = mujoco.MjModel.from_xml_string(hand_mjcf(finger_joints=HUMANLIKE_FINGER_JOINTS))
    joints = _names(model, mujoco.mjtObj.mjOBJ_JOINT, model.njnt)
    assert joints[:4] == ["f1_yaw0", "f1_pitch0", "f1_pitch1", "f1_pitch2"]
    assert model.nactuator == 16
    assert "f1_link3" in _names(model, mujoco.mjtObj.mjOBJ_GEOM, model.ngeom)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    tip = data.geom_xpos[model.geom("f3_tip").id]
    np.testing.assert_allclose(tip, [0.05 + 0.3, 0, 0], atol=1e-12)  # three links of 0.1 m


def test_link_masses_and_centres(hand: mujoco.MjModel) -> None:
    for i in range(1, 5):
        for k in (1, 2):
            b = hand.body(f"f{i}_link{k}").id
            assert hand.body_mass[b] == pytest.approx(0.051)
            np.testing.assert_allclose(hand.body_ipos[b], [0.05, 0, 0])


@pytest.mark.parametrize("mg", [0.5, 1.0, 3.0])
def test_object_mass_follows_weight(mg: float) -> None:
    model = mujoco.MjModel.from_xml_string(hand_mjcf(mg=mg))
    b = model.body("object").id
    assert model.body_mass[b] * G == pytest.approx(mg)
    assert model.body_gravcomp[b] == 0
    assert model.geom_size[model.geom("object").id][0] == pytest.approx(0.1)


def test_weightless_object_is_gravity_compensated() -> None:
    model = mujoco.MjModel.from_xml_string(hand_mjcf(mg=0.0))
    assert model.body_gravcomp[model.body("object").id] == 1.0


def test_straight_fingers_point_along_their_headings(hand: mujoco.MjModel) -> None:
    data = mujoco.MjData(hand)
    mujoco.mj_kinematics(hand, data)
    tips = {i: data.geom_xpos[hand.geom(f"f{i}_tip").id] for i in range(1, 5)}
    np.testing.assert_allclose(tips[1], [-0.3, -0.05, 0], atol=1e-12)  # finger 1 points to -x
    np.testing.assert_allclose(tips[2], [0.25, 0.1, 0], atol=1e-12)
    np.testing.assert_allclose(tips[3], [0.25, 0.0, 0], atol=1e-12)
    np.testing.assert_allclose(tips[4], [0.25, -0.1, 0], atol=1e-12)


def test_positive_pitch_flexes_and_distal_yaw_turns_with_pitch(hand: mujoco.MjModel) -> None:
    data = mujoco.MjData(hand)
    for finger in (1, 3):
        data.qpos[:] = hand.qpos0
        data.qpos[hand.joint(f"f{finger}_pitch0").qposadr[0]] = 0.4
        data.qpos[hand.joint(f"f{finger}_pitch1").qposadr[0]] = 0.7
        mujoco.mj_kinematics(hand, data)
        assert data.geom_xpos[hand.geom(f"f{finger}_tip").id][2] > 0.1
        link2 = data.xmat[hand.body(f"f{finger}_link2").id].reshape(3, 3)[:, 0]
        yaw1 = data.xaxis[hand.joint(f"f{finger}_yaw1").id]
        assert abs(link2 @ yaw1) < 1e-12  # the yaw axis stays perpendicular to link 2
        assert abs(yaw1[2] - np.cos(1.1)) < 1e-12  # and is turned by both pitches


def test_case1_finger3_configuration_is_reachable(hand: mujoco.MjModel) -> None:
    """Paper, Case 1: link 1 on the palm, contact [0.171 0 0.072] on link 2, 0.075 m from its axis."""
    data = mujoco.MjData(hand)
    pitch1 = np.arctan2(0.072, 0.021)
    lo, hi = hand.jnt_range[hand.joint("f3_pitch1").id]
    assert lo < pitch1 < hi
    data.qpos[hand.joint("f3_pitch1").qposadr[0]] = pitch1
    mujoco.mj_kinematics(hand, data)
    b = hand.body("f3_link2").id
    point = data.xpos[b] + 0.075 * data.xmat[b].reshape(3, 3)[:, 0]
    np.testing.assert_allclose(point, [0.171, 0, 0.072], atol=1e-12)


# ------------------------------------------------------------- committed files
def test_committed_models_equal_generator_output() -> None:
    for name, text in model_files().items():
        path = ROOT / "models" / "paper_hand" / name
        assert path.read_text(encoding="utf-8") == text, f"{path} is stale: run tools/make_models.py"
        mujoco.MjModel.from_xml_path(str(path))


def test_make_models_script_writes_the_files(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location("make_models", ROOT / "tools" / "make_models.py")
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    assert module.main([str(tmp_path)]) == 0
    for name, text in model_files().items():
        assert (tmp_path / name).read_text(encoding="utf-8") == text


# --------------------------------------------------- dcmotor -> operation range
def test_compiled_dcmotor_fields(hand: mujoco.MjModel) -> None:
    motor = DCMotor.from_datasheet()
    r_ohm, k = hand.actuator_gainprm[0, :2]
    assert k == pytest.approx(24 / (9560 * RPM))  # K = V / no-load speed
    assert r_ohm == pytest.approx(k * 24 / motor.stall_torque)  # R = K V / stall torque
    assert hand.actuator_gainprm[0, 7] == 24  # Vmax
    np.testing.assert_allclose(hand.actuator_forcerange[0], [-0.0263, 0.0263])
    assert hand.actuator_gear[0, 0] == 40


def test_range_from_actuator_matches_datasheet_polygon(hand: mujoco.MjModel) -> None:
    expected = np.array([[0, 0], [T_MAX, 0], [T_MAX, Q_NOM], [0, Q_MAX]])
    np.testing.assert_allclose(expected[1:], [[1.052, 0], [1.052, 21.81], [0, 25.03]], atol=5e-3)
    default = default_operation_range()
    for a in range(hand.nactuator):
        rng = operation_range_from_actuator(hand, a)
        np.testing.assert_allclose(rng.vertices, expected, rtol=1e-8, atol=1e-12)
        np.testing.assert_allclose(rng.vertices, default.vertices, rtol=1e-8, atol=1e-12)
    # the datasheet's nominal point (26.3 mN m at 8330 rpm) lies on the compiled line
    rng = operation_range_from_actuator(hand, "f2_pitch1")
    assert rng.max_speed_at(T_MAX) == pytest.approx(Q_NOM, rel=1e-8)


def test_catalogue_stall_torque_misses_the_nominal_point() -> None:
    """Stall 243 mN m: the line through it and the no-load point passes 2.3 % above the nominal point."""
    data = load_motor_data()
    slope = 9560 / 243  # rpm per mN m on the catalogue's line
    assert 9560 - slope * 26.3 == pytest.approx(8525.3, abs=0.1)  # vs 8330 rpm on the datasheet
    model = mujoco.MjModel.from_xml_string(hand_mjcf(motor=DCMotor.from_datasheet(data, line="stall")))
    v = operation_range_from_actuator(model, 0).vertices
    np.testing.assert_allclose(v[[0, 1, 3]], [[0, 0], [T_MAX, 0], [0, Q_MAX]], rtol=1e-8)
    assert v[2, 1] / Q_NOM - 1 == pytest.approx((9560 - slope * 26.3) / 8330 - 1, rel=1e-6)
    assert 0.02 < v[2, 1] / Q_NOM - 1 < 0.025
    assert DCMotor.from_datasheet(data, line="stall").stall_torque == pytest.approx(0.243)
    assert DCMotor.from_datasheet(data).stall_torque == pytest.approx(26.3e-3 * 9560 / (9560 - 8330))


@pytest.mark.parametrize("load", [0.0, 0.5, 1.0])
def test_simulated_dcmotor_runs_on_the_derived_line(load: float) -> None:
    """Full voltage (Vmax) against a constant joint load: MuJoCo's steady speed is the range's edge."""
    motor = DCMotor.from_datasheet()
    xml = f"""<mujoco><option timestep="0.001" integrator="implicitfast" gravity="0 0 0"/>
      <worldbody><body><joint name="j" axis="0 0 1"/>
        <inertial pos="0.05 0 0" mass="0.051" diaginertia="1e-6 1e-4 1e-4"/></body></worldbody>
      <actuator>{motor.mjcf("m", "j")}</actuator></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.ctrl[0] = 1e4  # velocity setpoint far above the no-load speed: the drive runs at Vmax
    data.qfrc_applied[0] = -load
    for _ in range(4000):
        mujoco.mj_step(model, data)
    rng = operation_range_from_actuator(model, "m")
    assert data.qvel[0] == pytest.approx(rng.max_speed_at(load), rel=1e-6)


def _one_joint(actuator: str, joint_extra: str = "") -> mujoco.MjModel:
    xml = f"""<mujoco><worldbody><body><joint name="j" axis="0 1 0" {joint_extra}/>
      <geom type="capsule" fromto="0 0 0 .1 0 0" size=".004" mass=".051"/></body></worldbody>
      <actuator>{actuator}</actuator></mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)


def test_range_without_saturation_is_a_triangle() -> None:
    model = _one_joint(
        '<dcmotor name="m" joint="j" gear="40" nominal="24 0.243 1001.12" input="vel" '
        'controller="0 0 0.001 0 0 24"/>'
    )
    np.testing.assert_allclose(
        operation_range_from_actuator(model, 0).vertices, [[0, 0], [40 * 0.243, 0], [0, 1001.12 / 40]]
    )


def test_voltage_input_uses_its_ctrlrange_and_joint_force_limit() -> None:
    model = _one_joint(
        '<dcmotor name="m" joint="j" gear="10" nominal="12 0.1 500" saturation="0.02 0 0" ctrlrange="-6 6"/>',
        'actuatorfrcrange="-0.15 0.15"',
    )
    v = operation_range_from_actuator(model, "m").vertices
    # K = 12/500 = 0.024, R = K 12/0.1 = 2.88; V = 6; joint torque 0.15 (motor 0.015 < 0.02)
    speed_at = (6 - 2.88 * 0.015 / 0.024) / 0.024 / 10  # 17.5 rad/s
    np.testing.assert_allclose(v, [[0, 0], [0.15, 0], [0.15, speed_at], [0, 25.0]], rtol=1e-9)


@pytest.mark.parametrize(
    ("actuator", "match"),
    [
        ('<motor name="m" joint="j" gear="40"/>', "not a <dcmotor>"),
        ('<dcmotor name="m" joint="j" nominal="24 0.243 1001.12"/>', "no supply voltage"),
        (
            '<dcmotor name="m" joint="j" nominal="24 0.243 1001.12" cogging="0.001 4 0" ctrlrange="-24 24"/>',
            "cogging",
        ),
    ],
)
def test_range_from_actuator_errors(actuator: str, match: str) -> None:
    model = _one_joint(actuator)
    with pytest.raises(ModelError, match=match):
        operation_range_from_actuator(model, 0)


def test_unknown_actuator(hand: mujoco.MjModel) -> None:
    with pytest.raises(ModelError, match="actuator 'f5_yaw0': not in the model"):
        operation_range_from_actuator(hand, "f5_yaw0")
    with pytest.raises(ModelError, match="no such actuator"):
        operation_range_from_actuator(hand, 16)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"finger_joints": (("yaw", "bend"),)}, "unknown joint kind 'bend'"),
        ({"finger_joints": (("pitch", "pitch"),)}, "repeats"),
        ({"finger_joints": ()}, "one non-empty joint sequence per link"),
        ({"mg": -1.0}, "mg"),
        ({"link_length": 0.0}, "link_length"),
        ({"finger_bases": [(0, 0, 0)], "finger_headings": [0.0, 1.0]}, "finger_bases"),
    ],
)
def test_hand_parameter_errors(kwargs: dict, match: str) -> None:
    with pytest.raises(ModelError, match=match):
        hand_mjcf(**kwargs)


def test_motor_errors() -> None:
    data = dict(load_motor_data())
    with pytest.raises(ModelError, match="line"):
        DCMotor.from_datasheet(data, line="cold")  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="gear is ideal"):
        DCMotor.from_datasheet({**data, "gear_efficiency": 0.7})
    with pytest.raises(ModelError, match=r"DCMotor\.voltage"):
        DCMotor(voltage=0, stall_torque=0.2, no_load_speed=1000, max_continuous_torque=0.02, gear=40)
