"""Monotonicity and scaling properties of alpha, each with the condition that makes it a theorem."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from benchmarks.synthetic import random_state
from mjtvm import Contact, tvmmp

FAST = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
TYPES_FLD = st.sampled_from([("F", "L", "F", "L", "D"), ("F", "F", "F"), ("L", "F", "D", "F")])


def with_mu(state, mu):
    return state.with_(contacts=tuple(Contact(**{**vars(c), "mu": mu}) for c in state.contacts))


def optimal_alpha(res):
    a = res.alpha.copy()
    a[[[s == "unbounded" for s in row] for row in res.status]] = np.inf
    a[[[s == "infeasible" for s in row] for row in res.status]] = -np.inf
    return a


@settings(FAST)
@given(seed=st.integers(0, 10_000), types=TYPES_FLD, mu=st.floats(0.05, 0.8), grow=st.floats(1.0, 3.0))
def test_alpha_never_shrinks_when_mu_grows(seed, types, mu, grow):
    r"""Theorem for F, L and D contacts: with a fixed pyramid orientation the friction set
    of mu grows with mu (each edge n + mu t_k scales out), and every other constraint is
    unchanged, so the feasible set of eq. (31) grows. (Not for S-points: there mu turns
    the force direction n - mu s.)"""
    state = random_state(seed, contact_types=types, mu=mu, load=0.6)
    small, large = tvmmp(with_mu(state, mu)), tvmmp(with_mu(state, mu * grow))
    assert np.all(optimal_alpha(large) >= optimal_alpha(small) * (1 - 1e-7) - 1e-9)


@settings(FAST)
@given(
    seed=st.integers(0, 10_000),
    factor=st.floats(1.0, 4.0),
    types=st.sampled_from([("F", "S", "L", "D"), ("F", "L")]),
)
def test_alpha_never_grows_when_refs_scale_up_without_finger_weight(seed, factor, types):
    r"""Theorem when g_f = 0: if (f, tau = J^T f, qd, alpha) is feasible for c w (c >= 1),
    then (f / c, tau / c, qd, alpha) is feasible for w, because (|tau| / c, |qd|) stays in
    the down-closed operation range. So alpha(c w) <= alpha(w)."""
    state = random_state(seed, contact_types=types, gravity_scale=0.0, load=0.4)
    base, scaled = tvmmp(state), tvmmp(state.with_(refs=state.refs * factor))
    assert np.all(optimal_alpha(scaled) <= optimal_alpha(base) * (1 + 1e-7) + 1e-9)


@settings(FAST)
@given(
    seed=st.integers(0, 10_000),
    c=st.floats(0.1, 10.0),
    types=st.sampled_from([("F", "S", "L", "D"), ("F", "L", "F")]),
)
def test_alpha_scales_linearly_with_every_speed_limit(seed, c, types):
    r"""Theorem: the kinematic constraints (eq. 11-13) are homogeneous in (qd, rdot, rho);
    scaling every operation range's speed axis by c maps feasible (qd, alpha) to
    (c qd, c alpha) and back. So alpha -> c alpha, for any contact types."""
    state = random_state(seed, contact_types=types)
    ranges = tuple(op.scaled(speed=c) for op in state.operation_ranges)
    base, scaled = tvmmp(state), tvmmp(state.with_(operation_ranges=ranges))
    assert base.status == scaled.status
    np.testing.assert_allclose(scaled.alpha, c * base.alpha, rtol=1e-7, atol=1e-9)
