r"""Convex hulls of point sets that may span a subspace: the geometry under Problem 1.

* [`polish_vertices()`][mjtvm.polytopes.hull.polish_vertices]: the facets and exact vertices of a bounded polytope given by
  inequalities and points (the vertex enumeration is [`polar`][mjtvm.polytopes.polar]);
* [`triangulate()`][mjtvm.polytopes.hull.triangulate]: simplicial facets of a full-dimensional point set (Qhull, joggled);
* [`vertex_mask()`][mjtvm.polytopes.hull.vertex_mask], [`distinct()`][mjtvm.polytopes.hull.distinct], [`span()`][mjtvm.polytopes.hull.span]: vertices of a triangulated hull,
  clusters of round-off, linear hulls;
* [`reduce_points()`][mjtvm.polytopes.hull.reduce_points]: linear hull and vertices of the hull of points and the origin
  (the last step of the cdd baseline); [`cone_facets()`][mjtvm.polytopes.hull.cone_facets]: a cone's facets (cddlib);
* the measures (volumes, Hausdorff distance) are in [`volume`][mjtvm.polytopes.volume].
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError, cKDTree

from mjtvm.errors import SolverError

__all__ = [
    "CDD_REL_TOL",
    "ZERO_TOL",
    "cone_facets",
    "distinct",
    "incidence",
    "polish_vertices",
    "reduce_points",
    "span",
    "triangulate",
    "vertex_mask",
]

ZERO_TOL = 1e-9  #: an S_ov within this distance of the origin (scaled units) is {0}
CDD_REL_TOL = 1e-9  #: round-off of float cddlib relative to the extent
JOGGLE = 1e-9  #: relative perturbation of points before Qhull (polar points, a facet's points)
WELL_APART = 0.05  #: facets through a point whose normals' smallest singular value exceeds this


def _hull_residual(point: NDArray[np.float64], others: NDArray[np.float64], scale: float) -> float:
    """Non-negative least squares on ``[(Q - p) / scale; 1] mu = [0; 1]``, ``mu >= 0``: the
    residual is about the distance from ``p`` to the hull of the rows of ``Q``, over ``scale``."""
    from scipy.optimize import nnls  # imported when needed: 0.1 s

    y = np.vstack([((others - point) / scale).T, np.ones(len(others))])
    return float(nnls(y, np.append(np.zeros(len(point)), 1.0))[1])


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


def incidence(
    points: NDArray[np.float64], normals: NDArray[np.float64], offsets: NDArray[np.float64], band: float
) -> NDArray[np.bool_]:
    """``(n, f)`` whether each point lies within ``band`` of each row's plane, computed in blocks
    of points (never the ``(n, f)`` distances at once: 8 bytes per entry against 1)."""
    out = np.zeros((len(points), len(offsets)), dtype=bool)
    step = max(1, 2**22 // max(len(offsets), 1))
    for lo in range(0, len(points), step):
        out[lo : lo + step] = np.abs(points[lo : lo + step] @ normals.T - offsets) <= band
    return out


def _distinct_columns(incident: NDArray[np.bool_], least: int) -> Iterator[tuple[int, NDArray[np.bool_]]]:
    """``(j, column j)`` of a ``(points, rows)`` incidence matrix, once per distinct column
    with at least ``least`` points."""
    count = incident.sum(axis=0)
    seen: set[bytes] = set()
    for j in np.flatnonzero(count >= least):
        key = np.packbits(incident[:, j]).tobytes()
        if key not in seen:
            seen.add(key)
            yield int(j), incident[:, j]


def polish_vertices(
    points: NDArray[np.float64], normals: NDArray[np.float64], offsets: NDArray[np.float64], tol: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    r"""Vertices and facets of a full-dimensional polytope given as ``conv(points)`` and
    as $\{u : a_j^T u \le b_j\}$ (the same set up to ``tol``).

    The inequalities (some not facet-defining, some near copies of one another) are
    refitted: a row whose points (those within ``10 tol`` of it) span a hyperplane becomes
    the least-squares plane through them, rows with the same points are one facet, the
    other rows (lower-dimensional faces) are dropped. Points on the same facets, of rank
    ``k``, are one candidate (their mean: this merges the near copies that nearly parallel
    rows leave behind, and would also average a stray point in, were it within ``10 tol``
    of exactly the vertex's facets); a candidate is a vertex unless it lies, to ``10 tol``,
    in the hull of the other candidates on its facets.

    Returns
    -------
    vertices, facet_normals, facet_offsets
        ``(n, k)``, ``(f, k)`` unit outward normals and ``(f,)`` offsets.
    """
    facet_n, facet_b = _refit_facets(points, normals, offsets, tol)
    reps, active, apart = _vertex_candidates(points, facet_n, facet_b, tol)
    keep = _not_in_hull_of_neighbours(reps, active, apart, facet_n, tol)
    return distinct(reps[keep], 10 * tol), facet_n, facet_b


def _refit_facets(
    points: NDArray[np.float64], normals: NDArray[np.float64], offsets: NDArray[np.float64], tol: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The facets of [`polish_vertices()`][mjtvm.polytopes.hull.polish_vertices]: the least-squares plane through the points of each
    row whose points span a hyperplane (one per distinct point set), outward as the row."""
    k = points.shape[1]
    incident = incidence(points, normals, offsets, 10 * tol)
    fit_n, fit_b = [], []
    for j, on in _distinct_columns(incident, k):
        q = points[on]
        mean = q.mean(axis=0)
        _, sv, vt = np.linalg.svd(q - mean, full_matrices=False)
        flat = 10 * tol * np.sqrt(len(q))
        if sv[k - 2] <= flat or (len(sv) == k and sv[k - 1] > flat):
            continue  # a lower-dimensional face, or points off any plane
        a = vt[k - 1] * np.sign(vt[k - 1] @ normals[j])
        fit_n.append(a)
        fit_b.append(float(a @ mean))
    return np.array(fit_n).reshape(-1, k), np.array(fit_b)


def _vertex_candidates(
    points: NDArray[np.float64], facet_n: NDArray[np.float64], facet_b: NDArray[np.float64], tol: float
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_]]:
    """The points on facets of rank k, merged by their facet sets (the mean of each group):
    ``(c, k)`` candidates, ``(c, f)`` their facets, ``(c,)`` whether those are well apart."""
    k = points.shape[1]
    on_facet = incidence(points, facet_n, facet_b, 10 * tol)
    # The smallest singular value of each point's facet normals, from the Gram matrices
    # (accurate to ~1e-7 absolute: an SVD settles the rank where it is below 1e-4).
    gram = (on_facet.astype(float) @ np.einsum("fi,fj->fij", facet_n, facet_n).reshape(-1, k * k)).reshape(
        -1, k, k
    )
    least_sv = np.sqrt(np.clip(np.linalg.eigvalsh(gram)[:, 0], 0.0, None))
    for i in np.flatnonzero(least_sv <= 1e-4):
        act = on_facet[i]
        least_sv[i] = (
            np.linalg.svd(facet_n[act], compute_uv=False)[k - 1] if np.count_nonzero(act) >= k else 0.0
        )
    is_vertex = least_sv > 1e-8  # facets of rank k through it
    # Points on the same facets are one candidate (their mean): the near copies of a vertex
    # that nearly parallel rows leave behind.
    cand, sv = points[is_vertex], least_sv[is_vertex]
    _, first, group = np.unique(
        np.packbits(on_facet[is_vertex], axis=1), axis=0, return_index=True, return_inverse=True
    )
    group = group.reshape(-1)
    reps = np.zeros((len(first), k))
    np.add.at(reps, group, cand)
    reps /= np.bincount(group, minlength=len(first))[:, None]
    return reps, on_facet[is_vertex][first], sv[first] > WELL_APART


def _not_in_hull_of_neighbours(
    reps: NDArray[np.float64],
    active: NDArray[np.bool_],
    apart: NDArray[np.bool_],
    facet_n: NDArray[np.float64],
    tol: float,
) -> NDArray[np.bool_]:
    """Which candidates are vertices: those not within ``10 tol`` of the hull of their neighbours.

    Facets meeting at a tiny angle leave points within tolerance of both far from their
    intersection: such a point lies (to 10 tol) in the hull of the other points on its
    facets, a vertex does not (non-negative least squares on [Q - p; 1] mu = [0; 1]).
    Where no two facets through a point are nearly parallel (``apart``), its facets pin it down.
    """
    k = reps.shape[1]
    keep = np.ones(len(reps), dtype=bool)
    for i in _uncertified(reps, active, ~apart, facet_n, tol):
        shared = np.count_nonzero(active[:, active[i]], axis=1)
        shared[i] = 0
        # Its neighbours on a common 2-face (k - 2 shared facets; edges among them): where
        # nearly parallel facets meet others, a stray point sits on such faces.
        # Only candidates still kept: a point dropped for lying in the hull of others must
        # not in turn make one of those others look redundant (both would be lost).
        near = np.flatnonzero((shared >= max(k - 2, 1)) & keep)
        if not len(near):
            continue
        # Cheap certificate first: a direction along which the point beats them all by
        # more than 20 tol keeps the NNLS residual above 10 tol (a vertex, no NNLS). The sum
        # of its facets' normals: every point of the polytope is at most level with it there.
        d = facet_n[active[i]].sum(axis=0)
        norm = float(np.linalg.norm(d))
        if norm > 0.0 and (d @ reps[i] - np.max(reps[near] @ d)) > 20 * tol * norm:
            continue
        if _hull_residual(reps[i], reps[near], 1.0) <= 10 * tol:
            keep[i] = False
    return keep


def _uncertified(
    reps: NDArray[np.float64],
    active: NDArray[np.bool_],
    check: NDArray[np.bool_],
    facet_n: NDArray[np.float64],
    tol: float,
) -> NDArray[np.int64]:
    """The candidates among ``check`` that `_not_in_hull_of_neighbours()` must look at one by one.

    Its cheap certificate, for all candidates at once and against all their neighbours (a
    superset of the kept ones the loop compares with, so passing here means passing there),
    with a margin of 1e-6 of its own for the round-off of another order of summation; so are
    the candidates without neighbours. Those left keep their order and meet the same kept
    neighbours in the loop: the result is the loop's alone (0.1 s -> 0.03 s on Case 2's 1,280).
    """
    idx = np.flatnonzero(check)
    if not len(idx):
        return idx
    on = sp.csr_matrix(active, dtype=np.int32)
    # Pairs (candidate, neighbour) sharing at least k - 2 facets (a sparse product: a few
    # facets per candidate), the candidate itself left out.
    shared = (on[idx] @ on.T).tocoo()
    pick = (shared.data >= max(reps.shape[1] - 2, 1)) & (idx[shared.row] != shared.col)
    row, col = shared.row[pick], shared.col[pick]
    d = on[idx] @ facet_n  # the sum of each candidate's facet normals
    level = np.full(len(idx), -np.inf)
    np.maximum.at(level, row, np.einsum("ij,ij->i", d[row], reps[col]))
    margin = np.einsum("ij,ij->i", d, reps[idx]) - level
    norm = np.linalg.norm(d, axis=1)
    sure = (norm > 0.0) & (margin > 20 * tol * norm * (1.0 + 1e-6) + 1e-300)
    return idx[~sure & np.isfinite(level)]


def vertex_mask(
    local: NDArray[np.float64], simp: NDArray[np.int64], candidates: NDArray[np.int64], tol: float
) -> NDArray[np.bool_]:
    r"""Which ``candidates`` (indices of ``local``) are vertices of the hull triangulated by ``simp``.

    A point inside a face of dimension >= 1 lies in the convex hull of its neighbours
    in the triangulation (its star covers a neighbourhood of it in the face), a vertex
    does not; the distance is measured by non-negative least squares on
    ``[Q - p; 1] mu = [0; 1]``, ``mu >= 0``, and distances up to ``10 tol`` are round-off.
    """
    scale = float(np.max(np.abs(local)))
    owner = simp.ravel()
    order = np.argsort(owner, kind="stable")
    starts = np.searchsorted(owner[order], np.arange(len(local) + 1))
    facet = np.repeat(np.arange(len(simp)), simp.shape[1])[order]
    mask = np.zeros(len(candidates), dtype=bool)
    for n, i in enumerate(candidates):
        near = np.setdiff1d(simp[facet[starts[i] : starts[i + 1]]], [i])
        mask[n] = len(near) == 0 or _hull_residual(local[i], local[near], scale) > 10 * tol / scale
    return mask


def cone_facets(gens: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(h, d)`` unit rows ``a`` with cone(gens) = {f : a f >= 0}, for ``(d, m)`` generators
    (cddlib, V- to H-form; a lower-dimensional cone's equalities come as rows too)."""
    import cdd

    rays = np.column_stack([np.zeros(gens.shape[1]), gens.T]).tolist()
    mat = cdd.matrix_from_array(rays, rep_type=cdd.RepType.GENERATOR)
    ineq = cdd.copy_inequalities(cdd.polyhedron_from_matrix(mat))
    rows = np.array(ineq.array, dtype=float).reshape(-1, gens.shape[0] + 1)[:, 1:]
    norm = np.linalg.norm(rows, axis=1, keepdims=True)
    return rows[norm[:, 0] > 0.0] / norm[norm[:, 0] > 0.0]


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
