r"""The certified bracket of an anytime projection (Problem 1): inner and outer polytopes.

While `project_lp()` refines its outer polytope
$O \supseteq S_{ov}$ (the cutting planes), every LP also proves points of
$S_{ov}$: the support LPs' solutions, the points where the rays leave it and the
certified vertices. Their hull is the inner polytope $I \subseteq S_{ov}$, so

$$
\mathrm{vol}(I) \le \mathrm{vol}(S_{ov}) \le \mathrm{vol}(O), \qquad
d_H(I, S_{ov}),\ d_H(S_{ov}, O) \le d_H(I, O),
$$

and both sides move monotonically: ``I`` only gains points, ``O`` only gains rows.

Volumes without a triangulation of the whole polytope (an exact decomposition; see
``docs/problem1.md`` for the choice):

* [`outer_volume()`][mjtvm.polytopes.bracket.outer_volume]: O's face lattice from the simplices of its polar hull, and the
  pyramids over its faces, nested ([`lattice`][mjtvm.polytopes.lattice]; no points x facets
  incidence matrix, no triangulation by Qhull);
* [`inner_hull()`][mjtvm.polytopes.bracket.inner_hull]: Qhull on the proven points (their facets also give the ray lengths
  [`ray_lengths()`][mjtvm.polytopes.bracket.ray_lengths] and the Hausdorff bound [`hausdorff_bound()`][mjtvm.polytopes.bracket.hausdorff_bound]).

Every function takes a [`Budget`][mjtvm.polytopes.budget.Budget] and reserves its arrays
before making them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError, cKDTree

from mjtvm.polytopes.budget import Budget, LimitReached
from mjtvm.polytopes.hull import JOGGLE
from mjtvm.polytopes.lattice import FaceLattice
from mjtvm.polytopes.polar import PolarHull

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
    r"""The hull of proven points: volume, facets $n^T u \le o$ (unit ``n``) and vertices."""

    volume: float
    normals: NDArray[np.float64]
    offsets: NDArray[np.float64]
    vertices: NDArray[np.float64]


def outer_volume(polar: PolarHull, budget: Budget) -> tuple[float, FaceLattice]:
    r"""An upper bound of the volume of $O = \{u : a_j^T u \le b_j\}$ (``polar``'s rows)
    and the face lattice it comes from ([`PolarHull.lattice()`][mjtvm.polytopes.polar.PolarHull.lattice], its ``vertices`` and uniform
    points: [`FaceLattice`][mjtvm.polytopes.lattice.FaceLattice]).

    The lattice measures the joggled $O' = \{u : y'^T_j (u - c) \le 1\}$ exactly (the
    pyramids over its faces, nested; no Qhull triangulation of the facets). With
    $\delta_j = y'_j - y_j$ and $R \ge \max_{u \in O} |u - c|$, every
    $u \in O$ has $y'^T_j (u - c) \le 1 + \epsilon$, $\epsilon = R
    \max_j |\delta_j|$: O lies in $c + (1 + \epsilon)(O' - c)$, so
    $\mathrm{vol}(O) \le (1 + \epsilon)^k \mathrm{vol}(O')$ (``R`` from O''s vertices with 1 %
    to spare, as O' is within $\epsilon$ of O). Up to round-off: the corners of flat
    simplices are ill-conditioned (4e-8 relative on the 4- to 6-D cross-polytopes, whose
    vertices lie on 2^(k-1) facets).
    """
    lattice = polar.lattice(budget)
    k = len(polar.center)
    reach = 1.01 * float(np.max(np.linalg.norm(lattice.vertices - polar.center, axis=1), initial=0.0))
    eps = reach * polar.joggle_size()
    return lattice.volume * (1.0 + eps) ** k, lattice


def inner_hull(points: NDArray[np.float64], budget: Budget) -> InnerHull:
    """The hull of ``(n, k)`` proven points, k >= 2 (joggled by [`JOGGLE`][mjtvm.polytopes.bracket.JOGGLE] of their extent:
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
    r"""``max t`` with $t d \in \{u : n^T u \le o\}$ for each row ``d`` (the origin inside;
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
    r"""An upper bound of $d_H(I, O)$: as I is inside O, $d_H$ is the largest
    distance from a vertex ``v`` of O to I, and $d(v, I) \le |v - p|$ for the nearest
    vertex ``p`` of I (a k-d tree: no vertices x facets array). ``center`` is unused (kept for
    the ray bound's signature)."""
    if len(outer_vertices) == 0 or len(inner.vertices) == 0:
        return 0.0
    budget.reserve(64.0 * (len(outer_vertices) + len(inner.vertices)), "the Hausdorff bound")
    return float(np.max(cKDTree(inner.vertices).query(outer_vertices)[0]))
