"""The second drive of the dynamic alpha (mjtvm.physics.feedforward) on the one-joint pusher of
``test_push`` (a block pushed against its 2 N weight by a frictionless tip)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mjtvm.errors import ParamError
from mjtvm.model.transmission import Transmission
from mjtvm.physics.dynamic import demand_of, dynamic_pair
from mjtvm.physics.feedforward import alpha_sim_ff, feedforward_drive
from mjtvm.physics.settings import SimSettings
from mjtvm.physics.witness import central_witness
from mjtvm.problem2.tvmmp import tvmmp
from tests.physics.test_push import F0, L, pusher

Q = 0.9


def _pair() -> tuple[object, np.ndarray, object, float, float]:
    model, qpos, state = pusher(Q)
    a_kl = float(tvmmp(state).alpha[0, 0])
    st = SimSettings()
    a_dyn = dynamic_pair(model, qpos, state, 0, 0, object_body="object", window=st.startup + st.window).alpha
    return model, qpos, state, a_kl, a_dyn


def test_the_drive_is_the_dynamic_lps_witness_without_its_demand() -> None:
    """Below alpha_dyn: the torque is the loaded state's central witness minus the demand,
    i.e. the tip's 2 N times the lever l cos q (gravity off the link), whatever the demand;
    the speed and the twist are those of s alpha_kl."""
    model, qpos, state, a_kl, a_dyn = _pair()
    demand = demand_of(model, qpos, state, 0, 0, a_kl, object_body="object")
    s = 0.5 * a_dyn / a_kl
    drive = feedforward_drive(state, 0, 0, a_kl, a_dyn, s, demand)
    d = demand(s * a_kl)
    assert d[0] > 0.05  # a demand that matters at this speed (N m)
    loaded = state.with_(gravity_torque=state.gravity_torque + d)
    w = central_witness(loaded, 0, 0, s * a_kl * (1 - 1e-7))
    np.testing.assert_allclose(drive.torques, w["torques"] - d, rtol=1e-9, atol=1e-12)
    assert drive.torques[0] == pytest.approx(F0 * L * math.cos(Q), rel=1e-6)
    np.testing.assert_allclose(drive.twist, s * a_kl * np.array([1.0, 0, 0, 0, 0, 0]))
    assert drive.speeds[0] == pytest.approx(s * a_kl / (L * math.cos(Q)), rel=1e-6)


def test_past_alpha_dyn_the_forces_stay_those_at_alpha_dyn() -> None:
    model, qpos, state, a_kl, a_dyn = _pair()
    demand = demand_of(model, qpos, state, 0, 0, a_kl, object_body="object")
    at = feedforward_drive(state, 0, 0, a_kl, a_dyn, a_dyn / a_kl, demand)
    past = feedforward_drive(state, 0, 0, a_kl, a_dyn, 1.5 * a_dyn / a_kl, demand)
    np.testing.assert_allclose(past.torques, at.torques, rtol=1e-6)
    assert past.speeds[0] == pytest.approx(1.5 * at.speeds[0], rel=1e-6)
    rest = feedforward_drive(state, 0, 0, a_kl, a_dyn, 0.0, demand)
    assert rest.speeds[0] == 0.0 and rest.torques[0] == pytest.approx(F0 * L * math.cos(Q), rel=1e-6)


def test_alpha_sim_under_the_second_drive_is_a_bisection_of_its_rollouts() -> None:
    """A threshold inside the bracket, the rollout just above it failing; with the rotor's
    torque fed forward the motor saturates below alpha_dyn here (docs/dynamics.md)."""
    model, qpos, state, a_kl, a_dyn = _pair()
    a_ff, b, fail = alpha_sim_ff(model, qpos, state, 0, 0, a_kl, a_dyn, object_body="object")
    assert not (b.below_bracket or b.above_bracket) and not fail.passed
    assert a_ff == pytest.approx(b.value * a_kl)
    assert fail.failure[0] == "torque limit"
    assert 0.5 * a_dyn < a_ff < a_dyn


def test_no_second_drive_without_joint_torques_or_a_dynamic_alpha() -> None:
    model, qpos, state, a_kl, _a_dyn = _pair()
    with pytest.raises(ParamError, match=r"alpha_dyn.*expected a positive dynamic alpha"):
        alpha_sim_ff(model, qpos, state, 0, 0, a_kl, 0.0, object_body="object")
    coupled = state.with_(transmission=Transmission(("a",), np.array([[1.0]])))
    with pytest.raises(ParamError, match=r"dynamics.*needs joint torques"):
        alpha_sim_ff(model, qpos, coupled, 0, 0, a_kl, 1.0, object_body="object")


def test_a_witness_the_solvers_miss_is_a_row_note_not_a_crash(monkeypatch: pytest.MonkeyPatch) -> None:
    import mjtvm.physics.check as check
    from mjtvm.errors import SolverError

    model, qpos, state, a_kl, _a_dyn = _pair()
    res = tvmmp(state)

    def fails(*_: object, **__: object) -> None:
        raise SolverError("clarabel", "MaxIterations")

    monkeypatch.setattr(check, "alpha_sim_ff", fails)
    row = check.dynamic_row(model, qpos, state, 0, res, a_kl, a_kl, "central", None, "object", 0.9)
    assert math.isnan(row["alpha_sim_ff"]) and row["ff_verdict"].startswith("no witness: ")
    assert row["alpha_dyn"] > 0  # the rest of the dynamic columns stand
