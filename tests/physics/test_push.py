"""The physics check on a hand-built case whose answer is known: a one-joint finger pushing a
block against its weight (issue 35's acceptance).

The pusher of ``test_dynamic`` (a hinge about +y, a link of l = 0.1 m, a frictionless L tip
at its end) pushes a free block along +x, now against gravity along -x (block weight 2 N,
the REFS): the tip needs the force 2 N, the joint the torque 2 l cos q, and the operation
range is the motor's own (the dcmotor's no-load speed 1001.12 / 40 rad/s, stall torque
0.2044 x 40 N m, current limit 0.0263 x 40 N m), so that Problem 2's alpha_kl is the speed
the motor's line allows at that torque: alpha_kl = l cos q w0 (1 - 2 l cos q / tau_s).
Where the rotor's demand is small (q = 0.6) the simulated speed limit is the LP's; where it
is not (q = 0.9, the demand grows as 1 / cos^3 q) the torque saturates below alpha_kl and the
ratio says why.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.physics.bisection import alpha_sim
from mjtvm.physics.check import pair_check
from mjtvm.physics.settings import sim_model
from mjtvm.physics.simulate import rollout
from mjtvm.physics.witness import witness_drive
from mjtvm.problem2.tvmmp import tvmmp
from tests.physics.test_dynamic import L
from tests.physics.test_dynamic import model as pusher_model
from tests.physics.test_dynamic import state as pusher_state

F0 = 2.0  # N: the block's weight
W0, TAU_S, TAU_C = 1001.120859 / 40, 0.2044130081 * 40, 0.0263 * 40  # rad/s, N m, N m (joint side)


def pusher(q: float) -> tuple[mujoco.MjModel, np.ndarray, GraspState]:
    """The simulated model (frictionless tip), its configuration and the grasp state at ``q``."""
    raw, qpos = pusher_model(q, gravity="-9.81 0 0", block_mass=F0 / 9.81)
    model = sim_model(raw, {"tip": "L"}, mu=0.0, object_body="object")
    motor = OperationRange([[0, 0], [TAU_C, 0], [TAU_C, W0 * (1 - TAU_C / TAU_S)], [0, W0]])
    state = pusher_state(q, F0).with_(operation_ranges=(motor,))
    return model, qpos, state


def test_alpha_kl_is_the_motor_line_at_the_pushing_torque() -> None:
    q = 0.6
    _m, _qpos, state = pusher(q)
    lc = L * math.cos(q)
    assert float(tvmmp(state).alpha[0, 0]) == pytest.approx(lc * W0 * (1 - F0 * lc / TAU_S), rel=1e-9)


def test_the_simulated_speed_limit_is_the_lps() -> None:
    """q = 0.6: alpha_sim within 1 % of alpha_kl; just above it the finger, at its motor's
    speed, falls behind the block (contact lost)."""
    model, qpos, state = pusher(0.6)
    a_sim, a_kl, b = alpha_sim(model, qpos, state, 0, 0, object_body="object", tol=0.002)
    assert not (b.below_bracket or b.above_bracket)
    assert a_sim / a_kl == pytest.approx(1.0, abs=0.01)
    above = rollout(model, qpos, witness_drive(state, 0, 0, a_kl, b.value + 0.01), object_body="object")
    assert above.failure[0] == "contact lost"


def test_rotor_inertia_is_the_cause_where_the_demand_grows() -> None:
    """q = 0.9: the rotor's demand (1 / cos^3 q) saturates the torque below alpha_kl, and the
    row's cause says so, with the inertial torque."""
    model, qpos, state = pusher(0.9)
    res = tvmmp(state)
    row = pair_check(
        model, qpos, state, res, 0, settings=None, witness="central", object_body="object",
        check_s=0.9, dynamics=False, launch_distance=None,
    )  # fmt: skip
    assert row["ratio"] < 0.9
    assert row["verdict"] == "torque limit at joint q"
    assert row["cause"].startswith("rotor inertia: ") and row["inertia_joint"] == "q"
    assert row["inertia_max"] > 0.1 * TAU_C  # the demand is a sizeable share of the torque limit
