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


def test_session_options_are_checked_and_survive_the_retries():
    """A session's own options (the oracles' primal simplex) are what solve() restores after
    a cold-start retry; a rejected option is a SolverError naming it."""
    import scipy.sparse as sp

    from mjtvm.errors import SolverError
    from mjtvm.solvers import HighsSession, LinearProgram

    # max x + y on the unit square: optimal (1, 1) with value -2 (minimising -x - y)
    lp = LinearProgram(
        np.array([-1.0, -1.0]), sp.csc_matrix(np.eye(2)), np.zeros(2), np.ones(2), np.zeros(2), np.ones(2)
    )
    session = HighsSession(lp)
    session.set_option("simplex_strategy", 4)
    with pytest.raises(SolverError, match="simplex_strategy"):
        session.set_option("simplex_strategy", "no such strategy")
    assert session._options["simplex_strategy"] == 4
    sol = session.solve(duals=True)
    assert sol.status == "optimal" and sol.objective == pytest.approx(-2.0)
    np.testing.assert_allclose(sol.x, [1.0, 1.0])
    assert sol.row_dual is not None and sol.row_dual.shape == (2,)
    assert session.highs.getOptionValue("simplex_strategy")[1] == 4
