r"""A dynamics-aware alpha: eq. (31) with extra joint torque demands that grow with alpha.

The paper's Problem 2 is quasi-static: the torque of joint j balances gravity and the contact
forces (eq. 19), $\tau = g_f + J^T f$, and the operation range (eq. 1-3) bounds the pair
$(\tau_j, \dot q_j)$. Moving the object at a constant twist $\alpha \hat r_l$ while
the configuration changes needs joint accelerations as well: $\dot q \propto \alpha$,
$\ddot q \propto \alpha^2$, and the motors must supply
$M(q)\ddot q + c(q, \dot q)$ on top. This module takes that extra torque as a
*demand*, a function of the candidate alpha returning ``(M,)`` joint torques (N m), and finds

$$
\alpha^{dyn}_{kl} = \max \{\alpha \ge 0 :\ \alpha \le A(d(\alpha))\},
$$

where $A(d)$ is the LP of eq. (31) for pair (k, l) with the statics rows
$\tau - J^T E \lambda = g_f + d$ (the demand added to the gravity torque). The core
does not know where the demand comes from (no MuJoCo here); [`mjtvm.physics.dynamic`][mjtvm.physics.dynamic]
computes it from the hand's model.

Why one LP per candidate decides it exactly
-------------------------------------------
For a fixed demand d, the alphas of the feasible set of eq. (31) form an interval
$[0, A(d)]$: with $\dot q = 0$, $\rho = 0$, $\alpha = 0$ every kinematic
row holds, and the operation ranges are mirrored and down-closed (each row pair
$c_\tau \tau \pm c_{qd} \dot q \le b$ averages to $c_\tau \tau \le b$), so any
feasible torque is feasible at rest. Hence alpha is dynamically feasible iff
$A(d(\alpha)) \ge \alpha$ (one LP; ``A = None`` when the demand cannot be balanced even
at rest).

Convergence (bisection)
-----------------------
Let $d(\alpha) = \alpha^2 h$ with a fixed h (the joint motion per unit alpha fixed, as
for a non-redundant hand), and $P = \{(\alpha, t)\}$ the alphas and demand scales
$t h$ for which eq. (31) is feasible: a projection of a polyhedron, so convex. If
$a_2 \le \alpha_{kl} = A(0)$ is feasible, i.e. $(a_2, a_2^2) \in P$, then every
$a \in [0, a_2]$ is: $(a, 0) \in P$ (quasi-static, $a \le \alpha_{kl}$) and
$(a, a a_2) \in P$ (the chord from $(0, 0)$ to $(a_2, a_2^2)$), hence
$(a, a^2) \in P$ as $0 \le a^2 \le a a_2$. The feasible alphas below
$\alpha_{kl}$ are an interval $[0, \alpha^{dyn}]$, and bisection on the test
converges to its end, halving the bracket with every LP. When the demand *helps* (negative
work, $A(d(\alpha_{kl})) > \alpha_{kl}$) the bracket is extended by doubling above
$\alpha_{kl}$; there the interval property is assumed, not proved. At the end,
$|A(d(\alpha^{dyn})) - \alpha^{dyn}|$ is within the tolerance when A and d are
continuous (the fixed point of $\alpha \mapsto A(d(\alpha))$); `DynamicAlpha.residual`
reports it.

Demands along a window
----------------------
A state's demand is that of one instant; the motion that checks it lasts a window, along which
$M(q)\ddot q + c$ changes with the configuration (near a stretched finger it grows like
$1/\cos^3 q$). A demand may therefore return several vectors ``(n, M)``, e.g. the extremes
of each joint's demand over the window ([`mjtvm.physics.dynamic.window_demand()`][mjtvm.physics.dynamic.window_demand]): alpha is
feasible iff eq. (31) is feasible with *each* of them, $\min_i A(d_i(\alpha)) \ge \alpha$
(one LP per vector, each with its own forces, as the forces of the motion change along it). The
feasible alphas are then the intersection of the intervals of the vectors, again an interval,
and the bisection above applies unchanged. (A window's demand is not $\alpha^2 h$: at a
higher speed the window covers more of the path; there the interval property is assumed.)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import ParamError, StateError
from mjtvm.model.state import GraspState
from mjtvm.problem2.result import Witness
from mjtvm.problem2.tvmmp import tvmmp

__all__ = ["TERMS", "Demand", "DynamicAlpha", "dynamic_alpha", "limiting_term", "pair_alpha", "quadratic"]

Demand = Callable[[float], ArrayLike]
"""alpha -> ``(M,)`` extra joint torque (N m) the motion at speed alpha along r_l needs, or
``(n, M)``: n such torques that must each be met (module docstring, "Demands along a window")."""
TERMS = ("gravity/grasp", "speed", "inertia")
"""The parts of a joint's operation range a witness uses: the torque of eq. (19) (gravity and
contact forces), the joint speed, and the extra (inertial) demand."""


def quadratic(h: ArrayLike) -> Demand:
    r"""The demand $d(\alpha) = \alpha^2 h$ of a fixed joint motion per unit alpha
    ($\ddot q = \alpha^2 \dot u\,$, Coriolis quadratic in $\dot q = \alpha u$)."""
    hv = np.asarray(h, dtype=float).copy()
    return lambda a: a * a * hv


def pair_alpha(
    state: GraspState, k: int, l: int, offset: ArrayLike | None = None, *, solver: str = "highs"
) -> tuple[float | None, Witness | None]:
    r"""$A(d)$: alpha of pair (k, l) (eq. 31) with ``offset`` (N m per joint) added to
    $g_f$ in the statics rows (eq. 19); ``(None, None)`` when the LP is infeasible."""
    if state.rvds is None:
        raise StateError("rvds", "Problem 2 needs RVDS vertices (a non-empty list of twists)")
    g = state.gravity_torque if offset is None else state.gravity_torque + np.asarray(offset, dtype=float)
    one = state.with_(gravity_torque=g, refs=state.refs[k : k + 1], rvds=state.rvds[l : l + 1])
    res = tvmmp(one, solver=solver)
    if res.status[0][0] != "optimal":
        return None, None
    return float(res.alpha[0, 0]), res.witnesses[0][0]


@dataclass(frozen=True, eq=False)
class DynamicAlpha:
    r"""The dynamic alpha of one pair (module docstring).

    Attributes
    ----------
    alpha
        $\alpha^{dyn}_{kl}$ (0 when even a slow motion is infeasible; ``nan`` when the
        pair has no quasi-static solution).
    alpha_static
        $\alpha_{kl}$ (no demand), or ``nan``.
    demand
        ``(M,)`` the demand at $\alpha^{dyn}$ (N m); of a demand with several vectors, the
        one whose LP gives the least alpha (the binding one).
    witness
        The LP's solution with that demand (its alpha is $A(d(\alpha^{dyn}))$), or None.
    joint
        Index of the limiting joint: the least slack of its operation range at the witness
        (a simplex vertex: [`mjtvm.physics.dynamic`][mjtvm.physics.dynamic] names it at a central solution instead).
    term
        Which use of that joint's range is largest ([`TERMS`][mjtvm.problem2.dynamic.TERMS]): the torque of eq. (19)
        $|\tau_j - d_j| / \tau_{max}$, the speed $|\dot q_j| / \dot q_{max}$ or the
        demand $|d_j| / \tau_{max}$.
    residual
        $A(d(\alpha^{dyn})) - \alpha^{dyn}$ (>= 0; small at a fixed point).
    lps
        Number of LPs solved (one per demand vector and candidate); ``bracket`` the final bisection bracket.
    """

    alpha: float
    alpha_static: float
    demand: NDArray[np.float64]
    witness: Witness | None
    joint: int | None
    term: str
    residual: float
    lps: int
    bracket: tuple[float, float]


def limiting_term(
    state: GraspState, torques: ArrayLike, speeds: ArrayLike, demand: ArrayLike
) -> tuple[int, str]:
    """The limiting joint of a solution (joint ``torques`` and ``speeds``, the ``demand`` included
    in the torques) and its dominant term (`DynamicAlpha.term`). With a transmission,
    the limiting actuator (its force and speed), the demand carried by the actuator forces
    that balance it in the least-squares sense."""
    d = np.asarray(demand, dtype=float)
    if state.transmission is not None:  # the actuator forces that carry the demand (least squares)
        d = np.linalg.lstsq(state.transmission.moment.T, d, rcond=None)[0]
    tau, qd = np.asarray(torques, dtype=float), np.asarray(speeds, dtype=float)
    slack = []
    for op, t, q in zip(state.operation_ranges, tau, qd):
        hp = op.mirrored_halfplanes
        slack.append(float(np.min((hp[:, 2] - hp[:, 0] * t - hp[:, 1] * q) / hp[:, 2])))
    j = int(np.argmin(slack))
    op = state.operation_ranges[j]
    shares = (abs(tau[j] - d[j]) / op.max_torque, abs(qd[j]) / op.max_speed, abs(d[j]) / op.max_torque)
    return j, TERMS[int(np.argmax(shares))]


def dynamic_alpha(
    state: GraspState,
    k: int,
    l: int,
    demand: Demand,
    *,
    rtol: float = 1e-4,
    max_lps: int = 80,
    solver: str = "highs",
) -> DynamicAlpha:
    r"""$\alpha^{dyn}_{kl}$ by bisection over LPs (module docstring).

    Parameters
    ----------
    state
        The grasp state (REFS vertex ``k``, RVDS vertex ``l``).
    demand
        alpha -> ``(M,)`` extra joint torque (N m), or ``(n, M)`` torques each to be met
        (module docstring); ``d(0)`` should be 0.
    rtol
        Bracket width relative to $\alpha_{kl}$ at which the bisection stops.
    max_lps
        Upper bound on LPs (the bisection stops earlier at ``rtol``).

    Returns
    -------
    DynamicAlpha
    """
    if not (0 < rtol < 1):
        raise ParamError("rtol", f"expected a number in (0, 1), got {rtol!r}", rtol)
    m = state.num_joints
    lps = 1
    a0, _ = pair_alpha(state, k, l, solver=solver)
    if a0 is None:
        return DynamicAlpha(math.nan, math.nan, np.zeros(m), None, None, "", math.nan, lps, (0.0, 0.0))

    def value(a: float) -> tuple[float | None, Witness | None, NDArray[np.float64]]:
        """min over the demand's vectors of A(d_i(a)), that LP's witness and vector (None: one
        of them is infeasible)."""
        nonlocal lps
        rows = np.asarray(demand(a), dtype=float)
        if rows.ndim > 2 or rows.shape[-1] != m:
            raise ParamError("demand", f"expected ({m},) or (n, {m}) joint torques, got shape {rows.shape}")
        vecs = rows.reshape(-1, m)
        low, wit, dv = math.inf, None, vecs[0]
        for d in vecs:
            lps += 1
            got, w = pair_alpha(state, k, l, d, solver=solver)
            if got is None:
                return None, None, d
            if got < low:
                low, wit, dv = got, w, d
        return low, wit, dv

    def feasible(a: float) -> bool:
        got = value(a)[0]
        return got is not None and got >= a * (1 - 1e-9)

    if a0 == 0.0:
        lo, hi = 0.0, 0.0
    else:
        lo, hi = 0.0, a0
        while feasible(hi) and lps < max_lps:  # the demand helps: extend upwards
            lo, hi = hi, 2 * hi
        while hi - lo > rtol * a0 and lps < max_lps:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if feasible(mid) else (lo, mid)
    got, w, d = value(lo)
    if w is None or got is None:  # lo = 0 with a demand that is not 0 at rest
        return DynamicAlpha(0.0, a0, d, None, None, "", math.nan, lps, (lo, hi))
    j, term = limiting_term(state, w.torques, w.range_speeds, d)
    return DynamicAlpha(lo, a0, d, w, j, term, got - lo, lps, (lo, hi))
