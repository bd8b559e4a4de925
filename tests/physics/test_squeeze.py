"""The squeeze and the hold test's position loop (mjtvm.physics.squeeze) on a hand-built pinch.

Two fingers on slide joints along x (finger 1 at -x pushing +x, finger 2 at +x pushing -x), each
a sphere tip (F contact, mu = 0.6) on a face of a free box of mass m = 0.02 kg under gravity -z,
each driven by the dcmotor of ``test_push`` (joint side: continuous force F_c = 0.0263 x 40 N,
damping k_v gear^2 = 0.0005 x 40^2 = 0.8 N s/m). Known answers:

* the squeeze at rest presses both fingers with F_c (the motors' force at zero speed), each
  carrying half the weight by friction;
* the central witness alone presses each finger with the least forces (the least-norm
  generators) that carry the weight, 2 mu N < m (g + 10): a push along -z slides the box
  out; with the squeeze (half of F_c beyond them), 2 mu N > m (g + 10) holds;
* along x the pinch is a mechanism: the push m 10 is resisted only by the loop's stiffness
  2 k_v gear^2 kp (the box settles at m 10 / (2 k_v gear^2 kp)) or, without a loop, by the
  motors' damping (it drifts at m 10 / (2 k_v gear^2), past the 5 cm bound within 0.4 s);
* with friction 0.05 in the simulation even the full squeeze, 2 x 0.05 F_c < m g, cannot hold
  the weight at rest.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ParamError
from mjtvm.model.contacts import Contact
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.physics.disturb import DIRECTIONS, disturb_test
from mjtvm.physics.hold import hold_test, state_hold
from mjtvm.physics.settings import sim_model
from mjtvm.physics.squeeze import SERVO_GAIN, squeeze_drive, squeeze_witness, with_position_loop
from mjtvm.problem2.tvmmp import tvmmp

HALF, R_TIP, MASS, MU, G = 0.02, 0.005, 0.02, 0.6, 9.81
W0, TAU_S, TAU_C = 1001.120859 / 40, 0.2044130081 * 40, 0.0263 * 40  # rad/s, N, N (joint side)
DAMPING = 0.0005 * 40**2  # N s/m: the motor's k_v gear^2 at the joint

_FINGER = """
    <body name="finger{i}" pos="{x} 0 0">
      <joint name="q{i}" type="slide" axis="{ax} 0 0"/>
      <geom name="tip{i}" type="sphere" size="{r}" mass="0.001"/>
    </body>"""
_MOTOR = """
    <dcmotor name="q{i}" joint="q{i}" gear="40" nominal="24 0.2044130081 1001.120859"
             saturation="0.0263 0 0" armature="1e-8" input="vel ff" controller="0 0 0.0005 0 0 24"/>"""


def pinch(mu: float = MU) -> tuple[mujoco.MjModel, np.ndarray, GraspState]:
    """The simulated pinch (friction ``mu``), its configuration and the grasp state."""
    fingers = "".join(_FINGER.format(i=i, x=s * (HALF + R_TIP), ax=-s, r=R_TIP) for i, s in ((1, -1), (2, 1)))
    xml = f"""
<mujoco>
  <option timestep="0.00025" gravity="0 0 -{G}"/>
  <worldbody>{fingers}
    <body name="object">
      <freejoint/>
      <geom name="box" type="box" size="{HALF} {HALF} {HALF}" mass="{MASS}"/>
    </body>
  </worldbody>
  <actuator>{_MOTOR.format(i=1)}{_MOTOR.format(i=2)}</actuator>
</mujoco>"""
    raw = mujoco.MjModel.from_xml_string(xml)
    model = sim_model(raw, {"tip1": "F", "tip2": "F"}, mu=mu, mg=MASS * G, object_body="object")
    motor = OperationRange([[0, 0], [TAU_C, 0], [TAU_C, W0 * (1 - TAU_C / TAU_S)], [0, W0]])
    contacts = tuple(
        Contact(f"tip{i}", "F", [-s * HALF, 0, 0], [s, 0, 0], np.outer([s, 0, 0], np.eye(2)[i - 1]), mu=MU)
        for i, s in ((1, 1.0), (2, -1.0))
    )
    state = GraspState(
        space=3,
        object_position=np.zeros(3),
        joint_names=("q1", "q2"),
        operation_ranges=(motor, motor),
        gravity_torque=[0.0, 0.0],
        contacts=contacts,
        refs=[[0, 0, -MASS * G, 0, 0, 0]],
        rvds=[[0, 0, 1.0, 0, 0, 0]],
    )
    return model, raw.qpos0.copy(), state


@pytest.fixture(scope="module")
def case() -> tuple[mujoco.MjModel, np.ndarray, GraspState, object]:
    model, qpos, state = pinch()
    return model, qpos, state, tvmmp(state, witnesses=True)


def test_the_squeeze_presses_with_the_motors_force_at_zero_speed(case: tuple) -> None:
    _m, _q, state, _res = case
    sq = squeeze_witness(state)
    assert sq["least"] == pytest.approx(TAU_C, rel=1e-6)
    assert sq["total"] == pytest.approx(2 * TAU_C, rel=1e-6)
    f = sq["forces"]
    assert f[:, 2].sum() == pytest.approx(MASS * G, rel=1e-6)  # friction carries the weight
    assert f[0, 0] == pytest.approx(TAU_C, rel=1e-6) and f[1, 0] == pytest.approx(-TAU_C, rel=1e-6)
    assert np.abs(sq["torques"]) == pytest.approx([TAU_C, TAU_C], rel=1e-6)


def test_the_squeeze_holds_the_push_and_the_least_forces_do_not(case: tuple) -> None:
    model, qpos, state, res = case
    rest = squeeze_drive(state, res, share=0.0)
    sq = squeeze_drive(state, res)
    assert rest is not None and sq is not None
    # the central witness's least forces carry the weight, not the weight and the push; the
    # squeeze's do: friction 2 mu N against m (g + 10)
    assert 2 * MU * np.abs(rest.torques).min() < MASS * (G + 10.0) < 2 * MU * np.abs(sq.torques).min()
    assert 2 * MU * np.abs(rest.torques).min() > MASS * G
    assert np.abs(sq.torques) == pytest.approx(
        np.abs(rest.torques) + 0.5 * (TAU_C - np.abs(rest.torques)), rel=1e-3
    )
    with_sq = disturb_test(model, qpos, sq, servo=SERVO_GAIN, duration=0.6)
    assert with_sq.held, with_sq
    # along x only the loop's stiffness resists: the box settles at m 10 / (2 k_v gear^2 kp)
    settle_x = MASS * 10.0 / (2 * DAMPING * SERVO_GAIN)
    dx = dict(zip(DIRECTIONS, with_sq.translation, strict=True))
    assert dx["-x"] == pytest.approx(settle_x, rel=0.1) and dx["+x"] == pytest.approx(settle_x, rel=0.1)
    least = disturb_test(model, qpos, rest, servo=SERVO_GAIN, duration=0.6)
    assert not dict(zip(DIRECTIONS, least.directions, strict=True))["-z"]  # slides out downwards
    # without the loop the x push meets the motors' damping only: 0.2 s at m 10 / (2 k_v gear^2)
    # (0.125 m/s: 25 cm in the benchmark's 2 s)
    damper = disturb_test(model, qpos, sq, servo=0.0, duration=0.2)
    drift = MASS * 10.0 / (2 * DAMPING) * 0.2
    assert damper.translation[0] == pytest.approx(drift, rel=0.1) and damper.translation[4] < 2e-3


def test_too_little_friction_cannot_hold_at_rest(case: tuple) -> None:
    _m, qpos, state, res = case
    slippery, _q, _s = pinch(mu=0.05)
    sq = squeeze_drive(state, res)
    assert sq is not None and 2 * 0.05 * TAU_C < MASS * G
    out = hold_test(slippery, qpos, sq, servo=SERVO_GAIN)
    assert not out.held and out.translation > 5e-4
    assert disturb_test(slippery, qpos, sq, servo=SERVO_GAIN, duration=0.2).held_count == 1  # +z only
    with pytest.raises(ParamError, match="share"):
        squeeze_drive(state, res, share=1.5)
    with pytest.raises(ParamError, match="servo"):
        disturb_test(slippery, qpos, sq, servo=-1.0, duration=0.2)
    assert math.isfinite(out.drift)


def test_state_hold_with_the_squeeze_holds_the_pinch(case: tuple) -> None:
    model, qpos, state, res = case
    out = state_hold(model, qpos, state, res, squeeze=True, duration=0.3)
    assert out is not None and out.held and out.translation < 5e-4, out  # MuJoCo's soft friction creeps
    forces = [c.force_end for c in out.contacts]  # each finger presses with the squeeze's force
    tau = np.abs(squeeze_drive(state, res).torques)  # type: ignore[union-attr]
    assert forces == pytest.approx(tau, rel=0.02)


def test_the_native_position_loop_commands_the_servos_torque(case: tuple) -> None:
    # at one state (fingers off the held configuration, moving), the dcmotor controller with
    # k_p = gain k_d, speed setpoint 0 and feedforward tau + k_p l_0 commands what `Servo`'s
    # speed setpoint gain (l_0 - l) does: k_d gain (l_0 - l) - k_d l' + tau (no clamp reached)
    model, qpos, _state, _res = case
    acts = np.arange(model.nu // 2)
    cadr = model.actuator_ctrladr[acts]
    native = with_position_loop(model, acts, SERVO_GAIN)
    kd = model.actuator_gainprm[acts, 6]
    assert np.array_equal(native.actuator_gainprm[acts, 4], SERVO_GAIN * kd)
    assert not np.any(model.actuator_gainprm[acts, 4])  # the model itself is not changed
    assert with_position_loop(model, acts, 0.0) is model
    d = mujoco.MjData(model)
    d.qpos[:] = qpos
    mujoco.mj_forward(model, d)
    l0 = d.actuator_length[acts].copy()
    ff = np.array([2e-3, -1e-3])
    d.qpos[model.jnt_qposadr[:2]] += [0.02, -0.01]
    d.qvel[model.jnt_dofadr[:2]] = [0.3, 0.1]
    mujoco.mj_forward(model, d)  # the lengths at this state
    d.ctrl[cadr] = SERVO_GAIN * (l0 - d.actuator_length[acts])  # what Servo.step sets ...
    d.ctrl[cadr + 1] = ff
    mujoco.mj_forward(model, d)  # ... at this step's lengths
    servo = d.actuator_force[acts].copy()
    l, ldot = d.actuator_length[acts].copy(), d.actuator_velocity[acts].copy()
    d.ctrl[cadr] = 0.0
    d.ctrl[cadr + 1] = ff + native.actuator_gainprm[acts, 4] * l0
    mujoco.mj_forward(native, d)
    closed = kd * SERVO_GAIN * (l0 - l) - kd * ldot + ff
    assert np.all(np.abs(closed) < model.actuator_forcerange[acts, 1])  # below the saturation
    assert np.allclose(d.actuator_force[acts], closed, rtol=1e-12, atol=0.0)
    assert np.allclose(servo, closed, rtol=1e-12, atol=0.0)
    with pytest.raises(ParamError, match="servo"):
        with_position_loop(model, acts, -1.0)


def test_a_shared_witness_problem_gives_the_same_drive(case: tuple) -> None:
    # grasp_sim's hold drive shares the speed test's QP set-up: the same drive to the bit;
    # a problem of another reference wrench is refused.
    from mjtvm.errors import ParamError
    from mjtvm.physics.witness import WitnessProblem

    _m, _q, state, res = case
    alone = squeeze_drive(state, res)
    shared = squeeze_drive(state, res, problem=WitnessProblem(state, 0))
    assert alone is not None and shared is not None
    assert np.array_equal(alone.torques, shared.torques) and np.array_equal(alone.speeds, shared.speeds)
    assert np.array_equal(alone.twist, shared.twist)
    other = WitnessProblem(state, 0)
    other.k = 1
    with pytest.raises(ParamError, match="WitnessProblem of this state and k = 0"):
        squeeze_drive(state, res, problem=other)
