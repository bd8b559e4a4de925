"""The servo datasheet form (stall torque, no-load speed; ``mjtvm/grasp/actuation/servo.py``).

Expected ranges are the hand-derived vertices of the speed-torque line (eq. 1-3): the
triangle (0, 0), (T_s, 0), (0, w_0) and, with a continuous torque T_c, the quadrilateral
(0, 0), (T_c, 0), (T_c, w_0 (1 - T_c / T_s)), (0, w_0); torques times gear x efficiency and
speeds over the gear at the joint. The maxon form and the equivalent servo form give the same
range and the same motor; the motor's compiled ``<dcmotor>`` reads back as the same range and
adds gear^2 x rotor inertia to the joint's inertia.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.actuator import operation_range_from_actuator
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.grasp.actuation.servo import ServoDatasheet
from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.resolve.file import load_grasp
from mjtvm.model.operation_range import OperationRange, load_motor_data
from mjtvm.physics.motors import attach_dcmotors, dcmotor_of_joint

GRIPPER = Path(__file__).resolve().parents[3] / "models" / "gripper3"
RPM = 2.0 * math.pi / 60.0
XH430 = {"voltage_V": 12.0, "stall_torque_Nm": 3.4, "no_load_speed_rpm": 30.0}  # 30 rev/min = pi rad/s


def _vertices(rng: OperationRange) -> np.ndarray:
    return np.asarray(rng.vertices, dtype=float)


def test_the_shipped_servo_sheet_is_the_triangle_of_its_two_published_ends() -> None:
    figures = load_motor_data("dynamixel_xh430_w350")
    rng = ServoDatasheet.from_figures(figures).operation_range()
    np.testing.assert_allclose(_vertices(rng), [[0, 0], [3.4, 0], [0, math.pi]], rtol=0, atol=1e-15)


@pytest.mark.parametrize(
    ("extra", "expected"),
    [
        ({}, [[0, 0], [3.4, 0], [0, math.pi]]),
        # T_c = 1.5 N m: the line at T_c runs at pi (1 - 1.5 / 3.4) = pi 19/34 rad/s
        ({"continuous_torque_Nm": 1.5}, [[0, 0], [1.5, 0], [1.5, math.pi * 19 / 34], [0, math.pi]]),
        ({"continuous_torque_Nm": 3.4}, [[0, 0], [3.4, 0], [0, math.pi]]),  # T_c = T_s: the triangle
        ({"gear_efficiency": 0.8}, [[0, 0], [2.72, 0], [0, math.pi]]),  # torque x 0.8 only
        (
            {"continuous_torque_Nm": 1.5, "gear_efficiency": 0.5},
            [[0, 0], [0.75, 0], [0.75, math.pi * 19 / 34], [0, math.pi]],
        ),
    ],
)
def test_servo_ranges_are_the_hand_derived_vertices(
    extra: dict[str, float], expected: list[list[float]]
) -> None:
    rng = ServoDatasheet.from_figures({**XH430, **extra}).operation_range()
    np.testing.assert_allclose(_vertices(rng), expected, rtol=1e-15, atol=1e-15)


def test_motor_side_figures_behind_a_gear_give_the_output_figures_range() -> None:
    """The XH430-W350's gear 353.5: the motor's own figures are 3.4 / 353.5 N m and 30 x 353.5 rpm."""
    g = 353.5
    motor_side = {
        "voltage_V": 12.0,
        "stall_torque_Nm": 3.4 / g,
        "no_load_speed_rpm": 30.0 * g,
        "gear_ratio": g,
    }
    out = ServoDatasheet.from_figures({**XH430, "continuous_torque_Nm": 1.5}).operation_range()
    geared = ServoDatasheet.from_figures({**motor_side, "continuous_torque_Nm": 1.5 / g}).operation_range()
    np.testing.assert_allclose(_vertices(geared), _vertices(out), rtol=1e-14, atol=1e-15)


def _re25_as_servo() -> dict[str, Any]:
    """The shipped RE25's nominal line in the servo form: the stall torque where the line
    through the no-load point and the nominal point meets zero speed, T_N n_0 / (n_0 - n_N)."""
    m = load_motor_data()
    n0, nn, tn = m["no_load_speed_rpm"], m["nominal_speed_rpm"], m["nominal_torque_mNm"] * 1e-3
    return {
        "voltage_V": m["nominal_voltage_V"],
        "stall_torque_Nm": tn * n0 / (n0 - nn),
        "no_load_speed_rpm": n0,
        "continuous_torque_Nm": tn,
        "gear_ratio": m["gear_ratio"],
        "rotor_inertia_kgm2": m["rotor_inertia_gcm2"] * 1e-7,
    }


def test_a_maxon_sheet_and_its_servo_form_give_the_same_range_and_motor() -> None:
    m = load_motor_data()
    maxon = OperationRange.from_datasheet(
        no_load_speed_rpm=m["no_load_speed_rpm"],
        nominal_speed_rpm=m["nominal_speed_rpm"],
        nominal_torque_mNm=m["nominal_torque_mNm"],
        max_permissible_speed_rpm=m["max_permissible_speed_rpm"],
        gear_ratio=m["gear_ratio"],
    )
    servo = ServoDatasheet.from_figures(_re25_as_servo())
    np.testing.assert_allclose(_vertices(servo.operation_range()), _vertices(maxon), rtol=1e-14, atol=1e-14)
    # the paper's actuator (Fig. 1): (1.052, 0), (1.052, 8330 rpm / 40), (0, 9560 rpm / 40)
    np.testing.assert_allclose(
        _vertices(servo.operation_range())[1:],
        [[1.052, 0], [1.052, 8330 * RPM / 40], [0, 9560 * RPM / 40]],
        rtol=1e-14,
        atol=1e-14,
    )
    a, b = servo.motor(), DCMotor.from_datasheet(m)
    for field in (
        "voltage",
        "stall_torque",
        "no_load_speed",
        "max_continuous_torque",
        "gear",
        "rotor_inertia",
    ):
        assert getattr(a, field) == pytest.approx(getattr(b, field), rel=1e-14), field


_HINGE = """<mujoco><option timestep="0.00025" integrator="implicitfast" gravity="0 0 0"/>
<worldbody><body name="link"><joint name="j" type="hinge" axis="0 0 1"/>
<geom type="capsule" fromto="0 0 0 0.05 0 0" size="0.01" mass="0.02"/></body></worldbody></mujoco>"""


def _xh430_on_either_side() -> list[dict[str, Any]]:
    """The XH430-W350's figures at its output, and the same servo's motor behind its 353.5 gear."""
    g = 353.5
    motor_side = {**XH430, "stall_torque_Nm": 3.4 / g, "no_load_speed_rpm": 30.0 * g, "gear_ratio": g}
    return [XH430, motor_side]


@pytest.mark.parametrize("side", [0, 1], ids=["output", "motor-side"])
def test_a_servo_s_speed_loop_gain_at_the_joint_is_its_stall_torque_over_its_no_load_speed(side: int) -> None:
    """A free hinge on the servo, speed setpoint 0, pushed by 0.5 N m, turns at the speed where
    the loop's torque kd (0 - qdot) balances the push: qdot = 0.5 / (3.4 / pi) = 0.4620 rad/s,
    the same with the figures on either side of the gear (kd x gear^2 at the joint). The
    default gain (5e-4 N m s/rad) gave 3.60 rad/s (past the no-load speed: only the voltage
    clamp braked) at the output and 0.0080 rad/s behind the gear."""
    servo = ServoDatasheet.from_figures(_xh430_on_either_side()[side])
    motor = servo.motor()
    assert motor.velocity_gain * motor.gear**2 == pytest.approx(3.4 / math.pi, rel=1e-12)
    model = attach_dcmotors(_HINGE, {"j": motor})
    data = mujoco.MjData(model)
    data.qfrc_applied[0] = 0.5
    data.ctrl[:] = 0.0  # the speed setpoint and the feedforward
    mujoco.mj_step(model, data, nstep=8000)  # 2 s: the link's time constant is 0.02 ms
    assert data.qvel[0] == pytest.approx(0.5 * math.pi / 3.4, rel=1e-6)
    assert data.actuator_force[0] * motor.gear == pytest.approx(-0.5, rel=1e-9)


def test_the_hold_test_s_position_loop_on_a_servo_is_kd_kp_stiff() -> None:
    """The hold test's position loop (speed setpoint kp (l_0 - l), kp = 10 1/s) on the output-side
    XH430-W350 holds a 0.5 N m push at the deflection 0.5 / (kd kp) = 0.5 pi / 34 = 0.04620 rad
    (kd = 3.4 / pi N m s/rad): a stiffness of 10.82 N m/rad. The default gain gave 0.005 N m/rad."""
    from mjtvm.physics.squeeze import SERVO_GAIN, Servo

    model = attach_dcmotors(_HINGE, {"j": ServoDatasheet.from_figures(XH430).motor()})
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    loop = Servo(model, data, np.array([0]), np.array([0]), SERVO_GAIN)
    data.qfrc_applied[0] = 0.5
    loop.step(8000)  # 2 s = 20 time constants of the loop (1 / kp)
    assert data.qpos[0] == pytest.approx(0.5 * math.pi / (3.4 * SERVO_GAIN), rel=1e-6)


def _gripper_doc(entry: dict[str, Any]) -> dict[str, Any]:
    doc = tomllib.loads((GRIPPER / "gripper3-box.toml").read_text(encoding="utf-8"))
    doc["model"] = str(GRIPPER / "gripper3.xml")
    doc["ranges"] = {"*": entry}
    doc["joint_losses"] = "ignore"
    return doc


def test_a_grasp_file_takes_the_shipped_servo_sheet_and_an_inline_one() -> None:
    shipped = load_grasp(_gripper_doc({"datasheet": "dynamixel_xh430_w350"}))
    inline = load_grasp(_gripper_doc({"datasheet": {**XH430, "continuous_torque_Nm": 1.5}}))
    for joint in shipped.joints:
        np.testing.assert_allclose(
            _vertices(shipped.operation_ranges[joint]), [[0, 0], [3.4, 0], [0, math.pi]], rtol=0, atol=1e-15
        )
        motor = inline.motors[joint]
        assert isinstance(motor, DCMotor)
        assert (motor.stall_torque, motor.max_continuous_torque, motor.gear) == (3.4, 1.5, 1.0)


def test_the_entry_s_gear_ratio_overrides_the_sheet_s() -> None:
    g = 353.5
    motor_side = {"voltage_V": 12.0, "stall_torque_Nm": 3.4 / g, "no_load_speed_rpm": 30.0 * g}
    grasp = load_grasp(_gripper_doc({"datasheet": motor_side, "gear_ratio": g}))
    np.testing.assert_allclose(
        _vertices(grasp.operation_ranges["f1j1"]), [[0, 0], [3.4, 0], [0, math.pi]], rtol=1e-14, atol=1e-15
    )


@pytest.mark.parametrize("continuous", [None, 1.5])
def test_the_physics_check_s_dcmotor_reads_back_as_the_range_with_the_rotor_inertia_reflected(
    continuous: float | None,
) -> None:
    g, inertia = 353.5, 1.2e-7  # a motor-side rotor inertia (kg m^2)
    figures: dict[str, Any] = {
        "voltage_V": 12.0,
        "stall_torque_Nm": 3.4 / g,
        "no_load_speed_rpm": 30.0 * g,
        "gear_ratio": g,
        "rotor_inertia_kgm2": inertia,
    }
    if continuous is not None:
        figures["continuous_torque_Nm"] = continuous / g
    servo = ServoDatasheet.from_figures(figures)
    bare = mujoco.MjModel.from_xml_path(str(GRIPPER / "gripper3.xml"))
    model = attach_dcmotors(str(GRIPPER / "gripper3.xml"), {"f1j1": servo.motor()})
    a = dcmotor_of_joint(model, "f1j1")
    assert a is not None
    np.testing.assert_allclose(
        _vertices(operation_range_from_actuator(model, a)),
        _vertices(servo.operation_range()),
        rtol=1e-9,
        atol=1e-12,
    )

    def inertia_at(m: mujoco.MjModel) -> float:
        d = mujoco.MjData(m)
        mujoco.mj_forward(m, d)
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        dof = int(m.jnt_dofadr[m.joint("f1j1").id])
        return float(full[dof, dof])

    assert inertia_at(model) - inertia_at(bare) == pytest.approx(g * g * inertia, rel=1e-12)


@pytest.mark.parametrize(
    ("figures", "match"),
    [
        (
            {"stall_torque_Nm": 3.4, "no_load_speed_rpm": 30.0},
            r"datasheet: voltage_V: required in a servo datasheet",
        ),
        (
            {**XH430, "stall_torque_Nm": -3.4},
            r"datasheet: stall_torque_Nm: expected a positive finite number, got -3\.4",
        ),
        ({**XH430, "no_load_speed_rpm": "30"}, r"datasheet: no_load_speed_rpm: expected a number, got '30'"),
        (
            {**XH430, "no_load_speed_rpm": 0},
            r"datasheet: no_load_speed_rpm: expected a positive finite number, got 0",
        ),
        (
            {**XH430, "continuous_torque_Nm": 4.0},
            r"datasheet: continuous_torque_Nm: 4\.0 N m is above the stall torque 3\.4 N m",
        ),
        (
            {**XH430, "rotor_inertia_kgm2": -1e-7},
            r"datasheet: rotor_inertia_kgm2: expected a finite number >= 0",
        ),
        (
            {**XH430, "gear_efficiency": 1.2},
            r"datasheet: gear_efficiency: expected a number in \(0, 1\], got 1\.2",
        ),
        (
            {**XH430, "nominal_torque_mNm": 26.3},
            r"datasheet: nominal_torque_mNm: a maxon-form figure in a servo datasheet",
        ),
    ],
)
def test_a_bad_servo_sheet_is_one_line_naming_the_range_and_the_key(
    figures: dict[str, Any], match: str
) -> None:
    with pytest.raises(GraspError, match=r"ranges\.\*: joint 'f1j1': " + match) as info:
        load_grasp(_gripper_doc({"datasheet": figures}))
    assert "\n" not in str(info.value)


def test_an_unknown_shipped_sheet_lists_the_shipped_ones() -> None:
    with pytest.raises(
        GraspError, match=r"no shipped datasheet 'xh430' \(shipped: dynamixel_xh430_w350, maxon_re25_20w;"
    ):
        load_grasp(_gripper_doc({"datasheet": "xh430"}))


def test_a_servo_sheet_with_an_inefficient_gear_has_a_range_and_no_dcmotor() -> None:
    grasp = load_grasp(_gripper_doc({"datasheet": {**XH430, "gear_efficiency": 0.9}}))
    assert grasp.operation_ranges["f1j1"].vertices[1][0] == pytest.approx(3.06, rel=1e-15)
    assert isinstance(grasp.motors["f1j1"], str) and "gear is ideal" in grasp.motors["f1j1"]
    with pytest.raises(ModelError, match=r"gear_efficiency"):
        ServoDatasheet.from_figures({**XH430, "gear_efficiency": 0.9}).motor()


def test_a_grasp_on_servos_solves_as_the_cvxpy_reference_does() -> None:
    """The gripper3 box grasp with XH430-W350 servos (continuous torque 1.5 N m) in every joint."""
    import mjtvm
    from oracles.reference import reference_tvmmp

    state = load_grasp(_gripper_doc({"datasheet": {**XH430, "continuous_torque_Nm": 1.5}})).state()
    result = mjtvm.tvmmp(state)
    alpha, _status = reference_tvmmp(state)
    np.testing.assert_allclose(np.asarray(result.alpha, dtype=float), alpha, rtol=1e-6, atol=1e-8)
    assert result.tvmmp is not None and result.tvmmp > 0


@pytest.mark.parametrize("l", [0, 1])
def test_a_pinch_on_servo_motors_moves_its_box_at_half_the_alpha_in_a_rollout(l: int) -> None:
    """The physics check's pinch (tests/physics/test_any_hand.py) with XH430-W350-like servos
    (motor-side figures behind the 353.5 gear, continuous torque 1.5 N m at the output): the
    state's ranges, read back from the compiled <dcmotor>, are the servo's, and the rollout at
    half the witness speed passes."""
    from mjtvm.grasp.resolve.state import grasp_state
    from mjtvm.physics.simulate import rollout, sim_model
    from mjtvm.physics.witness import witness_drive
    from mjtvm.problem2.tvmmp import tvmmp
    from tests.physics.test_any_hand import PINCH

    g = 353.5
    servo = ServoDatasheet.from_figures(
        {
            "voltage_V": 12.0,
            "stall_torque_Nm": 3.4 / g,
            "no_load_speed_rpm": 30.0 * g,
            "gear_ratio": g,
            "continuous_torque_Nm": 1.5 / g,
            "rotor_inertia_kgm2": 1e-8,
        }
    )
    xml = PINCH.replace(
        '<geom type="capsule" fromto="-0.066', '<geom name="b_tip" type="capsule" fromto="-0.066'
    )
    model = attach_dcmotors(xml, dict.fromkeys(("a1", "a2", "b1", "b2", "c1", "c2"), servo.motor()))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    types = {"a_tip": "F", "b_tip": "F", "c_tip": "F"}
    rvds = [[0, 0, 1, 0, 0, 0], [0, 0, -1, 0, 0, 0]]
    state = grasp_state(model, data, contact_types=types, mu=0.8, rvds=rvds, object_body="box")
    for rng in state.operation_ranges:
        np.testing.assert_allclose(_vertices(rng), _vertices(servo.operation_range()), rtol=1e-9, atol=1e-12)
    res = tvmmp(state)
    assert res.status[0][l] == "optimal" and res.alpha[0, l] > 0
    drive = witness_drive(state, 0, l, float(res.alpha[0, l]), 0.5)
    out = rollout(
        sim_model(model, types, mu=0.8, object_body="box"), data.qpos.copy(), drive, object_body="box"
    )
    assert out.passed, out.reason
