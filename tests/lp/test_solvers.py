"""LP backends: HiGHS must certify every LP it is given, and agree with Clarabel."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from benchmarks.synthetic import random_state
from mjtvm import tvmmp
from mjtvm.errors import SolverError
from mjtvm.formats.state_file import load_state
from mjtvm.lift.states import lift_state
from mjtvm.lift.trajectory import scripted_lift
from mjtvm.polytopes.tvms import tvms

from ..helpers import distance_to_hull


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

    from mjtvm.errors import SolverError
    from mjtvm.lp.solvers import HighsSession, LinearProgram

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


# --------------------------------------------------------------- issue 12: solver handling
EXAMPLE = Path(__file__).resolve().parents[2] / "mjtvm" / "data" / "examples" / "pinch.json"


def mixed_scale(state, seed: int):  # type: ignore[no-untyped-def]
    """``state`` with every Jacobian entry set to +-1e-8 or +-1e4 times its contact's largest
    (at random) and a 1e7 N load: an impossible grasp (the torques cannot hold 1e7 N)."""
    rng = np.random.default_rng(seed)
    contacts = []
    for c in state.contacts:
        j = c.jacobian / np.abs(c.jacobian).max()
        contacts.append(replace(c, jacobian=np.where(rng.random(j.shape) < 0.5, j * 1e-8, j * 1e4)))
    refs = state.refs.copy()
    refs[:, :3] *= 1e7 / np.linalg.norm(refs[0, :3])
    return replace(state, contacts=tuple(contacts), refs=refs)


def test_pinch_tvms_no_longer_fails_on_a_highs_warning():
    """The ray-shooting LPs of the shipped example carry ~5e-14 round-off that HiGHS drops with
    kWarning, which was fatal (exit 3). Now the round-off is dropped before (relative to the
    equilibrated row and column) and a warning is not an error: the same 4 vertices as cdd."""
    state = load_state(EXAMPLE)
    lp, cdd = tvms(state), tvms(state, method="cdd")
    assert lp.status == cdd.status == "bounded" and lp.dimension == cdd.dimension == 2
    assert lp.affine_volume == pytest.approx(cdd.affine_volume, rel=1e-9)
    np.testing.assert_allclose(
        np.sort(np.abs(lp.vertices[:, 0])), np.sort(np.abs(cdd.vertices[:, 0])), atol=1e-9
    )


def test_random_states_through_the_ray_lps():
    """A sample of random valid states (the full 300: see the issue's closing note) through
    Problem 1's ray-shooting LPs (the TVMS in the RVDS cone) and Problem 2: no solver error,
    no fallback, bounded TVMS, positive finite alphas (the states are feasible with room by
    construction)."""
    for seed in range(0, 300, 15):
        state = random_state(seed)
        hull = tvms(state)
        res = tvmmp(state, witnesses=False)
        assert hull.status == "bounded" and res.feasible and res.notes == ()
        assert np.all(np.isfinite(res.alpha)) and np.all(res.alpha > 0)


def test_every_highs_call_is_status_checked():
    """changeCoeff/changeColBounds/changeRowsBounds/passModel/setOptionValue: kError raises a
    SolverError naming the call (monkeypatched HiGHS answers kError), kWarning passes."""
    import highspy

    from mjtvm.lp.solvers import HighsSession, LinearProgram

    lp = LinearProgram(
        np.array([-1.0, -1.0]), sp.csc_matrix(np.eye(2)), np.zeros(2), np.ones(2), np.zeros(2), np.ones(2)
    )
    session = HighsSession(lp)
    h = session.highs

    class Failing:
        def __init__(self, status):  # type: ignore[no-untyped-def]
            self.status = status

        def __getattr__(self, name):  # type: ignore[no-untyped-def]
            if name.startswith("change"):
                return lambda *a: self.status
            return getattr(h, name)

    session.highs = Failing(highspy.HighsStatus.kError)
    with pytest.raises(SolverError, match="changeCoeff"):
        session.set_column(0, np.array([0]), np.array([2.0]))
    with pytest.raises(SolverError, match="changeRowsBounds"):
        session.set_row_bounds(np.array([0]), np.zeros(1), np.ones(1))
    with pytest.raises(SolverError, match="changeColBounds"):
        session.set_col_bounds(0, 0.0, 1.0)
    session.highs = Failing(highspy.HighsStatus.kWarning)
    session.set_column(0, np.array([0]), np.array([2.0]))  # a warning is information, not failure


def test_a_coefficient_beyond_highs_range_is_an_error_not_a_silent_drop():
    """A scaled coefficient HiGHS would refuse (>= 1e15) or drop (<= 1e-12) is a SolverError."""

    from mjtvm.lp.solvers import HighsSession, LinearProgram

    lp = LinearProgram(
        np.zeros(2), sp.csc_matrix(np.eye(2)), np.zeros(2), np.ones(2), np.zeros(2), np.ones(2)
    )
    session = HighsSession(lp)
    with pytest.raises(SolverError, match="changeCoeff: an equilibrated coefficient is outside"):
        session.set_column(1, np.array([0, 1]), np.array([1e20, 1.0]))


def test_clarabel_no_longer_calls_an_impossible_grasp_feasible():
    """Jacobians mixing 1e-8 and 1e4, a 1e7 N load: HiGHS certifies infeasible; Clarabel said
    'unbounded' (feasible) on seeds 7, 13, 14, 16, 28 of this family before. Now its verdict is
    cross-checked (HiGHS and a feasibility re-solve) and the disagreement is noted."""
    state = load_state(EXAMPLE)
    for seed in (7, 13, 14, 16, 28):
        bad = mixed_scale(state, seed)
        a, b = tvmmp(bad), tvmmp(bad, solver="clarabel")
        assert not a.feasible and not b.feasible
        assert all(s == "infeasible" for s in b.status[0])
        assert b.tvmmp is None and b.to_dict()["feasible"] is False


def test_a_state_highs_left_unknown_is_settled():
    """Seed 6 of the mixed-scale family (entries 1e-12 apart in one row): HiGHS returned
    'Unknown' after its cold retries and mjtvm exited 3. Now every pair is certified
    infeasible from either backend; where HiGHS still cannot settle a pair (whether it does
    depends on the scaling's rounding at this extreme), Clarabel does and the note says so."""
    bad = mixed_scale(load_state(EXAMPLE), 6)
    for solver in ("highs", "clarabel"):
        res = tvmmp(bad, solver=solver)
        assert not res.feasible and res.status == (("infeasible",) * 4,)
        # HiGHS' 'Unknown' (as the solver, or as Clarabel's cross-check) is reported
        assert all("Unknown" in note for _, note in res.notes)


def test_highs_unknown_falls_back_to_clarabel(monkeypatch):
    """HiGHS stuck at 'Unknown' after its cold retries: the pair is settled by Clarabel, with
    the same alphas, and the result says so (settled_by, notes) instead of exit 3."""
    from mjtvm.lp import solvers

    state = load_state(EXAMPLE)
    ref = tvmmp(state)

    def unknown(self, *, duals=False):  # type: ignore[no-untyped-def]
        raise SolverError("highs", "Unknown")

    monkeypatch.setattr(solvers.HighsSession, "solve", unknown)
    res = tvmmp(state)
    np.testing.assert_allclose(res.alpha, ref.alpha, rtol=1e-7)
    assert all(s == "clarabel" for s in res.settled_by[0])
    assert [p for p, _ in res.notes] == [(0, l) for l in range(4)]
    assert all(m == "highs: Unknown; settled by clarabel: optimal" for _, m in res.notes)
    doc = res.to_dict()
    assert doc["settled_by"] == [["clarabel"] * 4] and doc["notes"][0]["pair"] == [0, 0]


def test_solver_error_only_when_nothing_settles_it(monkeypatch):
    """Both backends fail: SolverError naming the pair and both statuses, chained to HiGHS'."""
    from mjtvm.lp import clarabel, solvers

    def unknown(self, *, duals=False):  # type: ignore[no-untyped-def]
        raise SolverError("highs", "Unknown")

    def stalled(lp):  # type: ignore[no-untyped-def]
        raise SolverError("clarabel", "MaxIterations")

    monkeypatch.setattr(solvers.HighsSession, "solve", unknown)
    monkeypatch.setattr(clarabel, "_solve_clarabel", stalled)
    with pytest.raises(SolverError, match=r"Unknown; fallback clarabel: MaxIterations.*\(0, 0\)") as info:
        tvmmp(load_state(EXAMPLE))
    assert info.value.pair == (0, 0)
    assert isinstance(info.value.__cause__, SolverError)
    assert isinstance(info.value.__cause__.__cause__, SolverError)  # HiGHS' own


def test_documents_are_finite_json():
    """-1e308 in an RVDS vertex printed -Infinity: the loader now refuses it (|x| <= 1e12),
    and the writers never emit NaN/Infinity whatever they hold: non-finite numbers are
    null (json.dumps(allow_nan=False) holds)."""
    from mjtvm.errors import StateError
    from mjtvm.problem2.tvmmp import finite_floats

    assert finite_floats([1.0, -np.inf, np.nan, -0.0]) == [1.0, None, None, 0.0]
    assert finite_floats([[np.inf], [2.0]]) == [[None], [2.0]]
    state = load_state(EXAMPLE)
    mixed = state.rvds.copy()
    mixed[1, 0] = -1e308
    with pytest.raises(StateError, match="rvds"):
        replace(state, rvds=mixed)
    res = tvmmp(state)
    w = res.witnesses[0][1]
    assert w is not None
    broken = replace(
        res,
        alpha=np.array([[np.inf, res.alpha[0, 1], np.nan, res.alpha[0, 3]]]),
        tvmmp=float("inf"),
        distribution=(np.full(6, -np.inf), *res.distribution[1:]),
        witnesses=((None, replace(w, twist=np.full(6, np.nan)), None, None),),
    )
    doc = broken.to_dict()
    json.dumps(doc, allow_nan=False)
    assert doc["tvmmp"] is None and doc["alpha"][0][0] is None and doc["alpha"][0][2] is None
    assert doc["distribution"][0] == [None] * 6 and doc["witnesses"][0][1]["twist"] == [None] * 6
    json.dumps(res.to_dict(), allow_nan=False)
    json.dumps(tvms(state).to_dict(), allow_nan=False)


def test_a_disagreement_at_the_weight_limit_is_reported():
    """The 16-joint, four-fingertip hand (bench_suite.scaling_hand(4)) with its weight bisected
    (HiGHS) to the largest it holds, about 183.17865 x 1 N. 1e-7 below, both backends agree
    (feasible, no note). 1e-9 above, HiGHS certifies infeasible while Clarabel's interior
    point, within its tolerances, finds pairs feasible (or stalls): every pair where the two
    disagree carries a note naming both verdicts, whichever the result keeps. Nothing hidden."""
    from benchmarks.suite import scaling_hand

    state = scaling_hand(4)
    lo, hi = 183.0, 183.4
    for _ in range(45):
        mid = (lo + hi) / 2
        feasible = tvmmp(state.with_(refs=state.refs * mid), witnesses=False).feasible
        lo, hi = (mid, hi) if feasible else (lo, mid)
    assert lo == pytest.approx(183.17865, rel=1e-6)
    below = state.with_(refs=state.refs * lo * (1 - 1e-7))
    for solver in ("highs", "clarabel"):
        res = tvmmp(below, solver=solver, witnesses=False)
        assert res.feasible and res.notes == () and res.tvmmp is not None and res.tvmmp > 0.0
    above = state.with_(refs=state.refs * hi * (1 + 1e-9))
    assert tvmmp(above, witnesses=False).status == (("infeasible",) * 4,)
    res = tvmmp(above, solver="clarabel", witnesses=False)
    assert res.notes  # the case this test is about does occur
    for _, note in res.notes:
        assert note.startswith("clarabel: ") and "highs: infeasible" in note


def test_pyramid_edges_and_mujoco_data_carry_exact_zeros():
    """cos(pi/2) = 6e-17 in a pyramid edge and MuJoCo's ~1e-17 beside 0.1 in a Jacobian are
    exact zeros (grasp.without_round_off, contacts.force_generators): left in, they sat in the
    LPs beside O(1) entries where no equilibration can tell them from data."""
    from benchmarks.suite import scaling_hand
    from mjtvm import Contact
    from mjtvm.grasp.resolve.state import without_round_off
    from mjtvm.model import force_generators

    contact = Contact("c", "F", [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], np.ones((3, 1)), mu=0.5)
    edges = force_generators(contact, 16)
    np.testing.assert_array_equal(edges[:, 4], [0.0, 0.5, 1.0])  # theta = pi/2: t1 = e_x, t2 = e_y
    np.testing.assert_array_equal(edges[:, 8], [-0.5, 0.0, 1.0])
    np.testing.assert_array_equal(without_round_off(np.array([0.1, 1.8e-17, -1e-3])), [0.1, 0.0, -1e-3])
    np.testing.assert_array_equal(without_round_off(np.array([1e-13, 2e-30])), [1e-13, 0.0])  # relative
    for c in scaling_hand(8).contacts:
        j = np.abs(c.jacobian)
        assert not np.any((j > 0) & (j <= 1e-15 * j.max()))


def test_round_off_in_jacobians_does_not_change_the_tvms():
    """Putting MuJoCo-like round-off (1e-17 times the Jacobian's largest entry) back into the
    exact zeros of the generated 8-finger hand's Jacobians moves the TVMS by less than 1e-9
    relative (point-to-hull distances both ways; the vertex count, 78 or 79, is not decidable
    here: near-coplanar facets) and TVMMP by less than 1e-9. The round-off had put a vertex
    3e-8 outside and made Problem 1 on this hand 9x slower (0.14 -> 1.3 s) while it steered
    the equilibration."""
    from benchmarks.suite import scaling_hand

    state = scaling_hand(8)
    rng = np.random.default_rng(0)
    contacts = []
    for c in state.contacts:
        j = c.jacobian.copy()
        zero = (j == 0.0) & (np.abs(c.jacobian).sum(axis=0, keepdims=True) > 0)  # this finger's joints
        j[zero] = rng.choice([-1.0, 1.0], size=int(zero.sum())) * 1e-17 * np.abs(j).max()
        contacts.append(replace(c, jacobian=j))
    noisy = state.with_(contacts=tuple(contacts))
    assert sum(int(np.count_nonzero(a.jacobian != b.jacobian)) for a, b in zip(state.contacts, contacts)) > 0
    ref, raw = tvms(state).vertices, tvms(noisy).vertices
    scale = np.abs(ref).max()
    assert distance_to_hull(raw, ref).max() <= 1e-9 * scale
    assert distance_to_hull(ref, raw).max() <= 1e-9 * scale
    assert tvmmp(noisy).tvmmp == pytest.approx(tvmmp(state).tvmmp, rel=1e-9)


@pytest.mark.parametrize(
    ("values", "error"),
    [([5e-324, 1e-320], None), ([1e300, 1e-300], "outside"), ([np.inf, 1.0], "overflows")],
)
def test_rescaled_column_out_of_range_without_nan(values, error):
    """A column rescaled from subnormals only (its factor would be 2^1037) or holding an
    overflowed entry (its factor 2^-inf = 0) once gave ``inf * 0 = nan`` coefficients and
    bounds with a RuntimeWarning (a fuzzed Case 1-S). Clipped like equilibrate's factors:
    subnormals are round-off beside 1 (dropped), a span HiGHS cannot hold or an overflow is
    a SolverError, never a nan and never a warning."""
    import warnings

    from mjtvm.lp.solvers import HighsSession, LinearProgram

    lp = LinearProgram(
        np.array([-1.0, -1.0]), sp.csc_matrix(np.eye(2)), np.zeros(2), np.ones(2), np.zeros(2), np.ones(2)
    )
    session = HighsSession(lp)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        if error is None:
            session.set_column(1, np.array([0, 1]), np.array(values), rescale=True)
        else:
            with pytest.raises(SolverError, match=error):
                session.set_column(1, np.array([0, 1]), np.array(values), rescale=True)
    assert np.isfinite(session.column_scale(1)) and session.column_scale(1) > 0.0


def test_factor_of_largest_is_the_power_of_2_of_column_factor():
    """The float helper gives the numpy formula's power of 2 (clipped at 2^+-400) over 300
    orders of magnitude on either side, at the clip and for an overflowed entry."""
    from mjtvm.lp.scaling import column_factor, factor_of_largest

    rng = np.random.default_rng(0)
    bigs = np.concatenate([10.0 ** rng.uniform(-300, 300, 2000), [5e-324, 1e-310, 1.0, 2.0, 1.5, np.inf]])
    for big in bigs:
        want = float(np.exp2(np.clip(np.round(-np.log2(big)), -400.0, 400.0)))
        assert factor_of_largest(float(big)) == want
        assert column_factor(np.array([0.0, -big, big / 3])) == want
    assert column_factor(np.zeros(3)) == 1.0


def test_a_rescaled_column_keeps_the_scaled_cost_highs_holds():
    """Rescaling the only costed column moves the cost factor with it: its scaled cost, and
    every zero cost, stay as HiGHS holds them, so no cost is sent (a cost change makes HiGHS
    recompute its duals); the optimum is the LP's, as a fresh session finds it."""
    from mjtvm.lp.solvers import HighsSession, LinearProgram

    # max t s.t. x0 + d0 t = 1, x1 + d1 t = 1, 0 <= x <= 1, 0 <= t <= 1: t* = 1 / max(d) for d >= 1.
    a = sp.csc_matrix(np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]))
    lp = LinearProgram(np.array([0.0, 0.0, -1.0]), a, np.ones(2), np.ones(2), np.zeros(3), np.ones(3))
    session = HighsSession(lp)
    sent: list[int] = []
    real = session.highs

    class Spy:
        def __getattr__(self, name):  # type: ignore[no-untyped-def]
            if name == "changeColsCost":
                return lambda n, cols, cost: sent.append(n) or real.changeColsCost(n, cols, cost)
            return getattr(real, name)

    session.highs = Spy()
    for d in ([4.0, 2.0], [1e6, 3.0], [1.0, 8.0]):
        session.set_column(2, np.array([0, 1]), np.array(d), rescale=True)
        sol = session.solve()
        assert sol.x is not None
        assert sol.x[2] == pytest.approx(1.0 / max(d), rel=1e-12)
        lp_d = LinearProgram(
            lp.c,
            sp.csc_matrix(np.array([[1.0, 0.0, d[0]], [0.0, 1.0, d[1]]])),
            np.ones(2),
            np.ones(2),
            np.zeros(3),
            np.ones(3),
        )
        fresh = HighsSession(lp_d).solve()
        assert fresh.x is not None and sol.x[2] == pytest.approx(fresh.x[2], rel=1e-12)
    assert sent == []


def test_cost_scale_is_the_power_of_2_nearest_the_inverse_of_the_largest_scaled_cost():
    """The float path of cost_scale gives numpy's pow2 over 300 orders of magnitude on either
    side, inf where the inverse overflows, and 1 without costs."""
    from mjtvm.lp.scaling import cost_scale, pow2

    rng = np.random.default_rng(1)
    for big in np.concatenate([10.0 ** rng.uniform(-300, 300, 2000), [1.0, 0.75, 3.0, 1e-320]]):
        c, col = np.array([0.0, -big, big / 7]), np.array([4.0, 1.0, 1.0])
        with np.errstate(over="ignore", divide="ignore"):
            want = float(pow2(1.0 / big))
        assert cost_scale(c, col) == want
    assert cost_scale(np.zeros(3), np.ones(3)) == 1.0
    assert cost_scale(np.zeros(0), np.zeros(0)) == 1.0
