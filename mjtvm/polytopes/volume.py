r"""Measures of the polytopes of Problem 1: volumes and the Hausdorff distance.

* [`hull_volume()`][mjtvm.polytopes.volume.hull_volume]: one Qhull hull of the vertices;
* [`facet_volume()`][mjtvm.polytopes.volume.facet_volume]: pyramids over the facets that [`polish_vertices()`][mjtvm.polytopes.hull.polish_vertices]
  returns (no triangulation of the whole polytope);
* [`hausdorff()`][mjtvm.polytopes.volume.hausdorff]: the distance of two vertex sets (tests, benchmarks).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError
from scipy.spatial.distance import cdist

from mjtvm.polytopes.hull import JOGGLE, incidence

__all__ = ["facet_volume", "hausdorff", "hull_volume"]


def _joggled(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """``points`` moved by a seeded uniform perturbation of [`JOGGLE`][mjtvm.polytopes.hull.JOGGLE] x their extent."""
    rng = np.random.default_rng(0)
    return points + rng.uniform(-1.0, 1.0, points.shape) * JOGGLE * np.max(np.abs(points))


def hull_volume(points: NDArray[np.float64]) -> float:
    """Volume of the hull of ``(n, k)`` full-dimensional points, k >= 2.

    Where Qhull gives up on degenerate points, they are joggled by `JOGGLE` x their
    extent (a relative volume error of that order), and only then by Qhull's "QJ", whose
    retries can joggle by up to 1e-6 relative and more.
    """
    try:
        return float(ConvexHull(points).volume)
    except QhullError:
        pass
    try:
        return float(ConvexHull(_joggled(points)).volume)
    except QhullError:
        return float(ConvexHull(points, qhull_options="QJ").volume)


def _coplanar_groups(
    points: NDArray[np.float64], on: NDArray[np.bool_], normals: NDArray[np.float64], tol: float
) -> list[NDArray[np.int64]]:
    """Facets (columns of ``on``) whose common points span a hyperplane, in groups.

    Two facets share at most a ridge, of dimension k - 2; facets at a tiny angle (a sliver
    of S_ov) can share, to ``10 tol``, a region of dimension k - 1: the points of one lie in
    the band of the other, and counting both would count that region twice. Such facets are
    one group (a union-find over the pairs found).
    """
    k = points.shape[1]
    parent = list(range(on.shape[1]))

    def root(j: int) -> int:
        while parent[j] != j:
            parent[j] = parent[parent[j]]
            j = parent[j]
        return j

    # Facets sharing >= k points (a sparse product: the incidence has a few facets per point),
    # of those the nearly parallel ones: points 10 tol from both planes over a face of
    # diameter d make an angle <= 20 tol / d, far below this cheap filter.
    if on.size <= 2**24:  # small: one BLAS product (integer matmul is not BLAS)
        rows, cols = np.nonzero(np.triu(on.T.astype(float) @ on.astype(float) >= k, 1))
    else:
        sparse_on = sp.csc_matrix(on, dtype=np.int32)
        shared = sp.triu(sparse_on.T @ sparse_on, 1).tocoo()
        pick = shared.data >= k
        rows, cols = shared.row[pick], shared.col[pick]
    close = np.einsum("ij,ij->i", normals[rows], normals[cols]) > 1.0 - 1e-6
    for i, j in zip(rows[close], cols[close], strict=True):
        q = points[on[:, i] & on[:, j]]
        sv = np.linalg.svd(q - q.mean(axis=0), compute_uv=False)
        if sv[k - 2] > 10 * tol * np.sqrt(len(q)):
            parent[root(int(i))] = root(int(j))
    groups: dict[int, list[int]] = {}
    for j in range(on.shape[1]):
        groups.setdefault(root(j), []).append(j)
    return [np.array(g) for g in groups.values()]


def facet_volume(
    points: NDArray[np.float64], normals: NDArray[np.float64], offsets: NDArray[np.float64], tol: float
) -> float:
    r"""Volume of the full-dimensional polytope with vertices ``(n, k)`` and facets
    $a_j^T u \le b_j$ ([`polish_vertices()`][mjtvm.polytopes.hull.polish_vertices]), k >= 2, as pyramids over its facets.

    With ``c`` the mean of the vertices, $V = \sum_j h_j A_j / k$, where $h_j$
    is the distance from ``c`` to facet j's plane and $A_j$ the (k-1)-volume of the
    facet, the hull of its vertices (those within ``10 tol``) in that plane. Facets at a
    tiny angle that share a (k-1)-dimensional region to ``10 tol`` are measured as one
    (`_coplanar_groups()`; otherwise that region counts twice: 1e-5 of Case 2's TVMS),
    with the least-squares plane of their points: the error is the sliver between them,
    $\le 10\,tol \times$ its area.

    Each facet's area comes from Qhull on its points joggled by `JOGGLE` (so that it
    never gives up on degenerate faces), with the simplices measured on the unperturbed
    points: a simplex's sign is the joggled one's, so the signed sum is the area of the
    facet's boundary cycle, exact up to the joggle's effect on which simplices there are
    (round-off of order JOGGLE). Qhull works on a few dozen points per facet instead of
    triangulating the whole polytope, which degenerate facets make slow (Case 2: 250 000
    simplices); the facets are measured on two threads (Qhull releases the GIL).
    """
    from concurrent.futures import ThreadPoolExecutor

    k = points.shape[1]
    on = incidence(points, normals, offsets, 10 * tol)
    center = points.mean(axis=0)

    def pyramid(group: NDArray[np.int64]) -> float:
        q = points[np.any(on[:, group], axis=1)]
        if len(q) < k:
            return 0.0
        mean = q.mean(axis=0)
        _, _, vt = np.linalg.svd(q - mean, full_matrices=False)
        height = abs(vt[k - 1] @ (mean - center))
        x = (q - mean) @ vt[: k - 1].T  # coordinates in the facet's plane
        if k == 2:
            return height * float(np.ptp(x)) / 2
        joggled = _joggled(x)
        try:
            simp = np.asarray(ConvexHull(joggled).simplices)
        except QhullError:
            return 0.0  # fewer than k affinely independent points: no area
        # Cones from the mean (x = 0) over the boundary simplices, oriented as the joggled ones.
        sign = np.sign(np.linalg.det(joggled[simp] - joggled.mean(axis=0)))
        area = np.sum(sign * np.linalg.det(x[simp])) / math.factorial(k - 1)
        return height * abs(float(area)) / k

    groups = _coplanar_groups(points, on, normals, tol)
    if len(groups) > 64:
        with ThreadPoolExecutor(2) as pool:
            return float(sum(pool.map(pyramid, groups)))
    return float(sum(pyramid(g) for g in groups))


def hausdorff(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """Hausdorff distance of two non-empty ``(n, D)`` and ``(m, D)`` point sets."""
    d = cdist(a, b)
    return float(max(d.min(axis=0).max(), d.min(axis=1).max()))
