"""The physics check's hold drive (mjtvm.physics.hold_drive) on the hand-built pinch of test_squeeze.

The pinch moved along x (RVDS +-x): finger 1 pushes the box and finger 2 is pushed back, both
motors at the box's speed v, each finger's normal force N carrying half the weight by friction
(2 mu N >= m g). Known answers:

* alpha_kl = W0 (1 - N_min / TAU_S), N_min = m g / (2 mu): the motor's speed-torque line at the
  least force that holds the weight (the LP's friction, mu = 0.6);
* the squeeze at speed s alpha_kl presses with the least of F_c and the line's torque at that
  speed, TAU_S (1 - s alpha_kl / W0): none beyond the witness's at alpha_kl (no torque room),
  F_c at half the speed;
* with the simulation's friction at 0.3 the witness's least forces (N_w, 2 x 0.3 N_w < m g)
  let the box slide at rest, and the squeeze's (2 x 0.3 N > m g) hold it: ``auto`` checks the
  state with the squeeze, whose rollouts give alpha_sim / alpha_kl within the tolerance, and
  ``least`` stops it at the hold test;
* with friction 0.15 neither holds: ``auto`` reports the squeeze's failed hold.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from mjtvm.errors import ParamError
from mjtvm.physics.check import pair_check
from mjtvm.physics.hold_drive import check_hold, squeezed_drive
from mjtvm.physics.squeeze import squeeze_drive
from mjtvm.physics.witness import witness_drive
from mjtvm.problem2.tvmmp import tvmmp
from tests.physics.test_squeeze import MASS, MU, TAU_C, TAU_S, W0, G, pinch

N_MIN = MASS * G / (2 * MU)  # N: the least normal force per finger that holds the weight


@pytest.fixture(scope="module")
def sideways() -> tuple[Any, Any, Any]:
    _model, qpos, state = pinch()
    state = dataclasses.replace(state, rvds=np.array([[1.0, 0, 0, 0, 0, 0], [-1.0, 0, 0, 0, 0, 0]]))
    return qpos, state, tvmmp(state, witnesses=True)


def test_alpha_is_the_motor_line_at_the_least_holding_force(sideways: Any) -> None:
    _qpos, _state, res = sideways
    assert res.alpha[0] == pytest.approx([W0 * (1 - N_MIN / TAU_S)] * 2, rel=1e-6)


def test_the_squeeze_at_speed_has_the_torque_room_of_the_motor_line(sideways: Any) -> None:
    _qpos, state, res = sideways
    alpha = float(res.alpha[0, 0])
    at_rest = squeeze_drive(state, res)
    assert at_rest is not None
    assert squeezed_drive(state, 0, 0, alpha, 0.0).torques == pytest.approx(at_rest.torques, rel=1e-9)
    for s, room in ((0.5, TAU_C), (0.99, TAU_S * (1 - 0.99 * alpha / W0)), (1.0, N_MIN)):
        tau_w = witness_drive(state, 0, 0, alpha, s).torques
        tau = squeezed_drive(state, 0, 0, alpha, s).torques
        # tau = tau_w + 1/2 (tau_sq - tau_w), tau_sq pressing each finger with the room left
        assert np.abs(2 * tau - tau_w) == pytest.approx([room, room], rel=1e-4), s
        assert np.all(np.abs(tau) >= np.abs(tau_w) * (1 - 1e-6))
    above = squeezed_drive(state, 0, 0, alpha, 1.2)  # above alpha_kl: the torques of s = 1
    one = squeezed_drive(state, 0, 0, alpha, 1.0)
    assert above.torques == pytest.approx(one.torques) and above.speeds == pytest.approx(1.2 * one.speeds)


def test_auto_checks_with_the_squeeze_where_the_least_forces_let_go(sideways: Any) -> None:
    qpos, state, res = sideways
    model, _q, _s = pinch(mu=0.3)
    least = squeeze_drive(state, res, share=0.0)
    assert least is not None and 2 * 0.3 * np.abs(least.torques).min() < MASS * G
    hold, used = check_hold(model, qpos, state, res, hold_drive="least")
    assert used == "least" and hold is not None and not hold.held and hold.reach > 5e-4
    hold, used = check_hold(model, qpos, state, res)  # auto
    assert used == "squeeze" and hold is not None and hold.held and hold.reach < 1e-4
    for l in range(2):
        row = pair_check(
            model, qpos, state, res, l, settings=None, witness="central", object_body="object",
            check_s=0.9, dynamics=False, launch_distance=None, squeeze=True,
        )  # fmt: skip
        assert 0.95 <= row["ratio"] <= 1.05 and row["pass_check"], row
        assert row["verdict"].startswith("speed edge at joint"), row  # the motor line, not the hold


def test_where_not_even_the_squeeze_holds_auto_reports_its_hold(sideways: Any) -> None:
    qpos, state, res = sideways
    model, _q, _s = pinch(mu=0.15)
    hold, used = check_hold(model, qpos, state, res)
    assert used == "squeeze" and hold is not None and not hold.held
    with pytest.raises(ParamError, match="hold_drive"):
        check_hold(model, qpos, state, res, hold_drive="tight")  # type: ignore[arg-type]
