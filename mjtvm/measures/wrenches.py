r"""Wrench-space measures of a grasp state: force closure, the Ferrari-Canny epsilons and
the grasp matrix (``docs/measures.md``).

Every contact that transmits a force (F, L, S; a D-point carries none) contributes the
wrenches of its force generators `force_generators()` -- the
friction pyramid's edges of ``state.friction_edges`` for F, the normal for L, ``n - mu s``
for S -- each with unit normal component, so that a combination ``sum lam_k e_k`` with
``lam >= 0`` has normal force ``sum lam_k``. The wrench of a force ``f`` at ``p_C`` is
``[f; (p_C - p_O) x f / rho]``: the moment about the object position divided by the torque
scale ``rho`` (m), so that forces and moments share the unit N (Ferrari & Canny 1992).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from mjtvm.errors import ParamError, SolverError
from mjtvm.lp.lp import LinearProgram
from mjtvm.lp.solvers import solve_lp
from mjtvm.measures.hull import GrowingHull
from mjtvm.model.contacts import force_generators
from mjtvm.model.friction import margin_contacts
from mjtvm.model.state import GraspState
from mjtvm.problem2.assembly import grasp_map_transpose

__all__ = [
    "LINF_REL_TOL",
    "RANK_REL_TOL",
    "checked_torque_scale",
    "closure_margin",
    "default_torque_scale",
    "epsilon_l1",
    "epsilon_linf",
    "grasp_matrix",
    "primitive_wrenches",
    "scaled_rank",
]

RANK_REL_TOL = 1e-9  # singular values below this x the largest count as 0
LINF_REL_TOL = 1e-9  # the L-infinity epsilon's bracket, relative to the largest wrench
_LINF_MAX_ROUNDS = 1200
# The nearest facets refined per round: one, since a round inserts its points into the hull
# (mjtvm.measures.hull) instead of rebuilding it: on the five-finger Shadow grasps 38 ms a
# grasp against 55 ms with 3 and 80 ms with 8, the same epsilons within 3e-15 relative.
_LINF_FACETS_PER_ROUND = 1


def default_torque_scale(state: GraspState) -> float:
    """The object's bounding radius seen from the contacts (m): the largest distance of a
    force-transmitting contact (F, L, S) from ``state.object_position``; 1 m when there is
    none or all of them lie at the object position (no moment to scale)."""
    radii = [
        float(np.linalg.norm(c.position - state.object_position)) for c in state.contacts if c.type != "D"
    ]
    rho = max(radii, default=0.0)
    return rho if rho > 0.0 else 1.0


def checked_torque_scale(state: GraspState, torque_scale: float | None) -> float:
    """``torque_scale`` validated (a finite number > 0, m), or [`default_torque_scale()`][mjtvm.measures.wrenches.default_torque_scale]."""
    if torque_scale is None:
        return default_torque_scale(state)
    if isinstance(torque_scale, bool) or not isinstance(torque_scale, (int, float, np.floating, np.integer)):
        raise ParamError("torque_scale", f"expected a number > 0 (m), got {type(torque_scale).__name__}")
    rho = float(torque_scale)
    if not np.isfinite(rho) or rho <= 0.0:
        raise ParamError("torque_scale", f"expected a finite number > 0 (m), got {rho!r}")
    return rho


def _wrench_scale(state: GraspState, rho: float) -> NDArray[np.float64]:
    d = state.dim
    return np.concatenate([np.ones(d), np.full(state.twist_dim - d, 1.0 / rho)])


def primitive_wrenches(state: GraspState, torque_scale: float) -> list[NDArray[np.float64]]:
    """Per contact, ``(D, g)`` the scaled wrenches of its force generators (module docstring);
    ``g = 0`` for a D-point.

    Parameters
    ----------
    state
        The grasp state.
    torque_scale
        ``rho`` (m): moments (N m) are divided by it.
    """
    scale = _wrench_scale(state, torque_scale)
    out = []
    for c in margin_contacts(state):  # F pyramids at the state's friction margin
        gt = grasp_map_transpose(c.position, state.object_position)
        out.append(scale[:, None] * (gt.T @ force_generators(c, state.friction_edges)))
    return out


def grasp_matrix(state: GraspState, torque_scale: float) -> NDArray[np.float64]:
    r"""``(D, n)`` the grasp matrix $G$ (Li & Sastry 1988) of the components each contact
    transmits: all d force components of an F contact (the columns of $G_{ij}$ =
    $(G_{ij}^T)^T$), the normal $G_{ij} n$ of an L or S contact, nothing of a
    D-point; moment rows divided by ``torque_scale``. ``n = 0`` gives a ``(D, 0)`` matrix."""
    scale = _wrench_scale(state, torque_scale)
    cols = [np.zeros((state.twist_dim, 0))]
    for c in state.contacts:
        if c.type == "D":
            continue
        g = grasp_map_transpose(c.position, state.object_position).T
        cols.append(g if c.type == "F" else g @ c.normal.reshape(-1, 1))
    return scale[:, None] * np.hstack(cols)


def scaled_rank(m: NDArray[np.float64]) -> int:
    """Rank of ``m`` with singular values below `RANK_REL_TOL` x the largest as 0."""
    if m.size == 0:
        return 0
    s = np.linalg.svd(m, compute_uv=False)
    return int(np.sum(s > RANK_REL_TOL * s[0])) if s[0] > 0.0 else 0


def closure_margin(wrenches: NDArray[np.float64]) -> float:
    r"""The force-closure LP's margin of ``(D, n)`` primitive wrenches ``W``.

    ``max t`` s.t. ``W lam = 0``, ``sum lam = 1``, ``lam_k >= t``, returned as ``n t``: 1 when
    the uniform weights balance, > 0 exactly when the origin is a strictly positive
    combination of all the wrenches. With ``rank W = D`` that is force closure: the wrenches
    then positively span the wrench space, i.e. the origin lies strictly inside their convex
    hull (Murray, Li & Sastry 1994, ch. 5). Solved by HiGHS ([`solve_lp()`][mjtvm.lp.solvers.solve_lp]).
    """
    big_d, n = wrenches.shape
    if n == 0:
        return 0.0
    # With lam = mu + t 1 (mu >= 0, t >= 0: lam >= 0 and lam >= t, and t = 0 is feasible
    # whenever the LP is), the rows are W mu + t W 1 = 0 (D) and sum mu + n t = 1: D + 1 rows
    # instead of D + 1 + n, the same optimum (1.6e-14 relative on the five-finger Shadow
    # grasps) in 40% less time. HiGHS directly (the equilibrated session of mjtvm.lp):
    # scipy's linprog wrapper cost more than the LP itself.
    a = np.zeros((big_d + 1, n + 1))
    a[:big_d, :n] = wrenches
    a[:big_d, n] = wrenches.sum(axis=1)
    a[big_d, :n] = 1.0
    a[big_d, n] = n
    row_lower = np.zeros(big_d + 1)
    row_lower[big_d] = 1.0
    row_upper = row_lower.copy()
    c = np.zeros(n + 1)
    c[n] = -1.0
    col_lower = np.zeros(n + 1)
    col_upper = np.full(n + 1, np.inf)
    lp = LinearProgram(c, sp.csc_matrix(a), row_lower, row_upper, col_lower, col_upper)
    try:
        sol = solve_lp(lp)
    except SolverError as e:
        raise SolverError("highs", f"force-closure LP: {e}") from e
    if sol.status == "infeasible":  # the origin is no combination of the wrenches
        return 0.0
    if sol.status != "optimal" or sol.x is None:
        raise SolverError("highs", f"force-closure LP: {sol.status}")
    return float(n * sol.x[n])


def epsilon_l1(wrenches: NDArray[np.float64], *, margin: float | None = None) -> float:
    r"""Ferrari-Canny's L1 epsilon of ``(D, n)`` primitive wrenches: the radius of the largest
    ball about the origin inside their convex hull (the wrenches of unit total normal force;
    Ferrari & Canny 1992, GraspIt!'s quality measure of Miller & Allen 2004); 0 when the
    origin is not strictly inside (``rank < D`` or [`closure_margin()`][mjtvm.measures.wrenches.closure_margin]
    ``<= 0``: ``margin`` when the caller has it).

    Not the whole hull (2663 facets for the 48 wrenches of a three-finger grasp in 6-D): the
    expanding polytope of [`epsilon_linf()`][mjtvm.measures.wrenches.epsilon_linf] on the one set
    conv(W), whose support function is ``max_k u^T w_k``; it stops when its inner polytope's
    nearest facet is a facet of the hull (its distance and its normal's support value agree
    within `LINF_REL_TOL` x the largest wrench), 7x faster on the Shadow example dataset and
    within 2e-13 relative of the whole hull's nearest facet. Exact up to Qhull's round-off."""
    big_d, n = wrenches.shape
    if n <= big_d:
        return 0.0
    return _expanding([wrenches], margin)[0]


def _supports(
    groups: list[NDArray[np.float64]], u: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""The support function $h(u) = \sum_i \max(0, \max_k u^T w_{ik})$ of ``(n, D)``
    directions at once and a point attaining it: ``(n,)`` values, ``(n, D)`` points (the sum
    of each contact's best wrench, or of nothing where no wrench of it is positive)."""
    values, points = np.zeros(u.shape[0]), np.zeros_like(u)
    rows = np.arange(u.shape[0])
    for w in groups:
        s = u @ w
        k = np.argmax(s, axis=1)
        best = s[rows, k]
        on = best > 0.0
        values += np.where(on, best, 0.0)
        points += w[:, k].T * on[:, None]
    return values, points


def epsilon_linf(groups: list[NDArray[np.float64]], *, margin: float | None = None) -> tuple[float, float]:
    r"""Ferrari-Canny's L-infinity epsilon: the radius of the largest ball about the origin
    inside the Minkowski sum of the contacts' sets conv(0, W_i) (each contact's normal force
    at most 1), with the bracket's width.

    The sum has up to $\prod (g_i + 1)$ vertices, so it is not built: the expanding
    polytope algorithm refines an inner polytope ``Q`` (the hull of support points, so
    ``Q`` lies inside the sum) from its facet nearest the origin. The support function
    $h(u) = \sum_i \max(0, \max_k u^T w_{ik})$ is the optimum of the support LP over
    ``lam >= 0``, ``sum_k lam_ik <= 1``, in closed form. The nearest facet's distance of ``Q``
    is a lower bound, the smallest ``h(u)`` queried an upper bound (every facet of the sum
    has its normal's support value as its distance); refinement stops when they agree within
    `LINF_REL_TOL` x the largest wrench.

    Parameters
    ----------
    groups
        Per contact, ``(D, g_i)`` primitive wrenches ([`primitive_wrenches()`][mjtvm.measures.wrenches.primitive_wrenches]).
    margin
        [`closure_margin()`][mjtvm.measures.wrenches.closure_margin] of all of them, when the caller has it
        (not solved again).

    Returns
    -------
    (epsilon, gap)
        The lower bound (0 without force closure) and the upper bound minus it.
    """
    return _expanding(groups, margin)


def _expanding(groups: list[NDArray[np.float64]], margin: float | None) -> tuple[float, float]:
    """The expanding polytope of [`epsilon_linf()`][mjtvm.measures.wrenches.epsilon_linf] on ``groups``:
    ``(lower bound, bracket width)``, ``(0, 0)`` without force closure."""
    groups = [w for w in groups if w.shape[1] > 0]
    if not groups:
        return 0.0, 0.0
    big_d = groups[0].shape[0]
    allw = np.hstack(groups)
    if margin is None:
        margin = closure_margin(allw)
    if scaled_rank(allw) < big_d or margin <= 0.0:
        return 0.0, 0.0
    size = float(np.max(np.linalg.norm(allw, axis=0)))
    tol = LINF_REL_TOL * size
    # Seeded by the 2D axis directions only: with force closure each has a support point
    # strictly on its side, so their hull is full-dimensional, and the refinement adds points
    # only where the nearest facets are. Extra (random) seeds grow the hull everywhere
    # (6445 facets for 140 points in 6-D): 64 of them made the example dataset's 32 grasps
    # take 7.6 s instead of 0.8 s, for the same epsilons (within 3e-14).
    seeds = np.vstack([np.eye(big_d), -np.eye(big_d)])
    h0, p0 = _supports(groups, seeds / np.linalg.norm(seeds, axis=1, keepdims=True))
    upper = float(h0.min())
    hull = GrowingHull(p0)
    if hull.compiled:  # the same rounds as below, in numba (mjtvm.measures.hull_jit)
        starts = np.cumsum([0, *(w.shape[1] for w in groups)]).astype(np.int64)
        up, _ = hull.expand(allw, starts, tol, _LINF_MAX_ROUNDS)
        lower = float(max(0.0, hull.distances().min()))
        upper = min(upper, up)
        return lower, max(0.0, float(upper - lower))
    for _ in range(_LINF_MAX_ROUNDS):
        dist = hull.distances()
        lower = float(max(0.0, dist.min()))
        near = np.argsort(dist)[:_LINF_FACETS_PER_ROUND]  # the nearest facets per hull update
        h, p = _supports(groups, hull.equations[near, :-1])
        upper = min(upper, float(h.min()))
        added = p[h > dist[near] + tol]
        if upper - lower <= tol or not len(added):
            if hull.verified:  # the bounds read off a checked hull of every point
                break
            hull.verify()
            continue
        hull.add(added)
    else:
        hull.verify()
    lower = float(max(0.0, hull.distances().min()))
    return lower, max(0.0, float(upper - lower))
