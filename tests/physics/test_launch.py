"""The launch from rest (mjtvm.physics.launch): the command ramped from 0 to alpha_kl over the
stated distance; what the object reaches, and where the grasp gives out."""

from __future__ import annotations

from typing import Any

import pytest

from mjtvm.errors import ParamError
from mjtvm.jobs import verify
from mjtvm.lift.states import lift_state
from mjtvm.physics.launch import LAUNCH_DISTANCE, launch
from mjtvm.physics.simulate import SimSettings, sim_model
from mjtvm.physics.witness import witness_drive
from mjtvm.problem2.tvmmp import tvmmp


def _pair(grasp: str, l: int, mu: float, mg: float) -> tuple[Any, Any, Any, float, str]:
    lift = verify.checked_lift(grasp, 2)
    state = lift_state(lift, 0, variant="L", mu=mu, mg=mg)
    res = tvmmp(state)
    ob = lift.scenario.object_body
    types = {c.name.split("#")[0]: c.type for c in state.contacts}
    model = sim_model(verify.motor_model(lift.scenario), types, mu=mu, mg=mg, object_body=ob)
    alpha = float(res.alpha[0, l])
    return model, lift.qpos[0], witness_drive(state, 0, l, alpha, 1.0), alpha, ob


def test_the_allegro_reaches_its_lp_speed_from_rest() -> None:
    """A slow, damping-limited hand (alpha_kl 0.063 m/s along +y): the ramp's acceleration
    (alpha^2 / 2D = 1 m/s^2) is within what its motors give, so the object covers the 2 mm with
    the command: it reaches alpha_kl (within the twist tolerance) at t = 2D / alpha_kl."""
    model, qpos, drive, alpha, ob = _pair("allegro-ik", 2, 0.6, 0.981)
    out = launch(model, qpos, drive, distance=0.002, object_body=ob)
    assert out.verdict == "reached" and out.reached and out.distance == pytest.approx(0.002)
    assert 0.9 * alpha <= out.speed <= 1.1 * alpha
    # an object following the ramp covers D at t_r = 2D / alpha; it lags a little behind it
    assert 2 * 0.002 / alpha <= out.time <= 1.2 * 2 * 0.002 / alpha


def test_the_paper_hand_loses_its_grip_on_the_way() -> None:
    """The paper's hand (the RE 25's rotor through 40:1, 1.73e-3 kg m^2 per joint): its speed
    loops lag the ramp by different amounts on the two F-fingers, which slide on the sphere
    before the object covers 10 mm; the launch names the contact and the speed reached."""
    model, qpos, drive, alpha, ob = _pair("case2", 0, 0.3, 1.0)
    out = launch(model, qpos, drive, object_body=ob)
    assert out.target == LAUNCH_DISTANCE
    assert out.verdict in ("slip at contact f1_tip", "slip at contact f3_tip")
    assert 0.0 < out.speed < 0.5 * alpha and out.distance < LAUNCH_DISTANCE


def test_bad_launch_distance() -> None:
    model, qpos, drive, _alpha, ob = _pair("allegro-ik", 2, 0.6, 0.981)
    with pytest.raises(ParamError, match=r"distance: expected a positive length"):
        launch(model, qpos, drive, distance=-1.0, object_body=ob, settings=SimSettings())
