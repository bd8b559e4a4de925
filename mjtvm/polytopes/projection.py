r"""Problem 1: the projection of the lifted polytope of eq. (26) (eq. 34; :mod:`~mjtvm.polytopes.lifted`).

The TVMS is :math:`S_{ov}`, the projection onto the twist space of the lifted polytope

.. math:: \{ (x, \dot r) : \text{row\_lower} \le A x + A_{twist} \dot r \le
          \text{row\_upper},\ \text{col\_lower} \le x \le \text{col\_upper} \}

built by :func:`~mjtvm.core.assembly.assemble` with one statics copy per REFS vertex
(``statics_bounds`` puts :math:`-w_k` on copy k's balance rows), one common
:math:`\dot q` and one common box (eliminated exactly, :attr:`OperationRange.
mirrored_halfplanes`). With the RVDS cone, :math:`\dot r = \sum_l c_l \hat r_l`,
:math:`c_l \ge 0`, and the variables ``c`` replace :math:`\dot r` (columns
``A_twist @ R^T``). The lifted variables are ``y = [x; z]`` and the twist is
``generators @ z`` (``z`` is :math:`\dot r` itself without the cone).

**The origin.** :math:`S_{ov}` contains :math:`\dot r = 0` whenever it is non-empty:
with :math:`\dot q = 0`, :math:`\rho = 0` every kinematic row holds, and the
operation-range rows :math:`a_\tau |\tau| + a_{qd} |\dot q| \le b` are weakest at
:math:`\dot q = 0`, so the forces and torques of any feasible point still fit. Hence
the affine hull of :math:`S_{ov}` is a linear subspace, and its recession cone is the
projection of the lifted one (obtained from the same rows with zero bounds).

Two exact projections:

* :func:`project_lp` (fast, output-sensitive): LPs in twist space
  (:mod:`~mjtvm.polytopes.oracles`). First the linear hull: support LPs along :math:`\pm e_i`,
  then along directions orthogonal to the points found until each is either extended or
  proved orthogonal to :math:`S_{ov}` (max = min = 0). Inside it, an outer approximation
  refined by cutting planes (the dual of Bretl and Lall's inner one, in any dimension
  <= 6): a polytope O given by valid inequalities (support LPs' values, and the RVDS
  cone's facets when :math:`\dot r` is restricted to it), so O contains :math:`S_{ov}`; its
  vertices come from a convex hull of the polar points (Qhull,
  :class:`~mjtvm.polytopes.hull.PolarHull`); a ray-shooting LP either certifies a vertex as a
  point of :math:`S_{ov}` or yields a supporting hyperplane that cuts it off. When every
  vertex of O is certified, O is :math:`S_{ov}`. The LPs number about vertices +
  facets, and Qhull works on the facets (a few hundred on the Case 2 hand, whose 6-D
  TVMS has 2044 vertices: triangulating those takes 250 000 simplices, which made the
  earlier inner approximation take 47 s).
* :func:`~mjtvm.polytopes.enumeration.project_cdd` (the paper's way, the baseline): vertex
  enumeration of the lifted polytope with cddlib, projection of its vertices, convex hull
  (:func:`~mjtvm.polytopes.hull.reduce_points`).

Both work in scaled coordinates ``s = metric * rdot`` (the vertex set does not depend on
the metric, the tolerances do) and return the vertices in twist coordinates.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ..errors import SolverError
from .hull import ZERO_TOL, PolarHull, cone_facets, distinct, polish_vertices, span
from .lifted import LiftedPolytope, Projection, ProjectionStatus
from .oracles import DistanceOracle, RayShooter, SupportOracle

__all__ = ["REL_TOL", "project_lp"]

REL_TOL = 1e-9  #: tolerance relative to the extent of S_ov (LP tolerances are 1e-9)


def _linear_hull(
    support: SupportOracle, big_d: int, rel_tol: float
) -> tuple[list[NDArray[np.float64]], NDArray[np.float64], float, NDArray[np.float64] | None]:
    r"""Points of :math:`S_{ov}` spanning its linear hull, that hull's basis, the tolerance and a ray.

    LPs along :math:`\pm e_i` give the extent; then, while some direction ``u`` orthogonal
    to the span found so far is left, max and min of :math:`u^T s` either give a point
    off the span or prove ``u`` orthogonal to :math:`S_{ov}` (both 0).
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


def project_lp(
    poly: LiftedPolytope, *, metric: NDArray[np.float64] | None = None, rel_tol: float = REL_TOL
) -> Projection:
    r"""Exact projection of ``poly`` onto the twist space by support LPs (module docstring).

    Parameters
    ----------
    poly
        From :func:`lifted_polytope`.
    metric
        ``(D,)`` positive scaling of the working coordinates (default ones).
    rel_tol
        Facet and linear-hull tolerance, relative to the extent of :math:`S_{ov}`.
    """
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
    ) -> Projection:
        k = -1 if basis is None else basis.shape[0]
        ray_r = None if ray is None else (ray / w) / np.linalg.norm(ray / w)
        twist_facets = None
        if facets is not None and basis is not None:
            # a^T u <= b with u = basis (w * rdot): rows (basis^T a) * w over rdot, made unit.
            rows = (facets[0] @ basis) * w
            norm = np.linalg.norm(rows, axis=1)
            twist_facets = (rows / norm[:, None], facets[1] / norm)
        seconds = time.perf_counter() - t0
        return Projection(
            status, verts / w, k, basis, w, ray_r, support.num_lps, seconds, "lp", None, twist_facets
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
    return _refine(support, distinct(local, tol), basis, tol, result, (rows, offsets))


class _Cutter:
    """The LPs of :func:`_refine` (ray shooting, support, distance; one HiGHS session each),
    which certify vertices of O or cut them off."""

    def __init__(
        self, support: SupportOracle, basis: NDArray[np.float64], center: NDArray[np.float64], tol: float
    ) -> None:
        self.support, self.basis, self.center, self.tol = support, basis, center, tol
        self.rows = basis @ (support.metric[:, None] * support.poly.generators)
        self.shoot = RayShooter(support.poly, self.rows, center)
        self.nearest: DistanceOracle | None = None  # the distance LP only when needed
        self.found: set[tuple[float, ...]] = set()  # support LP solutions, on a grid of 10 tol

    def _cell(self, u: NDArray[np.float64]) -> tuple[float, ...]:
        return tuple(np.round(u / (10 * self.tol)).tolist())

    @property
    def num_lps(self) -> int:
        return self.support.num_lps + self.shoot.num_lps + (self.nearest.num_lps if self.nearest else 0)

    def cut(self, a: NDArray[np.float64]) -> float:
        """The support value :math:`h(a)` of :math:`S_{ov}` along ``a`` (local coordinates)."""
        status, s = self.support(self.basis.T @ a)
        if status != "optimal":  # bounded after _linear_hull: a solver fault
            raise SolverError("highs", f"support LP inside a bounded TVMS: {status}")
        self.found.add(self._cell(self.basis @ s))
        return float(a @ (self.basis @ s))

    def settle(
        self, verts: NDArray[np.float64]
    ) -> tuple[list[NDArray[np.float64]], NDArray[np.float64], NDArray[np.float64]]:
        """The certified vertices among ``verts`` and the rows ``(normals, offsets)`` cutting off the rest."""
        k, tol, center = self.basis.shape[0], self.tol, self.center
        certified: list[NDArray[np.float64]] = []
        new_n, new_b, cuts = np.zeros((len(verts), k)), np.zeros(len(verts)), 0
        for v in verts:
            if cuts and np.any(new_n[:cuts] @ v - new_b[:cuts] > tol):
                continue  # cut off by a row of this round already
            if self._cell(v) in self.found:  # a support LP's solution: a point of S_ov
                certified.append(v)
                continue
            t, a = self.shoot(v - center)
            if (1.0 - t) * np.linalg.norm(v - center) <= 10 * tol:  # as close as distinct() merges
                certified.append(v)
                continue
            b = self.cut(a)
            if a @ v <= b + tol:
                # The ray left S_ov far from v, but v lies within tol of that hyperplane (a ray
                # nearly along a facet, or duals picked at a lower-dimensional face): measure the
                # distance itself and cut with the dual's hyperplane.
                self.nearest = self.nearest or DistanceOracle(self.support.poly, self.rows)
                delta, a = self.nearest(v)
                if delta <= tol:
                    certified.append(v)
                    continue
                b = self.cut(a)
                if a @ v <= b + tol:
                    raise SolverError("highs", "no cutting plane separates a vertex outside the TVMS")
            new_n[cuts], new_b[cuts], cuts = a, b, cuts + 1
        return certified, new_n[:cuts], new_b[:cuts]


def _chain(points: NDArray[np.float64], center: NDArray[np.float64]) -> NDArray[np.int64]:
    """An order of ``points`` that keeps neighbours together, so that consecutive LPs
    warm-start from a nearby basis: lexicographic in their directions from ``center``
    rounded to a grid of 1/4 (Case 2's rays: 4.5 simplex iterations instead of 7 in the
    order Qhull gives, 16 in a random one; a greedy nearest-neighbour tour, 3.3, costs
    more in Python than it saves)."""
    d = points - center
    d = np.round(4.0 * d / np.linalg.norm(d, axis=1)[:, None])
    return np.lexsort(d.T[::-1])


def _refine(
    support: SupportOracle,
    local: NDArray[np.float64],
    basis: NDArray[np.float64],
    tol: float,
    result: Any,
    bounds: tuple[NDArray[np.float64], NDArray[np.float64]],
) -> Projection:
    r"""Outer approximation refined by cutting planes inside the linear hull (module docstring).

    ``local``: points of :math:`S_{ov}` spanning its linear hull, in its coordinates ``u``.
    ``O`` = :math:`\{u : a_j^T u \le b_j\}` starts as ``bounds`` (the support LPs along
    :math:`\pm e_i` of the twist and the RVDS cone's facets, in these coordinates) or, where
    they leave O unbounded, as the box of support LPs along :math:`\pm e_i` of ``u``; every
    row is a support LP's value or a facet of a cone that holds :math:`S_{ov}`, so
    :math:`O \supseteq S_{ov}`. Each round enumerates O's vertices (:class:`PolarHull`, which keeps Qhull's hull of the
    polar points between rounds) and shoots a ray from the centre ``c`` of the points to
    each vertex not yet certified (:class:`RayShooter`): a ray that reaches it (to ``10 tol``)
    certifies the vertex as a point of :math:`S_{ov}`, hence one of its vertices; otherwise
    the duals give the normal ``a`` of a hyperplane supporting :math:`S_{ov}` where the ray
    leaves it, and the support LP along ``a`` adds the row :math:`a^T u \le h(a)`, which cuts
    the vertex off. A vertex within ``tol`` of that row is settled by its distance to
    :math:`S_{ov}` (:class:`DistanceOracle`): within ``tol``, certified; otherwise cut off by
    the dual's separating hyperplane. When a round certifies every vertex, O =
    :math:`S_{ov}` (to ``10 tol``); :func:`polish_vertices` then refits the facets and sorts
    out the vertices. The rays of a round go in an order that keeps neighbours together
    (:func:`_chain`), and a vertex that is a support LP's solution needs none.
    """
    k = basis.shape[0]
    center = local.mean(axis=0)
    cutter = _Cutter(support, basis, center, tol)
    normals, offsets = bounds
    if np.linalg.matrix_rank(normals) < k:  # O would be unbounded (not met: basis rows span)
        normals = np.vstack([np.eye(k), -np.eye(k)])
        offsets = np.array([cutter.cut(a) for a in normals])
    certified: list[NDArray[np.float64]] = []
    polar = PolarHull(normals, offsets, center, tol)
    while True:
        verts = polar.new_vertices()
        if certified:
            verts = verts[cKDTree(certified).query(verts)[0] > 10 * tol]
        sure, new_n, new_b = cutter.settle(verts[_chain(verts, center)])
        certified.extend(sure)
        if not len(new_n):
            break
        polar.add(new_n, new_b)
    support.num_lps = cutter.num_lps
    verts, facet_n, facet_b = polish_vertices(np.array(certified), polar.normals, polar.offsets, tol)
    return result("bounded", verts @ basis, basis, facets=(facet_n, facet_b))
