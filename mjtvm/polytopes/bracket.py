r"""The certified bracket of an anytime projection (Problem 1): inner and outer polytopes.

While :func:`~mjtvm.polytopes.projection.project_lp` refines its outer polytope
:math:`O \supseteq S_{ov}` (the cutting planes), every LP also proves points of
:math:`S_{ov}`: the support LPs' solutions, the points where the rays leave it and the
certified vertices. Their hull is the inner polytope :math:`I \subseteq S_{ov}`, so

.. math:: \mathrm{vol}(I) \le \mathrm{vol}(S_{ov}) \le \mathrm{vol}(O), \qquad
          d_H(I, S_{ov}),\ d_H(S_{ov}, O) \le d_H(I, O),

and both sides move monotonically: ``I`` only gains points, ``O`` only gains rows.

Volumes without a triangulation of the whole polytope (an exact decomposition; see
``docs/problem1.md`` for the choice):

* :func:`outer_volume`: pyramids from an interior point over O's facets; each facet's
  vertices come from the simplices of the polar hull that contain its row (no
  points x facets incidence matrix), its area from Qhull in ``k - 1`` dimensions;
* :func:`inner_hull`: Qhull on the proven points (their facets also give the ray lengths
  :func:`ray_lengths` and the Hausdorff bound :func:`hausdorff_bound`).

Every function takes a :class:`~mjtvm.polytopes.budget.Budget` and reserves its arrays
before making them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError, cKDTree

from .budget import Budget, LimitReached
from .hull import JOGGLE, PolarHull

__all__ = ["Bracket", "InnerHull", "hausdorff_bound", "inner_hull", "outer_volume", "ray_lengths"]

QHULL_BYTES_PER_POINT = 2**14  #: a generous estimate of Qhull's memory per input point in 6-D


@dataclass(frozen=True)
class Bracket:
    """Volumes of the inner and outer polytopes (scaled units) and the Hausdorff bound between them."""

    inner: float
    outer: float
    hausdorff: float

    @property
    def gap(self) -> float:
        """``(outer - inner) / outer`` (0 when both are 0)."""
        return (self.outer - self.inner) / self.outer if self.outer > 0 else 0.0


@dataclass(frozen=True)
class InnerHull:
    r"""The hull of proven points: volume, facets :math:`n^T u \le o` (unit ``n``) and vertices."""

    volume: float
    normals: NDArray[np.float64]
    offsets: NDArray[np.float64]
    vertices: NDArray[np.float64]


def _area(x: NDArray[np.float64]) -> float:
    """(k-1)-volume of the hull of ``(n, k-1)`` points, k-1 >= 1 (joggled Qhull, signed simplices
    measured on the exact points as in :func:`~mjtvm.polytopes.volume.facet_volume`)."""
    if x.shape[1] == 1:
        return float(np.ptp(x))
    x = x - x.mean(axis=0)
    extent = float(np.max(np.abs(x))) if len(x) else 0.0
    if len(x) < x.shape[1] + 1 or extent == 0.0:
        return 0.0
    joggled = x + np.random.default_rng(0).uniform(-1.0, 1.0, x.shape) * JOGGLE * extent
    try:
        simp = np.asarray(ConvexHull(joggled).simplices)
    except QhullError:
        return 0.0  # not full-dimensional in the facet's plane: no area
    sign = np.sign(np.linalg.det(joggled[simp] - joggled.mean(axis=0)))
    return abs(float(np.sum(sign * np.linalg.det(x[simp])))) / math.factorial(x.shape[1])


def outer_volume(polar: PolarHull, budget: Budget) -> tuple[float, NDArray[np.float64]]:
    r"""Volume and vertices of :math:`O = \{u : a_j^T u \le b_j\}` (``polar``'s rows).

    :math:`\mathrm{vol}(O) = \sum_j h_j A_j / k` with :math:`h_j = (b_j - a_j^T c) / |a_j|`
    and :math:`A_j` the area of facet j, the hull of the vertices of the polar simplices
    that contain row j, projected on its plane.
    """
    k, center = len(polar.center), polar.center
    u, simp = polar.corners(budget)
    if len(u) == 0:
        return 0.0, u
    owner = simp.ravel()
    order = np.argsort(owner, kind="stable")
    starts = np.searchsorted(owner[order], np.arange(len(polar.offsets) + 1))
    corner = np.repeat(np.arange(len(u)), k)[order]
    total = 0.0
    for j in np.flatnonzero(np.diff(starts) >= k):
        if j % 64 == 0:
            budget.check()
        a, b = polar.normals[j], polar.offsets[j]
        norm = float(np.linalg.norm(a))
        q = u[np.unique(corner[starts[j] : starts[j + 1]])]
        q = q[np.unique(np.round(q / (10 * polar.tol)), axis=0, return_index=True)[1]]  # copies
        plane = np.linalg.svd(a[None, :] / norm)[2][1:]  # orthonormal basis of a's complement
        total += (b - a @ center) / norm * _area(q @ plane.T) / k
    return float(total), np.unique(np.round(u, 12), axis=0)


def inner_hull(points: NDArray[np.float64], budget: Budget) -> InnerHull:
    """The hull of ``(n, k)`` proven points, k >= 2 (joggled by :data:`JOGGLE` of their extent:
    a relative volume error of that order)."""
    k = points.shape[1]
    budget.reserve(len(points) * QHULL_BYTES_PER_POINT * k / 6, "the inner hull (Qhull)")
    extent = float(np.max(np.abs(points)))
    joggled = points + np.random.default_rng(1).uniform(-1.0, 1.0, points.shape) * JOGGLE * extent
    try:
        hull = ConvexHull(joggled)
    except QhullError as e:
        raise LimitReached("geometry", f"no inner hull: {str(e).splitlines()[0]}") from e
    normals, offsets = hull.equations[:, :-1], -hull.equations[:, -1]
    return InnerHull(float(hull.volume), normals, offsets, points[hull.vertices])


def ray_lengths(
    normals: NDArray[np.float64], offsets: NDArray[np.float64], directions: NDArray[np.float64]
) -> NDArray[np.float64]:
    r"""``max t`` with :math:`t d \in \{u : n^T u \le o\}` for each row ``d`` (the origin inside;
    ``inf`` where no row stops the ray)."""
    out = np.full(len(directions), np.inf)
    for i, d in enumerate(directions):
        rate = normals @ d
        hit = rate > 1e-300
        if np.any(hit):
            out[i] = float(np.min(np.maximum(offsets[hit], 0.0) / rate[hit]))
    return out


def hausdorff_bound(
    outer_vertices: NDArray[np.float64], inner: InnerHull, center: NDArray[np.float64], budget: Budget
) -> float:
    r"""An upper bound of :math:`d_H(I, O)`: as I is inside O, :math:`d_H` is the largest
    distance from a vertex ``v`` of O to I, and :math:`d(v, I) \le |v - p|` for the nearest
    vertex ``p`` of I (a k-d tree: no vertices x facets array). ``center`` is unused (kept for
    the ray bound's signature)."""
    if len(outer_vertices) == 0 or len(inner.vertices) == 0:
        return 0.0
    budget.reserve(64.0 * (len(outer_vertices) + len(inner.vertices)), "the Hausdorff bound")
    return float(np.max(cKDTree(inner.vertices).query(outer_vertices)[0]))
