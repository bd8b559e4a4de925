r"""Convex hulls of point sets that may span a subspace: the geometry under Problem 1.

* :func:`triangulate`: simplicial facets of a full-dimensional point set (Qhull, joggled);
  :func:`fit_planes` refits each simplex's plane on the unperturbed points, and
  :class:`PlaneCache` keeps the distinct planes met across rebuilt hulls;
* :func:`vertex_mask`, :func:`distinct`, :func:`span`: vertices of a triangulated hull,
  clusters of round-off, linear hulls;
* :func:`reduce_points`: linear hull and vertices of the hull of points and the origin
  (the last step of the cdd baseline);
* :func:`hull_volume` and :func:`hausdorff`: measures.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError, cKDTree
from scipy.spatial.distance import cdist

from .errors import SolverError

__all__ = [
    "CDD_REL_TOL",
    "SLIVER",
    "ZERO_TOL",
    "PlaneCache",
    "distinct",
    "fit_planes",
    "hausdorff",
    "hull_volume",
    "reduce_points",
    "span",
    "triangulate",
    "vertex_mask",
]

ZERO_TOL = 1e-9  #: an S_ov within this distance of the origin (scaled units) is {0}
SLIVER = 1e-8  #: simplices flatter than this (singular-value ratio) span no facet
CDD_REL_TOL = 1e-9  #: round-off of float cddlib relative to the extent


def triangulate(
    local: NDArray[np.float64],
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.int64]]:
    r"""Simplicial facets of the hull of ``(n, k)`` full-dimensional points, k >= 2.

    Qhull on joggled points ("QJ"): it never fails on the degenerate point sets a TVMS
    gives (many points on one facet, where Qhull's facet merging gives up). Returns the
    ``(F, k)`` point indices of each simplex, Qhull's ``(F, k)`` outward normals (of the
    joggled simplices) and the indices of the hull's points.
    """
    try:
        hull = ConvexHull(local, qhull_options="QJ")
    except QhullError as e:
        raise SolverError("qhull", str(e).splitlines()[0] if str(e) else "QhullError") from e
    return np.asarray(hull.simplices), hull.equations[:, :-1], np.asarray(hull.vertices)


def fit_planes(
    local: NDArray[np.float64], simp: NDArray[np.int64], normals: NDArray[np.float64]
) -> NDArray[np.float64]:
    r"""Rows ``[a, b, c]``: the plane ``a^T t = b`` (``|a| = 1``, oriented like ``normals``)
    through each simplex's unperturbed points, which removes the joggle's tilt, and the
    ratio ``c`` of the smallest to the largest singular value of its edge vectors.
    Simplices with ``c <=`` :data:`SLIVER` are slivers: their points span less than a
    hyperplane (they fill lower-dimensional faces in the joggled triangulation), and no
    facet of the hull is made of slivers only."""
    x = local[simp]
    _, sv, vt = np.linalg.svd(x[:, 1:] - x[:, :1])
    a = vt[:, -1] * np.sign(np.einsum("fk,fk->f", vt[:, -1], normals))[:, None]
    return np.column_stack([a, np.einsum("fk,fk->f", a, x[:, 0]), sv[:, -1] / sv[:, 0]])


class PlaneCache:
    r"""The facet planes met so far, with a flag for those confirmed by an LP.

    Cached by the points spanning a simplex (a 64-bit hash of their sorted ids) and by
    the plane's coefficients (rounded: normal to 1e-8, offset to ``tol``), so that a
    plane is fitted and solved once however often the hull is rebuilt.
    """

    def __init__(self, k: int, tol: float) -> None:
        self.k, self.tol = k, tol
        self.rows = np.zeros((0, k + 2))
        self.confirmed = np.zeros(0, dtype=bool)
        rng = np.random.default_rng(12345)
        self._mult = rng.integers(1, 2**62, size=k + 1, dtype=np.uint64) * np.uint64(2) + np.uint64(1)
        self._by_points = (np.zeros(0, dtype=np.uint64), np.zeros(0, dtype=np.int64))
        self._by_coeffs = (np.zeros(0, dtype=np.uint64), np.zeros(0, dtype=np.int64))

    def _hash(self, keys: NDArray[np.int64]) -> NDArray[np.uint64]:
        with np.errstate(over="ignore"):
            return np.sum(keys.astype(np.uint64) * self._mult[: keys.shape[1]], axis=1, dtype=np.uint64)

    @staticmethod
    def _find(
        table: tuple[NDArray[np.uint64], NDArray[np.int64]], keys: NDArray[np.uint64]
    ) -> tuple[NDArray[np.bool_], NDArray[np.int64]]:
        pos = np.minimum(np.searchsorted(table[0], keys), max(len(table[0]) - 1, 0))
        found = (table[0][pos] == keys) if len(table[0]) else np.zeros(len(keys), dtype=bool)
        return found, np.where(found, table[1][pos] if len(table[1]) else 0, -1)

    @staticmethod
    def _insert(
        table: tuple[NDArray[np.uint64], NDArray[np.int64]],
        keys: NDArray[np.uint64],
        values: NDArray[np.int64],
    ) -> tuple[NDArray[np.uint64], NDArray[np.int64]]:
        k, v = np.concatenate([table[0], keys]), np.concatenate([table[1], values])
        order = np.argsort(k, kind="stable")
        return k[order], v[order]

    def of(
        self,
        local: NDArray[np.float64],
        ids: NDArray[np.int64],
        simp: NDArray[np.int64],
        normals: NDArray[np.float64],
    ) -> NDArray[np.int64]:
        """The plane index of each simplex (fitting and registering the new ones)."""
        point_keys = self._hash(np.sort(ids[simp], axis=1))
        found, plane = self._find(self._by_points, point_keys)
        miss = np.flatnonzero(~found)
        if len(miss):
            fitted = fit_planes(local, simp[miss], normals[miss])
            rounded = np.round(np.column_stack([fitted[:, : self.k] * 1e8, fitted[:, self.k] / self.tol]))
            coeff_keys = self._hash(rounded.astype(np.int64))
            # A sliver's plane is arbitrary (its points span less than a hyperplane): keyed by its
            # points, so that it never stands for (and confirms) a real facet's plane.
            sliver = fitted[:, -1] <= SLIVER
            coeff_keys[sliver] = ~point_keys[miss][sliver]
            known, j = self._find(self._by_coeffs, coeff_keys)
            fresh, first, inverse = np.unique(coeff_keys[~known], return_index=True, return_inverse=True)
            index = len(self.rows) + np.arange(len(fresh))
            rows = fitted[~known][first]
            self.rows = np.vstack([self.rows, rows])
            self.confirmed = np.concatenate([self.confirmed, rows[:, -1] <= SLIVER])  # slivers need no LP
            j[~known] = index[inverse.ravel()]
            self._by_coeffs = self._insert(self._by_coeffs, fresh, index)
            self._by_points = self._insert(self._by_points, point_keys[miss], j)
            plane[miss] = j
        return plane


def vertex_mask(
    local: NDArray[np.float64], simp: NDArray[np.int64], candidates: NDArray[np.int64], tol: float
) -> NDArray[np.bool_]:
    r"""Which ``candidates`` (indices of ``local``) are vertices of the hull triangulated by ``simp``.

    A point inside a face of dimension >= 1 lies in the convex hull of its neighbours
    in the triangulation (its star covers a neighbourhood of it in the face), a vertex
    does not; the distance is measured by non-negative least squares on
    ``[Q - p; 1] mu = [0; 1]``, ``mu >= 0``, and distances up to ``10 tol`` are round-off.
    """
    from scipy.optimize import nnls

    scale = float(np.max(np.abs(local)))
    owner = simp.ravel()
    order = np.argsort(owner, kind="stable")
    starts = np.searchsorted(owner[order], np.arange(len(local) + 1))
    facet = np.repeat(np.arange(len(simp)), simp.shape[1])[order]
    mask = np.zeros(len(candidates), dtype=bool)
    for n, i in enumerate(candidates):
        near = np.setdiff1d(simp[facet[starts[i] : starts[i + 1]]], [i])
        y = np.vstack([((local[near] - local[i]) / scale).T, np.ones(len(near))])
        mask[n] = len(near) == 0 or nnls(y, np.append(np.zeros(local.shape[1]), 1.0))[1] > 10 * tol / scale
    return mask


def distinct(points: NDArray[np.float64], radius: float) -> NDArray[np.float64]:
    """One point of each cluster of ``points`` closer than ``radius`` (the first one)."""
    near = cKDTree(points).query_ball_point(points, radius)
    return points[[i for i, group in enumerate(near) if min(group) == i]]


def span(points: NDArray[np.float64], tol: float) -> NDArray[np.float64]:
    """``(k, D)`` orthonormal basis of the linear span of ``(n, D)`` points (round-off ``tol``)."""
    _, sv, vt = np.linalg.svd(points, full_matrices=False)
    return vt[: int(np.sum(sv > tol * np.sqrt(len(points))))]


def reduce_points(
    points: NDArray[np.float64], *, rel_tol: float = CDD_REL_TOL
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Linear hull and vertices of the convex hull of ``(n, D)`` points and the origin.

    Parameters
    ----------
    points
        Points in (scaled) twist coordinates, e.g. the projected lifted vertices.
    rel_tol
        Distances below ``rel_tol`` x extent are round-off.

    Returns
    -------
    vertices, basis
        ``(v, D)`` the vertices, projected onto the span, and the ``(k, D)``
        orthonormal basis of that span.
    """
    big_d = points.shape[1]
    pts = np.vstack([np.zeros((1, big_d)), points])
    extent = float(np.max(np.abs(pts)))
    if extent <= ZERO_TOL:
        return np.zeros((1, big_d)), np.zeros((0, big_d))
    tol = rel_tol * extent
    basis = span(pts, tol)
    local = distinct(pts @ basis.T, tol)
    if basis.shape[0] == 1:
        ends = local[[np.argmin(local[:, 0]), np.argmax(local[:, 0])]]
        return ends @ basis, basis
    simp, _, idx = triangulate(local)
    verts = local[idx[vertex_mask(local, simp, idx, tol)]]
    return distinct(verts, 10 * tol) @ basis, basis


def hull_volume(points: NDArray[np.float64]) -> float:
    """Volume of the hull of ``(n, k)`` full-dimensional points, k >= 2 (joggled if Qhull needs it)."""
    try:
        return float(ConvexHull(points).volume)
    except QhullError:
        return float(ConvexHull(points, qhull_options="QJ").volume)


def hausdorff(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """Hausdorff distance of two non-empty ``(n, D)`` and ``(m, D)`` point sets."""
    d = cdist(a, b)
    return float(max(d.min(axis=0).max(), d.min(axis=1).max()))
