"""MuJoCo rollouts (mjtvm.physics.simulate, mjtvm.jobs.verify): motor physics, holding still, bisection."""

from __future__ import annotations

import csv
import math

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ParamError, StateError
from mjtvm.grasp.actuation.actuator import operation_range_from_actuator
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.jobs.verify import verify_lift
from mjtvm.jobs.verify_report import summarize
from mjtvm.lift.states import lift_state
from mjtvm.lift.trajectory import Lift, scripted_lift
from mjtvm.physics.bisection import bisect
from mjtvm.physics.simulate import SimSettings, rerun_data, rollout, sim_model
from mjtvm.physics.witness import central_witness, witness_drive
from mjtvm.problem2.tvmmp import tvmmp

from ..helpers import Q_MAX, T_MAX

GEAR = 40.0


def _single_joint(timestep: float = 1e-3) -> mujoco.MjModel:
    motor = DCMotor.from_datasheet()
    xml = f"""<mujoco><option timestep="{timestep}" integrator="implicitfast" gravity="0 0 0"/>
    <worldbody><body><joint name="j" type="hinge" axis="0 0 1"/>
    <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.004" mass="0.051"/></body></worldbody>
    <actuator>{motor.mjcf("j", "j")}</actuator></mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)


def _run_joint(
    model: mujoco.MjModel, setpoint: float, load: float, seconds: float, qvel0: float = 0.0
) -> float:
    """Joint speed after ``seconds`` with a speed setpoint (joint side), ff = load, constant load torque."""
    data = mujoco.MjData(model)
    data.qvel[0] = qvel0
    data.ctrl[0] = setpoint * GEAR  # actuator-length units: joint speed x gear
    data.ctrl[1] = load / GEAR  # motor-side feedforward
    data.qfrc_applied[0] = -load
    mujoco.mj_step(model, data, nstep=round(seconds / model.opt.timestep))
    return float(data.qvel[0])


@pytest.mark.parametrize("load", [0.0, 0.25, 0.5, 0.75, 1.0])
def test_single_dcmotor_traces_the_operation_range(load: float) -> None:
    model = _single_joint()
    rng = operation_range_from_actuator(model, 0)
    speed = _run_joint(model, 1.5 * Q_MAX, load, 2.0)  # setpoint above the line: Vmax clamps
    later = _run_joint(model, 1.5 * Q_MAX, load, 2.1)
    assert abs(later - speed) < 1e-3 * Q_MAX  # steady
    assert speed == pytest.approx(rng.max_speed_at(load), rel=0.03)


def test_single_dcmotor_saturates_at_the_continuous_torque() -> None:
    model = _single_joint()
    assert T_MAX == pytest.approx(operation_range_from_actuator(model, 0).max_torque)
    assert _run_joint(model, 1.5 * Q_MAX, 1.05 * T_MAX, 1.0) < 0.0  # cannot hold a load above it


def test_bisection_finds_a_known_threshold() -> None:
    calls: list[float] = []

    def passes(x: float) -> bool:
        calls.append(x)
        return x <= 0.737

    b = bisect(passes, 0.0, 2.0, tol=1e-3)
    assert 0.737 - 1e-3 <= b.value <= 0.737 and not (b.below_bracket or b.above_bracket)
    assert b.evaluations == len(calls)
    assert bisect(lambda x: True, 0.0, 2.0).above_bracket
    assert bisect(lambda x: False, 0.0, 2.0).below_bracket
    with pytest.raises(StateError):
        bisect(passes, 1.0, 0.0)


def test_bisection_finds_the_motor_speed_limit() -> None:
    """Toy physics: setpoint s x line speed at a load is reached (1 %) iff s <= 1 / 0.99."""
    model = _single_joint(timestep=5e-4)
    load = 0.5
    line = operation_range_from_actuator(model, 0).max_speed_at(load)

    def passes(s: float) -> bool:
        speed = _run_joint(model, s * line, load, 0.15, qvel0=s * line)
        return abs(speed / (s * line) - 1.0) <= 0.01

    b = bisect(passes, 0.5, 1.5, tol=1e-3)
    assert b.value == pytest.approx(1 / 0.99, abs=2e-3)


# ------------------------------------------------------------------ the hand
@pytest.fixture(scope="module")
def lift() -> Lift:
    return scripted_lift("case2", num_states=2, height=0.004)


def test_central_witness_solves_the_lp_constraints(lift: Lift) -> None:
    state = lift_state(lift, 0, variant="L")
    res = tvmmp(state)
    alpha = float(res.alpha[0, 0]) * 0.9
    sol = central_witness(state, 0, 0, alpha)
    forces = sol["forces"]
    wrench = sum(
        np.r_[f, np.cross(c.position - state.object_position, f)] for c, f in zip(state.contacts, forces)
    )
    assert np.allclose(wrench + state.refs[0], 0.0, atol=1e-6)  # eq. 20
    tau = sum(c.jacobian.T @ f for c, f in zip(state.contacts, forces)) + state.gravity_torque
    assert np.allclose(tau, sol["torques"], atol=1e-6)  # eq. 19
    assert state.rvds is not None
    for c in state.contacts:
        if c.type == "F":  # eq. 7 at the twist alpha r_0
            v = state.rvds[0][:3] * alpha
            assert np.allclose(c.jacobian @ sol["speeds"], v, atol=1e-6)
    for rng, t, q in zip(state.operation_ranges, sol["torques"], sol["speeds"]):
        assert abs(q) <= rng.max_speed_at(min(abs(t), rng.max_torque)) + 1e-6
    vertex = res.witnesses[0][0]
    assert vertex is not None
    assert np.max(np.abs(sol["speeds"])) < np.max(np.abs(vertex.speeds))  # least motion


def test_grasp_holds_still_at_s_zero(lift: Lift) -> None:
    state = lift_state(lift, 0, variant="L")
    types = {c.name.split("#")[0]: c.type for c in state.contacts}
    model = sim_model(lift.scenario.model, types, mu=0.3)
    alpha = float(tvmmp(state, witnesses=False).alpha[0, 0])
    res = rollout(model, lift.qpos[0], witness_drive(state, 0, 0, alpha, 0.0), record=True)
    assert res.passed, res.reason
    assert res.settle_drift < 5e-5  # m over the 30 ms settle
    assert np.max(np.linalg.norm(res.trace["twist"], axis=1)) < 2e-3  # m/s
    assert res.gap < 0.0 and not res.saturated  # every finger still pressing
    logged = rerun_data(res)
    assert logged["rollout/object/position"]["positions"].shape == (len(res.trace["time"]), 3)


def test_rollout_fails_far_above_the_lp(lift: Lift) -> None:
    state = lift_state(lift, 0, variant="L")
    types = {c.name.split("#")[0]: c.type for c in state.contacts}
    model = sim_model(lift.scenario.model, types, mu=0.3)
    alpha = float(tvmmp(state, witnesses=False).alpha[0, 0])
    res = rollout(model, lift.qpos[0], witness_drive(state, 0, 0, alpha, 2.0))
    assert not res.passed and res.reason


def test_sim_model_contacts_and_mass(lift: Lift) -> None:
    types = {"f1_tip": "F", "f2_tip": "L", "f3_tip": "F", "f4_tip": "S", "palm": "D"}
    model = sim_model(lift.scenario.model, types, mu=0.4, mg=2.0, settings=SimSettings(cone="pyramidal"))
    assert model.opt.cone == int(mujoco.mjtCone.mjCONE_PYRAMIDAL)
    condim = {g: int(model.geom(g).condim[0]) for g in types}
    assert condim == {"f1_tip": 3, "f2_tip": 1, "f3_tip": 3, "f4_tip": 3, "palm": 1}
    assert model.geom("f1_tip").friction[0] == pytest.approx(0.4)
    assert model.body("object").mass[0] * 9.81 == pytest.approx(2.0)
    with pytest.raises(ParamError, match=r"^window: "):
        SimSettings(window=0.0)


def test_verify_lift_serial_and_parallel_agree(tmp_path) -> None:  # type: ignore[no-untyped-def]
    opts = {"num_states": 2, "runs": ("L",), "progress": False}
    serial = verify_lift(out=tmp_path, **opts)  # type: ignore[arg-type]
    assert (tmp_path / "verify.csv").exists() and (tmp_path / "verify.png").exists()
    parallel = verify_lift(out=None, jobs=2, start_method="spawn", **opts)  # type: ignore[arg-type]
    assert [r["alpha_sim"] for r in serial] == [r["alpha_sim"] for r in parallel]
    with (tmp_path / "verify.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 8 and all(math.isfinite(float(r["ratio"])) for r in rows)
    summary = summarize(serial)["L"]
    assert summary["pairs"] == 8 and 0.0 < summary["median"] <= 2.0


def test_monotone_flips_on_known_pass_fail_functions() -> None:
    """A step at 0.737 is monotone about its threshold; a pass window above it (about the
    grid's 1.2 (s* + 0.01)) and a failing dip below it (0.58 to 0.62, about 0.8 s*) are named
    at the grid's speeds; a censored bisection has no threshold to check."""
    from mjtvm.physics.bisection import MONOTONE_GRID, bisect, monotone_flips

    def step(s: float) -> bool:
        return s <= 0.737

    b = bisect(step)
    assert 0.727 <= b.value <= 0.737 and monotone_flips(b, step) == []
    above = 1.2 * (b.value + 0.01)
    tried: list[float] = []

    def window(s: float) -> bool:
        tried.append(s)
        return s <= 0.737 or abs(s - above) < 0.005

    b2 = bisect(window)  # the bisection's midpoints miss the window
    assert b2 == b
    tried.clear()
    assert monotone_flips(b2, window) == [f"passes at s = {above:.3g}"]
    assert len(tried) == len(MONOTONE_GRID)

    def dip(s: float) -> bool:
        return s <= 0.737 and not 0.58 <= s <= 0.62

    b = bisect(dip)
    assert monotone_flips(b, dip) == [f"fails at s = {0.8 * b.value:.3g}"]
    assert monotone_flips(bisect(lambda s: True), step) is None
    assert monotone_flips(bisect(lambda s: False), step) is None


def test_shared_settle_and_early_stop_give_the_full_rollouts_verdicts(lift: Lift) -> None:
    """Differential: the speed test's shortcuts (mjtvm.physics.grasp_sim) against the plain calls."""
    from mjtvm.physics.grasp_sim import faster_drive
    from mjtvm.physics.simulate import SettleCache

    state = lift_state(lift, 0, variant="L")
    types = {c.name.split("#")[0]: c.type for c in state.contacts}
    model = sim_model(lift.scenario.model, types, mu=0.3)
    alpha = float(tvmmp(state, witnesses=False).alpha[0, 0])
    at_one = witness_drive(state, 0, 0, alpha, 1.0)
    fast, plain = faster_drive(at_one, state, 0, alpha, 2.0), witness_drive(state, 0, 0, alpha, 2.0)
    for name in ("speeds", "torques", "twist"):  # the same numbers, bit for bit, without the QP
        assert np.array_equal(getattr(fast, name), getattr(plain, name))
    assert fast.slips.keys() == plain.slips.keys() and fast.contacts == plain.contacts
    cache = SettleCache()
    slow = witness_drive(state, 0, 0, alpha, 0.5)
    for drive in (slow, at_one, fast):
        full = rollout(model, lift.qpos[0], drive)
        short = rollout(model, lift.qpos[0], drive, stop_early=True, settled=cache)
        assert (short.passed, short.reason, short.settle_drift) == (
            full.passed,
            full.reason,
            full.settle_drift,
        )
        if full.passed:  # nothing stopped early: every maximum is the full run's
            assert (short.speed_error, short.angle_error, short.gap) == (
                full.speed_error,
                full.angle_error,
                full.gap,
            )
    assert rollout(model, lift.qpos[0], slow, settled=cache).passed
    assert not short.passed  # twice alpha fails (test_rollout_fails_far_above_the_lp)
    with pytest.raises(ParamError, match=r"^s: "):
        faster_drive(at_one, state, 0, alpha, 1.0)
