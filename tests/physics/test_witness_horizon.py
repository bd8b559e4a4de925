"""The rollout witness keeps Problem 2's travel horizon (mjtvm.physics.witness, docs/joint-limits.md):
hand-derived least-motion speeds of the planar finger of tests/model/test_limits.py with the
horizon row of its first joint active."""

from __future__ import annotations

import numpy as np
import pytest

from mjtvm.model.limits import JointLimits, travel_speed
from mjtvm.physics.witness import central_witness
from tests.model.test_limits import finger


def test_central_witness_keeps_the_horizon_bound() -> None:
    """Two joints, 0.1 (qd1 + qd2) = alpha up, each weighted 1 / 2^2: the least motion is
    qd1 = qd2 = 5 alpha. Joint 1 is sigma = 0.025 rad below its upper limit with H = 0.01 m and
    s = 1 per unit alpha: H qd1 <= sigma s alpha caps it at 2.5 alpha, so qd = (2.5, 7.5) alpha
    (qd2 = 7.5 alpha <= 2 up to alpha_kl = 4/15). Down, the lower limits are far: -5 alpha each."""
    lim = JointLimits([0.975, 0.0], [-1.0, -1.0], [1.0, 1.0], horizon=0.01)
    state = finger(2, lim)
    assert state.rvds is not None
    up = state.rvds[0]
    assert travel_speed(state, up) == pytest.approx(1.0)
    alpha = 0.2
    qd = central_witness(state, 0, 0, alpha)["speeds"]
    assert qd == pytest.approx([2.5 * alpha, 7.5 * alpha], rel=1e-6)
    h, s = lim.horizon, travel_speed(state, up)
    assert np.all(h * qd <= lim.upper_slack * s * alpha * (1 + 1e-7))
    assert h * qd[0] == pytest.approx(lim.upper_slack[0] * s * alpha, rel=1e-6)  # active
    assert np.all(-h * qd <= lim.lower_slack * s * alpha)
    qd = central_witness(state, 0, 1, alpha)["speeds"]
    assert qd == pytest.approx([-5 * alpha, -5 * alpha], rel=1e-6)
    # Without the horizon (H = 0) the least motion is the unbounded one.
    free = finger(2, lim.with_options(horizon=0.0))
    assert central_witness(free, 0, 0, alpha)["speeds"] == pytest.approx([5 * alpha, 5 * alpha], rel=1e-6)
