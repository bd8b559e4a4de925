"""The physics check on hands with a transmission: a ``<dcmotor>`` per actuator on the
actuator's own transmission, the box motor, the central witness and the tracked speeds.

Closed forms: MuJoCo applies ``moment^T force`` through a tendon (``qfrc_actuator``), the
moment of a fixed tendon is ``gear x coefficients``, the box motor's line passes through the
box's corner, and the witness's joint speeds keep the linkage's ``J_eq qd = 0``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ModelError, ParamError
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.grasp.actuation.transmission import dense_moment
from mjtvm.jobs.verify import cached_lift
from mjtvm.lift.states import lift_state
from mjtvm.physics.check import contact_types, motor_model
from mjtvm.physics.motors import (
    BOX_SPEED_MARGIN,
    CTRLSPEC,
    actuator_motors,
    attach_actuator_dcmotors,
    box_motor,
    dcmotor_of_actuator,
)
from mjtvm.physics.rig import Rig
from mjtvm.physics.simulate import sim_model
from mjtvm.physics.witness import Drive, central_witness, witness_drive
from mjtvm.problem2.tvmmp import tvmmp

MODELS = Path(__file__).resolve().parents[2] / "models"
F85 = MODELS / "robotiq_2f85" / "robotiq_2f85-sphere.toml"
SHADOW = MODELS / "shadow_hand" / "shadow_hand-sphere.toml"
R1, R2, G = 0.7, -0.3, 2.5
TENDON = f"""<mujoco>
  <worldbody><body><joint name="a" axis="0 0 1"/><geom size=".1" mass="1"/>
    <body pos="0 0 .3"><joint name="b" axis="0 1 0"/><geom size=".1" mass="1"/></body></body></worldbody>
  <tendon><fixed name="t"><joint joint="a" coef="{R1}"/><joint joint="b" coef="{R2}"/></fixed></tendon>
  <actuator><position name="servo" tendon="t" gear="{G}" kp="3" ctrlrange="-1 1"/></actuator>
  <sensor><actuatorfrc name="f" actuator="servo"/></sensor>
  <keyframe><key name="k" qpos="0.1 0.2" ctrl="0.5"/></keyframe>
</mujoco>"""


def test_dcmotor_on_a_tendon_applies_moment_transpose_force() -> None:
    """The replacing <dcmotor> keeps the name and the tendon, takes gear N x G; MuJoCo's moment is
    N G (r1, r2), its joint torques moment^T force and its speed N G (r1 qd1 + r2 qd2)."""
    n = 3.0
    model = attach_actuator_dcmotors(TENDON, {"servo": box_motor(2.0, 4.0, gear=n)})
    a = dcmotor_of_actuator(model, "servo")
    assert model.nactuator == 1 and model.nsensor == 0
    assert int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_TENDON)
    assert int(model.actuator_ctrlspec[a]) == CTRLSPEC and model.actuator_gear[a, 0] == n * G
    assert list(model.key_ctrl[0]) == [0.0, 0.0]
    data = mujoco.MjData(model)
    data.qpos[:] = [0.1, 0.2]
    data.qvel[:] = [0.4, -1.1]
    data.ctrl[:] = [0.0, 0.5]  # setpoint 0, feedforward 0.5 N m (motor side)
    mujoco.mj_forward(model, data)
    moment = dense_moment(model, data)
    np.testing.assert_allclose(moment, [[n * G * R1, n * G * R2]], rtol=1e-12)
    force = float(data.actuator_force[a])
    assert force != 0.0
    np.testing.assert_allclose(data.qfrc_actuator, moment[0] * force, rtol=1e-12)
    np.testing.assert_allclose(data.actuator_velocity[a], n * G * (R1 * 0.4 - R2 * 1.1), rtol=1e-12)


def test_box_motor_line_passes_through_the_corner() -> None:
    """Saturation U; stall torque x (1 - S / no-load) = U at the box's speed S; no-load (1 + m) S."""
    u, s = 5.0, 1.25
    m = box_motor(u, s)
    assert m.max_continuous_torque == u and m.gear == 1.0 and m.rotor_inertia == 0.0
    assert m.no_load_speed == pytest.approx((1 + BOX_SPEED_MARGIN) * s, rel=1e-15)
    assert m.stall_torque * (1 - s / m.no_load_speed) == pytest.approx(u, rel=1e-12)
    assert m.velocity_gain == pytest.approx(u / s, rel=1e-15)
    with pytest.raises(ModelError, match="max_speed: expected a positive finite number"):
        box_motor(1.0, float("inf"))


def test_unknown_actuator_is_refused() -> None:
    with pytest.raises(ModelError, match="actuator 'nope': not in the model"):
        attach_actuator_dcmotors(TENDON, {"nope": box_motor(1.0, 1.0)})


def test_f85_motor_model_and_central_witness() -> None:
    """The 2F-85: its one tendon actuator becomes a dcmotor (box 5 N m, 1.25 rad/s); the central
    witness at alpha keeps the linkage's J_eq qd = 0, its actuator speed is P qd, within the box;
    the tracked speeds keep J_eq qd = 0 at the state (MuJoCo's equality rows)."""
    lift = cached_lift(F85, 2)
    grasp = lift.scenario
    motors = actuator_motors(grasp)
    assert list(motors) == ["fingers_actuator"]
    assert motors["fingers_actuator"] == box_motor(5.0, 1.25)
    state = lift_state(lift, 0, variant="L", mu=0.6, mg=0.4905)
    # Its coupler joints reach their limit after 0.99999 mm of lift (docs/joint-limits.md): at
    # the default 1 mm horizon alpha_00 is 0; the linkage's witness is checked without it.
    assert state.joint_limits is not None
    state = state.with_(joint_limits=state.joint_limits.with_options(horizon=0.0))
    t = state.transmission
    assert t is not None and t.constraint_jacobian is not None
    res = tvmmp(state)
    alpha = float(res.alpha[0, 0])
    sol = central_witness(state, 0, 0, alpha * (1 - 1e-7))
    jeq = t.constraint_jacobian
    assert np.max(np.abs(jeq @ sol["speeds"])) <= 1e-9 * np.max(np.abs(sol["speeds"]))
    np.testing.assert_allclose(sol["actuator_speeds"], t.moment @ sol["speeds"], rtol=1e-12)
    assert abs(sol["actuator_speeds"][0]) <= 1.25 * (1 + 1e-6)
    assert abs(sol["torques"][0]) <= 5.0 * (1 + 1e-6)
    drive = witness_drive(state, 0, 0, alpha, 0.5)
    assert drive.actuators == ("fingers_actuator",)
    np.testing.assert_allclose(drive.actuator_speeds, 0.5 * sol["actuator_speeds"], rtol=1e-5)
    model = sim_model(motor_model(grasp), contact_types(state), mu=0.6, object_body=grasp.object_body)
    rig = Rig(model, drive, grasp.object_body)
    data = mujoco.MjData(model)
    data.qpos[:] = lift.qpos[0]
    mujoco.mj_forward(model, data)
    rig.bind(data, drive)
    assert rig.coupled and rig.gear[0] == pytest.approx(1.0, rel=1e-12)
    rows = rig.equality_rows(data)
    assert rows.shape[0] >= jeq.shape[0]
    q = rig.setpoints(data, drive)
    assert np.max(np.abs(rows @ q)) <= 1e-9 * np.max(np.abs(q))
    np.testing.assert_allclose(rig.motor_speeds(data, q), t.moment @ q, rtol=1e-9, atol=1e-12)


def test_shadow_box_motors_carry_the_friction_share() -> None:
    """The Shadow hand's 11 actuators: boxes |u| <= forcerange - 0.01 (the joints' friction loss),
    |s| <= 2; each motor saturates at the whole force range (the rollout feeds the 0.01 forward)."""
    grasp = cached_lift(SHADOW, 2).scenario
    motors = actuator_motors(grasp)
    assert len(motors) == 11
    force = {n: 1.0 for n in motors} | {"rh_A_THJ5": 3.0, "rh_A_THJ4": 2.0}
    for name, motor in motors.items():
        assert motor == box_motor(force[name], 2.0), name


def test_drive_shapes_are_checked() -> None:
    with pytest.raises(ParamError, match="expected 2 joint speeds and 1 torques"):
        Drive(("a", "b"), np.zeros(2), np.zeros(2), np.zeros(6), (), actuators=("m",), moment=np.ones((1, 2)))
    with pytest.raises(ParamError, match=r"drive.moment: expected shape \(1, 2\)"):
        Drive(("a", "b"), np.zeros(2), np.zeros(1), np.zeros(6), (), actuators=("m",), moment=np.ones((2, 2)))


def test_datasheet_motor_keeps_its_gear() -> None:
    """A datasheet motor (gear N) on a tendon actuator of MuJoCo gear G: the dcmotor's gear N G."""
    motor = DCMotor(
        voltage=12.0, stall_torque=0.1, no_load_speed=900.0, max_continuous_torque=0.02, gear=50.0
    )
    model = attach_actuator_dcmotors(TENDON, {"servo": motor})
    assert model.actuator_gear[0, 0] == pytest.approx(50.0 * G, rel=1e-15)


def test_damping_share_of_a_tendon_in_closed_form() -> None:
    """Least squares of P^T du = b qd with P = G (r1, r2): du = (r1 b1 q1 + r2 b2 q2) / (G (r1^2 + r2^2))."""
    b1, b2, q = 0.3, 0.05, np.array([1.5, -0.8])
    xml = TENDON.replace('<joint name="a" axis="0 0 1"/>', f'<joint name="a" axis="0 0 1" damping="{b1}"/>')
    xml = xml.replace('<joint name="b" axis="0 1 0"/>', f'<joint name="b" axis="0 1 0" damping="{b2}"/>')
    xml = xml.replace(
        "</worldbody>", '<body name="object" pos="1 0 0"><freejoint/><geom size=".05"/></body></worldbody>'
    )
    xml = xml.replace('qpos="0.1 0.2"', 'qpos="0.1 0.2 1 0 0 1 0 0 0"')
    model = attach_actuator_dcmotors(xml, {"servo": box_motor(2.0, 4.0)})
    p = np.array([[G * R1, G * R2]])
    drive = Drive(("a", "b"), q, np.zeros(1), np.zeros(6), (), actuators=("servo",), moment=p)
    rig = Rig(model, drive, "object")
    want = (R1 * b1 * q[0] + R2 * b2 * q[1]) / (G * (R1**2 + R2**2))
    np.testing.assert_allclose(rig.damping_share(q), [want], rtol=1e-12)


def test_gear_sweep_refuses_a_transmission() -> None:
    from mjtvm.jobs.gears import gear_sweep

    with pytest.raises(ParamError, match="gears: not available for a hand with a transmission"):
        gear_sweep(str(F85), (10.0,), num_states=2, states=(0,))


def _f85_state() -> tuple[Any, Any, Any, mujoco.MjModel]:
    """The 2F-85's lift, grasp, state 0 (L, mu 0.6, mg 0.4905 N) and its simulated model.

    Its coupler joints reach their limit after 0.99999 mm of lift (docs/joint-limits.md): at
    the default 1 mm horizon alpha_00 is 0; the linkage's witness is checked without it."""
    lift = cached_lift(F85, 2)
    grasp = lift.scenario
    state = lift_state(lift, 0, variant="L", mu=0.6, mg=0.4905)
    assert state.joint_limits is not None
    state = state.with_(joint_limits=state.joint_limits.with_options(horizon=0.0))
    model = sim_model(
        motor_model(grasp), contact_types(state), mu=0.6, mg=0.4905, object_body=grasp.object_body
    )
    return lift, grasp, state, model


def test_f85_dynamic_alpha_keeps_the_linkage_and_is_a_fixed_point() -> None:
    """The dynamic alpha of the 2F-85 (tendon actuator, linkage): the motion whose demand it takes
    keeps MuJoCo's equality rows J_eq qd = 0 at the state; alpha_dyn is a fixed point of
    alpha -> A(d(alpha)) (eq. 31 with the binding demand), at most alpha_kl when the demand costs
    torque, and the limit is named per actuator."""
    from mjtvm.physics.dynamic import dynamic_pair, joint_demand
    from mjtvm.problem2.dynamic import pair_alpha

    lift, grasp, state, model = _f85_state()
    res = tvmmp(state)
    alpha = float(res.alpha[0, 0])
    drive = witness_drive(state, 0, 0, alpha, 1.0)
    dem = joint_demand(model, lift.qpos[0], drive, object_body=grasp.object_body)
    data = mujoco.MjData(model)
    data.qpos[:] = lift.qpos[0]
    mujoco.mj_forward(model, data)
    rows = Rig(model, drive, grasp.object_body).equality_rows(data)
    assert rows.shape[0] > 0
    assert np.max(np.abs(rows @ dem.speeds)) <= 1e-9 * np.max(np.abs(dem.speeds))
    dyn = dynamic_pair(
        model, lift.qpos[0], state, 0, 0, result=res, object_body=grasp.object_body, window=0.007
    )
    assert 0 < dyn.alpha <= alpha * (1 + 1e-3)
    got = pair_alpha(state, 0, 0, dyn.demand)[0]
    assert got is not None and 0 <= got - dyn.alpha <= 2e-3 * alpha
    assert dyn.joint == 0  # the one actuator (fingers_actuator), not joint 0


def test_a_motor_driven_past_its_speed_edge_fails() -> None:
    """The 2F-85's box motor runs up to 10 % past the box's 1.25 rad/s (its no-load speed,
    BOX_SPEED_MARGIN): at 1.08 alpha the actuator passes its range's speed by more than 1 %,
    which fails the rollout ("speed edge"), though the twist, contacts and torques hold (the
    same drive passes with the edge check off); at 0.95 alpha it passes."""
    from mjtvm.physics.simulate import SimSettings, rollout
    from mjtvm.physics.verdict import failure_words

    lift, grasp, state, model = _f85_state()
    alpha = float(tvmmp(state).alpha[0, 0])
    slow = witness_drive(state, 0, 0, alpha, 0.95)
    fast = witness_drive(state, 0, 0, alpha, 1.08)
    np.testing.assert_allclose(fast.speed_limits, [1.25])
    assert rollout(model, lift.qpos[0], slow, object_body=grasp.object_body).passed
    failed = rollout(model, lift.qpos[0], fast, object_body=grasp.object_body)
    assert not failed.passed and failed.failure == ("speed edge", "fingers_actuator")
    assert "fingers_actuator" in failed.reason and "% past its range's speed" in failed.reason
    assert failure_words(failed, actuators=True) == "speed edge at actuator fingers_actuator"
    lenient = SimSettings(edge_tol=10.0)
    assert rollout(model, lift.qpos[0], fast, object_body=grasp.object_body, settings=lenient).passed
