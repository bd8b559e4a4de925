"""LP backends: HiGHS must certify every LP it is given, and agree with Clarabel."""

from __future__ import annotations

import numpy as np
import pytest

from mjtvm import tvmmp
from mjtvm.trajectory import lift_state, scripted_lift


@pytest.fixture(scope="module")
def lift():
    return scripted_lift(num_states=30)


def test_highs_settles_stalled_lps_on_the_lift(lift):
    """Under the physical slide reading most S-point lift states are infeasible; on some of
    them a warm-started HiGHS dual simplex stops with 'Unknown' (state 15 of this lift) and a
    cold primal simplex with 'Solve error'. The cold-start retries must certify every LP, with
    the same verdicts and alphas as Clarabel's interior point."""
    infeasible = 0
    for i in range(len(lift.z)):
        state = lift_state(lift, i, variant="S", reading="physical")
        a, b = tvmmp(state), tvmmp(state, solver="clarabel")
        assert a.status == b.status, i
        np.testing.assert_allclose(a.alpha, b.alpha, rtol=1e-6, atol=1e-8)
        infeasible += not a.feasible
    assert infeasible > 0
