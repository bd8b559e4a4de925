r"""Problem 1: the projection of the lifted polytope of eq. (26) (eq. 34; [`lifted`][mjtvm.polytopes.lifted]).

The TVMS is $S_{ov}$, the projection onto the twist space of the lifted polytope

$$
\{ (x, \dot r) : \text{row\_lower} \le A x + A_{twist} \dot r \le
\text{row\_upper},\ \text{col\_lower} \le x \le \text{col\_upper} \}
$$

built by `assemble()` with one statics copy per REFS vertex
(``statics_bounds`` puts $-w_k$ on copy k's balance rows), one common
$\dot q$ and one common box (eliminated exactly, `OperationRange.
mirrored_halfplanes`). With the RVDS cone, $\dot r = \sum_l c_l \hat r_l$,
$c_l \ge 0$, and the variables ``c`` replace $\dot r$ (columns
``A_twist @ R^T``). The lifted variables are ``y = [x; z]`` and the twist is
``generators @ z`` (``z`` is $\dot r$ itself without the cone).

**The origin.** $S_{ov}$ contains $\dot r = 0$ whenever it is non-empty:
with $\dot q = 0$, $\rho = 0$ every kinematic row holds, and the
operation-range rows $a_\tau |\tau| + a_{qd} |\dot q| \le b$ are weakest at
$\dot q = 0$, so the forces and torques of any feasible point still fit. Hence
the affine hull of $S_{ov}$ is a linear subspace, and its recession cone is the
projection of the lifted one (obtained from the same rows with zero bounds).

Two exact projections:

* `project_lp()` (fast, output-sensitive): LPs in twist space
  ([`oracles`][mjtvm.polytopes.oracles]). First the linear hull: support LPs along $\pm e_i$,
  then along directions orthogonal to the points found until each is either extended or
  proved orthogonal to $S_{ov}$ (max = min = 0). Inside it, an outer approximation
  refined by cutting planes (the dual of Bretl and Lall's inner one, in any dimension
  <= 6): a polytope O given by valid inequalities (support LPs' values, and the RVDS
  cone's facets when $\dot r$ is restricted to it), so O contains $S_{ov}$; its
  vertices come from a convex hull of the polar points (Qhull,
  [`PolarHull`][mjtvm.polytopes.polar.PolarHull]); a ray-shooting LP either certifies a vertex as a
  point of $S_{ov}$ or yields a supporting hyperplane that cuts it off. When every
  vertex of O is certified, O is $S_{ov}$. The LPs number about vertices +
  facets, and Qhull works on the facets (a few hundred on the Case 2 hand, whose 6-D
  TVMS has 2044 vertices: triangulating those takes 250 000 simplices, so an inner
  approximation built on the vertices takes 47 s).
* `project_cdd()` (the paper's way, the baseline): vertex
  enumeration of the lifted polytope with cddlib, projection of its vertices, convex hull
  ([`reduce_points()`][mjtvm.polytopes.hull.reduce_points]).

Both work in scaled coordinates ``s = metric * rdot`` (the vertex set does not depend on
the metric, the tolerances do) and return the vertices in twist coordinates.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from mjtvm.polytopes.budget import Budget, Limits
from mjtvm.polytopes.hull import ZERO_TOL, cone_facets, distinct, span
from mjtvm.polytopes.lifted import Approximation, LiftedPolytope, Projection, ProjectionStatus
from mjtvm.polytopes.oracles import SupportOracle
from mjtvm.polytopes.refine import refine

__all__ = ["REL_TOL", "project_lp", "twist_rows"]

REL_TOL = 1e-9  #: tolerance relative to the extent of S_ov (LP tolerances are 1e-9)


def _linear_hull(
    support: SupportOracle, big_d: int, rel_tol: float
) -> tuple[list[NDArray[np.float64]], NDArray[np.float64], float, NDArray[np.float64] | None]:
    r"""Points of $S_{ov}$ spanning its linear hull, that hull's basis, the tolerance and a ray.

    LPs along $\pm e_i$ give the extent; then, while some direction ``u`` orthogonal
    to the span found so far is left, max and min of $u^T s$ either give a point
    off the span or prove ``u`` orthogonal to $S_{ov}$ (both 0).
    """
    points: list[NDArray[np.float64]] = []
    ray: NDArray[np.float64] | None = None
    for h in np.vstack([np.eye(big_d), -np.eye(big_d)]):
        status, s = support(h)
        ray = s if status == "unbounded" else ray
        points.append(s)
    extent = float(np.max(np.abs(points)))
    tol = rel_tol * max(extent, 1.0) if ray is not None else rel_tol * extent
    if extent <= ZERO_TOL:
        return [], np.zeros((0, big_d)), tol, None
    basis = span(np.array(points), tol)
    normal_dirs = np.zeros((0, big_d))
    while basis.shape[0] + normal_dirs.shape[0] < big_d:
        known = np.vstack([basis, normal_dirs])
        u = np.linalg.svd(known, full_matrices=True)[2][known.shape[0]]  # orthogonal to known
        for sign in (1.0, -1.0):
            status, s = support(sign * u)
            ray = s if status == "unbounded" else ray
            if sign * (u @ s) > tol:
                points.append(s)
                basis = span(np.array(points), tol)
                break
        else:
            normal_dirs = np.vstack([normal_dirs, u])
    return points, basis, tol, ray


def twist_rows(
    facets: tuple[NDArray[np.float64], NDArray[np.float64]],
    basis: NDArray[np.float64],
    w: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Rows ``a^T u <= b`` in the local coordinates ``u = basis (w * rdot)`` as unit rows over the twist."""
    rows = (facets[0] @ basis) * w
    norm = np.linalg.norm(rows, axis=1)
    return rows / norm[:, None], facets[1] / norm


def project_lp(
    poly: LiftedPolytope,
    *,
    metric: NDArray[np.float64] | None = None,
    rel_tol: float = REL_TOL,
    limits: Limits | None = None,
) -> Projection:
    r"""Exact projection of ``poly`` onto the twist space by support LPs (module docstring).

    Parameters
    ----------
    poly
        From `lifted_polytope()`.
    metric
        ``(D,)`` positive scaling of the working coordinates (default ones).
    rel_tol
        Facet and linear-hull tolerance, relative to the extent of $S_{ov}$.
    limits
        When to stop before the polytope is exact (`Limits`;
        default: exact, within `default_memory_budget()`). Then
        the status is ``"approximate"`` and `Projection.approximation` holds the bracket.
    """
    budget = Budget(limits)
    t0 = time.perf_counter()
    big_d = poly.twist_dim
    w = np.ones(big_d) if metric is None else np.asarray(metric, dtype=float)
    support = SupportOracle(poly, w)

    def result(
        status: ProjectionStatus,
        verts: NDArray[np.float64],
        basis: NDArray[np.float64] | None,
        ray: NDArray[np.float64] | None = None,
        facets: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
        approximation: Approximation | None = None,
    ) -> Projection:
        k = -1 if basis is None else basis.shape[0]
        ray_r = None if ray is None else (ray / w) / np.linalg.norm(ray / w)
        twist_facets = None if facets is None or basis is None else twist_rows(facets, basis, w)
        if approximation is not None and basis is not None:
            approximation = replace(
                approximation,
                inner_facets=twist_rows(approximation.inner_facets, basis, w),
                outer_facets=twist_rows(approximation.outer_facets, basis, w),
            )
        seconds = time.perf_counter() - t0
        return Projection(
            status,
            verts / w,
            k,
            basis,
            w,
            ray_r,
            support.num_lps,
            seconds,
            "lp",
            None,
            twist_facets,
            approximation,
        )

    if support(np.zeros(big_d))[0] == "infeasible":
        return result("empty", np.zeros((0, big_d)), None)
    points, basis, tol, ray = _linear_hull(support, big_d, rel_tol)
    k = basis.shape[0]
    if ray is not None:
        return result("unbounded", np.zeros((0, big_d)), basis, ray)
    if k == 0:
        return result("bounded", np.zeros((1, big_d)), basis)
    local = np.vstack([np.zeros((1, k)), np.array(points) @ basis.T])
    if k == 1:
        ends = np.array([support(sign * basis[0])[1] @ basis[0] for sign in (1.0, -1.0)])
        return result("bounded", np.outer(np.unique(ends), basis[0]), basis)
    # The support LPs along +-e_i bound S_ov: e_i^T s <= h(e_i) reads basis[:, i]^T u <= h(e_i)
    # inside the linear hull, a first outer approximation at no further cost.
    ext = np.array(points[: 2 * big_d])
    rows = np.vstack([basis.T, -basis.T])
    norm = np.linalg.norm(rows, axis=1)
    offsets = np.concatenate([np.diag(ext[:big_d]), -np.diag(ext[big_d:])]) / np.maximum(norm, 1e-300)
    keep = norm > 1e-6  # directions nearly orthogonal to the linear hull say little
    rows, offsets = rows[keep] / norm[keep, None], offsets[keep]
    if poly.cone:
        # Inside the RVDS cone: its facets a^T s >= 0 hold for S_ov, (basis a)^T u >= 0 here.
        cone = -cone_facets(w[:, None] * poly.generators) @ basis.T
        norm = np.linalg.norm(cone, axis=1)
        cone = cone[norm > 1e-6] / norm[norm > 1e-6, None]
        rows, offsets = np.vstack([rows, cone]), np.concatenate([offsets, np.zeros(len(cone))])
    return refine(support, distinct(local, tol), basis, tol, result, (rows, offsets), budget)
