"""The dynamic alpha (mjtvm.problem2.dynamic) on a closed-form case: one joint pushing an object.

A one-joint finger of length l (joint at the origin, tip at (l sin q, l cos q)) pushes a block
along +x with a frictionless (L) tip against a resisting force F0; the block moves at constant
speed v = alpha. Tip speed l cos q qd = v, so qd = v / (l cos q) and
qdd = v^2 sin q / (l^2 cos^3 q). A rotor inertia I then needs the torque I qdd on top of
eq. (19)'s tau = l cos q F0. With the triangular operation range |tau| / T + |qd| / W <= 1:

* quasi-static: alpha_kl = l c W (1 - l c F0 / T);
* dynamic: (l c F0 + I a^2 s / (l^2 c^3)) / T + a / (l c W) = 1, a quadratic in a whose
  positive root is alpha_dyn.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from mjtvm.model.contacts import Contact
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.problem2.dynamic import dynamic_alpha, pair_alpha, quadratic

L, F0, T, W = 0.1, 2.0, 1.0, 30.0


def pusher(q: float, *, f0: float = F0) -> GraspState:
    tip = np.array([L * math.sin(q), L * math.cos(q)])
    contact = Contact("tip", "L", tip, [1.0, 0.0], [[L * math.cos(q)], [-L * math.sin(q)]])
    return GraspState(
        space=2,
        object_position=tip + np.array([0.05, 0.0]),
        joint_names=("q",),
        operation_ranges=(OperationRange([[0, 0], [T, 0], [0, W]]),),
        gravity_torque=[0.0],
        contacts=(contact,),
        refs=[[-f0, 0.0, 0.0]],
        rvds=[[1.0, 0.0, 0.0]],
    )


def closed_form(q: float, inertia: float) -> tuple[float, float]:
    s, c = math.sin(q), math.cos(q)
    static = L * c * W * (1 - L * c * F0 / T)
    qa, qb, qc = inertia * s / (T * L**2 * c**3), 1 / (L * c * W), L * c * F0 / T - 1
    dyn = (-qb + math.sqrt(qb * qb - 4 * qa * qc)) / (2 * qa) if qa > 0 else static
    return static, dyn


@pytest.mark.parametrize("q", [0.2, 0.5, 0.9])
@pytest.mark.parametrize("inertia", [1.73e-3, 1e-2])
def test_one_joint_pusher_matches_the_closed_form(q: float, inertia: float) -> None:
    state = pusher(q)
    h = inertia * math.sin(q) / (L**2 * math.cos(q) ** 3)  # torque per (m/s)^2
    res = dynamic_alpha(state, 0, 0, quadratic([h]), rtol=1e-7)
    static, dyn = closed_form(q, inertia)
    assert res.alpha_static == pytest.approx(static, rel=1e-9)
    assert res.alpha == pytest.approx(dyn, rel=1e-6)
    assert res.alpha < res.alpha_static
    assert res.joint == 0
    assert 0 <= res.residual <= 1e-6 * static  # a fixed point of alpha -> A(d(alpha))


def test_closed_form_values() -> None:
    # q = 0.5, I = 1e-2 kg m^2: l c = 0.087758 m, pushing torque l c F0 = 0.17552 N m,
    # alpha_kl = 0.087758 * 30 * (1 - 0.17552) = 2.17066 m/s; the quadratic
    # 0.70934 a^2 + 0.37983 a - 0.82448 = 0 gives alpha_dyn = 0.84312 m/s, where the inertial
    # torque is 0.70934 * 0.84312^2 = 0.50424 N m and the speed 9.607 rad/s (a third of W)
    static, dyn = closed_form(0.5, 1e-2)
    assert static == pytest.approx(0.1 * math.cos(0.5) * 30 * (1 - 0.2 * math.cos(0.5)), rel=1e-12)
    res = dynamic_alpha(pusher(0.5), 0, 0, quadratic([1e-2 * math.sin(0.5) / (L**2 * math.cos(0.5) ** 3)]))
    assert (round(static, 5), round(dyn, 5)) == (2.17066, 0.84312)
    assert 0.84312 - 2.2e-4 <= res.alpha <= 0.84312  # default rtol 1e-4 of alpha_kl, from below
    assert res.demand[0] == pytest.approx(0.50424, abs=3e-4)
    assert res.witness is not None and res.witness.speeds[0] == pytest.approx(9.607, abs=6e-3)
    assert res.term == "inertia"  # 0.504 N m of inertia against 0.176 N m of pushing


def test_zero_inertia_gives_the_quasi_static_alpha() -> None:
    res = dynamic_alpha(pusher(0.5), 0, 0, quadratic([0.0]))
    assert res.alpha == pytest.approx(res.alpha_static, rel=1e-4)
    assert res.alpha <= res.alpha_static
    assert res.alpha_static == pytest.approx(closed_form(0.5, 0.0)[0], rel=1e-9)


def test_bisection_converges_geometrically() -> None:
    """Each LP halves the bracket: width alpha_kl 2^-n after n tests, and the end is a fixed point."""
    h = [1e-2 * math.sin(0.5) / (L**2 * math.cos(0.5) ** 3)]
    widths = []
    for rtol in (1e-2, 1e-4, 1e-6):
        res = dynamic_alpha(pusher(0.5), 0, 0, quadratic(h), rtol=rtol)
        lo, hi = res.bracket
        assert lo <= closed_form(0.5, 1e-2)[1] <= hi
        widths.append((hi - lo, res.lps))
    for (w1, n1), (w2, n2) in itertools.pairwise(widths):
        assert w2 == pytest.approx(w1 * 2.0 ** -(n2 - n1), rel=1e-9)


def test_a_helping_demand_raises_alpha_above_the_quasi_static_one() -> None:
    # a decelerating joint (h < 0) gives torque back: the bracket is extended above alpha_kl
    res = dynamic_alpha(pusher(0.5), 0, 0, quadratic([-0.01]), rtol=1e-8)
    s = pair_alpha(pusher(0.5), 0, 0, [-0.01 * res.alpha**2])[0]
    assert res.alpha > res.alpha_static
    assert s == pytest.approx(res.alpha, rel=1e-6)


def test_a_demand_beyond_the_motor_gives_zero() -> None:
    res = dynamic_alpha(pusher(0.5), 0, 0, lambda a: [2.0 * T])  # a constant demand above T
    assert res.alpha == 0.0 and res.witness is None
    assert math.isnan(dynamic_alpha(pusher(0.5, f0=20.0), 0, 0, quadratic([0.0])).alpha)  # no quasi-static


def test_several_demand_vectors_must_each_be_met() -> None:
    """A demand of shape (n, M) (e.g. a joint's extremes along a window): alpha is feasible iff
    each vector's LP is, so alpha_dyn is that of the largest inertia (the closed form)."""
    hs = [c * math.sin(0.5) / (L**2 * math.cos(0.5) ** 3) for c in (1.73e-3, 1e-2)]

    def both(a: float) -> np.ndarray:
        return a * a * np.array([[hs[0]], [hs[1]]])

    res = dynamic_alpha(pusher(0.5), 0, 0, both, rtol=1e-7)
    assert res.alpha == pytest.approx(closed_form(0.5, 1e-2)[1], rel=1e-6)
    assert res.demand[0] == pytest.approx(hs[1] * res.alpha**2, rel=1e-9)  # the binding vector
    one = dynamic_alpha(pusher(0.5), 0, 0, quadratic([hs[1]]), rtol=1e-7)
    assert res.lps == 2 * one.lps - 1  # two LPs per candidate, one for alpha_kl


def test_a_demand_of_the_wrong_shape_is_refused() -> None:
    from mjtvm.errors import ParamError

    with pytest.raises(ParamError, match=r"demand: expected \(1,\) or \(n, 1\) joint torques"):
        dynamic_alpha(pusher(0.5), 0, 0, lambda a: np.zeros((2, 3)))


@pytest.mark.parametrize("seed", [0, 1])
def test_constant_demand_vectors_against_the_cvxpy_reference(seed: int) -> None:
    """A constant demand of two vectors (+d and -d, a window's two ends): alpha is feasible iff
    both loaded LPs reach it, so alpha_dyn = min_i A(d_i), each A solved independently by the
    cvxpy transcription of eq. (31) (oracles.reference) on the state with g_f + d_i."""
    from benchmarks.synthetic import random_state
    from oracles.reference import reference_alpha

    state = random_state(seed)
    rng = np.random.default_rng(seed)
    tmax = np.array([op.max_torque for op in state.operation_ranges])
    d = 0.05 * tmax * rng.choice([-1.0, 1.0], size=state.num_joints)
    refs = []
    for vec in (d, -d):
        status, a = reference_alpha(state.with_(gravity_torque=state.gravity_torque + vec), 0, 0)
        assert status == "optimal" and a is not None
        refs.append(a)
    res = dynamic_alpha(
        state, 0, 0, lambda a: np.vstack([d, -d]) if a > 0 else np.zeros(state.num_joints), rtol=1e-8
    )
    assert res.alpha == pytest.approx(min(refs), rel=1e-6)
    assert res.alpha < res.alpha_static  # the demand costs speed here
