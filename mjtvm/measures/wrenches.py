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
from numpy.typing import NDArray
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, QhullError

from mjtvm.errors import ParamError, SolverError
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
_LINF_MAX_ROUNDS = 400
_LINF_FACETS_PER_ROUND = 8


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
    hull (Murray, Li & Sastry 1994, ch. 5). Solved by HiGHS (``scipy.optimize.linprog``).
    """
    big_d, n = wrenches.shape
    if n == 0:
        return 0.0
    a_eq = np.zeros((big_d + 1, n + 1))
    a_eq[:big_d, :n] = wrenches
    a_eq[big_d, :n] = 1.0
    b_eq = np.zeros(big_d + 1)
    b_eq[big_d] = 1.0
    a_ub = np.hstack([-np.eye(n), np.ones((n, 1))])  # t - lam_k <= 0
    c = np.zeros(n + 1)
    c[n] = -1.0
    res = linprog(
        c, A_ub=a_ub, b_ub=np.zeros(n), A_eq=a_eq, b_eq=b_eq, bounds=[(0, None)] * n + [(None, None)],
        method="highs",
    )  # fmt: skip
    if res.status == 2:  # infeasible: the origin is no combination of the wrenches
        return 0.0
    if res.status != 0:
        raise SolverError("highs", f"force-closure LP: {res.message}")
    return float(n * res.x[n])


def _hull(points: NDArray[np.float64]) -> ConvexHull:
    """Qhull's hull; where it gives up on nearly degenerate input (many wrenches of the
    pyramids' edges lie on common facets), joggled by Qhull's "QJ" (about 1e-11 relative,
    more on its retries)."""
    try:
        return ConvexHull(points)
    except QhullError:
        pass
    try:
        return ConvexHull(points, qhull_options="QJ")
    except QhullError as e:
        raise SolverError("qhull", " ".join(str(e).split())[:200] or "QhullError") from e


def epsilon_l1(wrenches: NDArray[np.float64]) -> float:
    r"""Ferrari-Canny's L1 epsilon of ``(D, n)`` primitive wrenches: the radius of the largest
    ball about the origin inside their convex hull (the wrenches of unit total normal force;
    Ferrari & Canny 1992, GraspIt!'s quality measure of Miller & Allen 2004), as the smallest
    distance of a facet of ``scipy.spatial.ConvexHull`` (Qhull) from the origin; 0 when the
    origin is not strictly inside. Exact up to Qhull's round-off (about 1e-12 relative)."""
    big_d, n = wrenches.shape
    if n <= big_d or scaled_rank(wrenches) < big_d:
        return 0.0
    eq = _hull(wrenches.T).equations  # rows [a, b]: a.x + b <= 0 inside, |a| = 1
    return max(0.0, float(np.min(-eq[:, -1])))


class _Hull:
    """A growing point set's hull, rebuilt from all the points (`_hull()`) when asked.

    Not Qhull's incremental mode: on nearly degenerate input (facets wider than its
    precision allows, ``qh_ERRwide``) ``add_points`` ends the process with exit code 7
    instead of raising, which a batch over thousands of grasps meets (a Shadow grasp of
    ``mjtvm rank``'s mesh dataset did)."""

    def __init__(self, points: NDArray[np.float64]) -> None:
        self.points = points

    def add(self, new: NDArray[np.float64]) -> None:
        self.points = np.vstack([self.points, new])

    def equations(self) -> NDArray[np.float64]:
        """``(f, D + 1)`` the facets ``[a, b]``, ``a.x + b <= 0`` inside, ``|a| = 1``."""
        return np.asarray(_hull(self.points).equations)


def _supports(
    groups: list[NDArray[np.float64]], u: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """`_support()` of ``(n, D)`` directions at once: ``(n,)`` values, ``(n, D)`` points."""
    values, points = np.zeros(u.shape[0]), np.zeros_like(u)
    for w in groups:
        s = u @ w
        k = np.argmax(s, axis=1)
        best = s[np.arange(u.shape[0]), k]
        on = best > 0.0
        values += np.where(on, best, 0.0)
        points += np.where(on[:, None], w[:, k].T, 0.0)
    return values, points


def epsilon_linf(groups: list[NDArray[np.float64]]) -> tuple[float, float]:
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

    Returns
    -------
    (epsilon, gap)
        The lower bound (0 without force closure) and the upper bound minus it.
    """
    groups = [w for w in groups if w.shape[1] > 0]
    if not groups:
        return 0.0, 0.0
    big_d = groups[0].shape[0]
    allw = np.hstack(groups)
    if scaled_rank(allw) < big_d or closure_margin(allw) <= 0.0:
        return 0.0, 0.0
    size = float(np.max(np.linalg.norm(allw, axis=0)))
    tol = LINF_REL_TOL * size
    # Seeded by the 2D axis directions only: with force closure each has a support point
    # strictly on its side, so their hull is full-dimensional, and the refinement adds points
    # only where the nearest facets are. Extra (random) seeds grow every hull Qhull rebuilds
    # (6445 facets for 140 points in 6-D, ~50 ms each): 64 of them made the example
    # dataset's 32 grasps take 7.6 s instead of 0.8 s, for the same epsilons (within 3e-14).
    seeds = np.vstack([np.eye(big_d), -np.eye(big_d)])
    h0, p0 = _supports(groups, seeds / np.linalg.norm(seeds, axis=1, keepdims=True))
    upper = float(h0.min())
    points = list(p0)
    hull = _Hull(np.array(points))
    lower = 0.0
    for _ in range(_LINF_MAX_ROUNDS):
        eq = hull.equations()
        dist = -eq[:, -1]
        lower = float(max(0.0, dist.min()))
        if upper - lower <= tol:
            break
        near = np.argsort(dist)[:_LINF_FACETS_PER_ROUND]  # the nearest facets per hull update
        h, p = _supports(groups, eq[near, :-1])
        upper = min(upper, float(h.min()))
        added = p[h > dist[near] + tol]
        if not len(added):
            break
        hull.add(added)
    else:
        lower = float(max(0.0, (-hull.equations()[:, -1]).min()))
    return lower, max(0.0, float(upper - lower))
