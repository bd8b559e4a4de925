r"""Convex hulls of point sets that may span a subspace: the geometry under Problem 1.

* :class:`PolarHull`, :func:`polar_vertices`: vertex enumeration of a bounded polytope given by
  inequalities (Qhull on the polar points); :func:`polish_vertices`: its facets and exact vertices;
* :func:`triangulate`: simplicial facets of a full-dimensional point set (Qhull, joggled);
* :func:`vertex_mask`, :func:`distinct`, :func:`span`: vertices of a triangulated hull,
  clusters of round-off, linear hulls;
* :func:`reduce_points`: linear hull and vertices of the hull of points and the origin
  (the last step of the cdd baseline); :func:`cone_facets`: a cone's facets (cddlib);
* the measures (volumes, Hausdorff distance) are in :mod:`~mjtvm.polytopes.volume`.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError, cKDTree

from ..errors import SolverError
from .budget import Budget
from .lattice import FaceLattice

__all__ = [
    "CDD_REL_TOL",
    "FLAT",
    "ZERO_TOL",
    "PolarHull",
    "cone_facets",
    "distinct",
    "incidence",
    "polar_vertices",
    "polish_vertices",
    "reduce_points",
    "span",
    "triangulate",
    "vertex_mask",
]

ZERO_TOL = 1e-9  #: an S_ov within this distance of the origin (scaled units) is {0}
CDD_REL_TOL = 1e-9  #: round-off of float cddlib relative to the extent
FLAT = 1e-11  #: Hadamard ratio below which a simplex of the polar hull is flat
JOGGLE = 1e-9  #: relative perturbation of points before Qhull (polar points, a facet's points)
WELL_APART = 0.05  #: facets through a point whose normals' smallest singular value exceeds this


def _joggled(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """``points`` moved by a seeded uniform perturbation of :data:`JOGGLE` x their extent."""
    rng = np.random.default_rng(0)
    return points + rng.uniform(-1.0, 1.0, points.shape) * JOGGLE * np.max(np.abs(points))


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


class PolarHull:
    r"""Vertices of the bounded polytope :math:`O = \{u : a_j^T u \le b_j\}` around an
    interior point, as rows are added (the cutting planes of Problem 1).

    Vertex enumeration by duality: with ``c`` = ``center`` inside O, the polar points
    :math:`y_j = a_j / (b_j - a_j^T c)` have a hull whose facets :math:`\{y : w^T y = 1\}`
    are O's vertices :math:`c + w`. Qhull on joggled points (each moved by :data:`JOGGLE`
    x its size, seeded, so that the many coplanar polar points of a degenerate O never stop
    it) gives the simplices, and keeps its hull between calls: added rows are added points
    ("QJ" on all points from scratch where that fails). Each simplex's ``k`` inequalities
    are then solved exactly on the unperturbed rows (flat simplices, see :data:`FLAT`,
    skipped); a solution that breaks some inequality (an ill-conditioned corner) is pulled
    back along the ray from ``c`` onto O's boundary. Every vertex of O is found: its polar
    facet is covered by the triangulation's simplices, at least one of them
    full-dimensional in it.

    Parameters
    ----------
    normals, offsets
        ``(m, k)`` and ``(m,)``: the inequalities, ``m >= k + 1``, O bounded.
    center
        ``(k,)`` a point with :math:`a_j^T c < b_j` for all ``j``.
    tol
        Round-off of the inequalities (absolute, in the units of ``u``).
    """

    def __init__(
        self,
        normals: NDArray[np.float64],
        offsets: NDArray[np.float64],
        center: NDArray[np.float64],
        tol: float,
    ) -> None:
        self.center, self.tol = np.asarray(center, dtype=float), tol
        self.normals = np.zeros((0, len(self.center)))
        self.offsets = np.zeros(0)
        self._polar = np.zeros((0, len(self.center)))
        self._joggled = np.zeros((0, len(self.center)))
        self._rng = np.random.default_rng(0)
        self._hull: ConvexHull | None = None
        self._added = 0  # rows already in self._hull
        self._count = 0  # simplices of the last hull (the budget's estimate of the next)
        self._seen = np.zeros(0, dtype=np.int64)  # keys of the simplices solved last time
        self.add(normals, offsets)

    def add(self, normals: NDArray[np.float64], offsets: NDArray[np.float64]) -> None:
        r"""Add the rows :math:`a^T u \le b` (``(m, k)``, ``(m,)``; ``c`` strictly inside)."""
        normals, offsets = np.atleast_2d(normals), np.atleast_1d(offsets)
        polar = normals / (offsets - normals @ self.center)[:, None]
        size = np.max(np.abs(polar), axis=1, keepdims=True)
        self.normals = np.vstack([self.normals, normals])
        self.offsets = np.concatenate([self.offsets, offsets])
        self._polar = np.vstack([self._polar, polar])
        self._joggled = np.vstack(
            [self._joggled, polar + self._rng.uniform(-1.0, 1.0, polar.shape) * JOGGLE * size]
        )

    def _simplices(self, budget: Budget | None = None) -> NDArray[np.int64]:
        if budget is not None:  # Qhull's hull grows with its simplices: about as many again
            budget.reserve(self._count * 8.0 * (4 * len(self.center) + 8), "the polar hull (Qhull)")
        # Our own joggle spares Qhull its "QJ" retries and lets it add points to its hull;
        # "QJ" from scratch is the fallback. Only the triangulation comes from the joggle.
        try:
            if self._hull is None:
                self._hull = ConvexHull(self._joggled, incremental=True)
            elif self._added < len(self._joggled):
                self._hull.add_points(self._joggled[self._added :])
            self._added = len(self._joggled)
            simp = np.asarray(self._hull.simplices)
            self._count = len(simp)
            return simp
        except QhullError:
            self._hull, self._added = None, 0
        try:
            return np.asarray(ConvexHull(self._polar, qhull_options="QJ").simplices)
        except QhullError as e:
            raise SolverError("qhull", str(e).splitlines()[0] if str(e) else "QhullError") from e

    def vertices(self, budget: Budget | None = None) -> NDArray[np.float64]:
        """``(n, k)`` the vertices of O, clusters closer than ``10 tol`` merged (near-parallel
        rows can leave spurious points on O's boundary: :func:`polish_vertices` sorts them out)."""
        return self._solve(self._simplices(budget), budget)

    def new_vertices(self, budget: Budget | None = None) -> NDArray[np.float64]:
        """The vertices of O as :meth:`vertices`, less those of simplices of Qhull's hull that
        an earlier call solved already (the vertices that survived the rows added since)."""
        simp = self._simplices(budget)
        k, base = simp.shape[1], 2 ** (62 // simp.shape[1])
        if len(self._polar) <= base:  # sorted indices as one integer in that base
            keys = np.sort(simp, axis=1) @ (base ** np.arange(k, dtype=np.int64))
            simp = simp[~np.isin(keys, self._seen, assume_unique=True)]
            # A simplex that left the hull never comes back (added points only grow it):
            # the last call's keys are all there is to compare with.
            self._seen = keys
        return self._solve(simp, budget)

    @property
    def size(self) -> int:
        """Simplices of the last hull (what a vertex enumeration or a face lattice now costs)."""
        return self._count

    def predicted_size(self) -> int:
        """Simplices the hull will have with the rows added since it was last made: as the
        rows' number to the power 1.5 (the Allegro grasp's 6-D TVMS: 230, 654, 1894 rows had
        8016, 41168, 183322 simplices)."""
        if self._added == 0:
            return max(self._count, 1)
        return max(int(self._count * (len(self.offsets) / self._added) ** 1.5), 1)

    def joggle_size(self) -> float:
        """The largest distance between a polar point and its joggled copy (``max_j |y'_j - y_j|``)."""
        return float(np.max(np.linalg.norm(self._joggled - self._polar, axis=1), initial=0.0))

    def lattice(self, budget: Budget | None = None) -> FaceLattice:
        r"""The face lattice of the joggled polytope :math:`O'` that Qhull's simplices describe
        exactly (:class:`~mjtvm.polytopes.lattice.FaceLattice`: O's volume, uniform points).

        :math:`O' = \{u : y'^T_j (u - c) \le 1\}` with the joggled polar points :math:`y'_j`
        is simple, and its vertices :math:`c + w`, :math:`Y'_S w = 1`, belong to every
        simplex, flat ones too: on O's own rows a flat simplex has no vertex, and dropping it
        loses the flags through it (the 4-D cross-polytope came out 0.50 instead of 2/3). The
        volumes of O and O' differ by the joggle's order (:data:`JOGGLE`, relative)."""
        simp = self._simplices(budget)
        k = len(self.center)
        if budget is not None:  # the lattice's subsets, faces and edges: about 8 (k + 2) 2^k bytes a simplex
            budget.reserve(8.0 * len(simp) * (k + 2) * 2**k, "the face lattice of the outer polytope")
        y = self._joggled
        w = np.linalg.solve(y[simp], np.ones((len(simp), k, 1)))[..., 0]
        return FaceLattice(y, 1.0 + y @ self.center, self.center, self.center + w, simp, budget)

    def _corners(
        self, simp: NDArray[np.int64], budget: Budget | None
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """The vertices of the simplices ``simp``, in blocks that fit the budget (a block's
        ``(n, m)`` distances to the rows are the largest array: never all of them at once)."""
        k, m = len(self.center), len(self.offsets)
        per_row = 8.0 * (3 * k * k + 2 * m + 4 * k)
        step = budget.chunk_rows(per_row) if budget is not None else max(1, int(2**27 // per_row))
        out_u, out_s = [], []
        for lo in range(0, len(simp), step):
            if budget is not None:
                budget.reserve(per_row * min(step, len(simp) - lo), "the vertices of the outer polytope")
            u, keep = self._solve_block(simp[lo : lo + step])
            out_u.append(u)
            out_s.append(simp[lo : lo + step][keep])
        if not out_u:
            return np.zeros((0, k)), np.zeros((0, k), dtype=np.int64)
        return np.vstack(out_u), np.vstack(out_s)

    def _solve_block(self, simp: NDArray[np.int64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        k, normals, offsets, center = len(self.center), self.normals, self.offsets, self.center
        rows = self._polar[simp]
        # Flat simplices (rows dependent up to the joggle) fill lower-dimensional faces of the
        # polar hull and stand for no vertex: their |det| / product of row norms is <= 1e-12,
        # that of the others >= 1e-9 on the TVMSs met (a Hadamard ratio, cheaper than SVDs).
        hadamard = np.abs(np.linalg.det(rows)) / np.prod(np.linalg.norm(rows, axis=2), axis=1)
        keep = hadamard > FLAT
        w = np.linalg.solve(rows[keep], np.ones((int(np.count_nonzero(keep)), k, 1)))[..., 0]
        finite = np.all(np.isfinite(w), axis=1)
        keep[np.flatnonzero(keep)[~finite]] = False
        u = center + w[finite]
        # Where rows are nearly dependent (facets at tiny angles) a vertex is ill-conditioned and
        # the joggled simplex's solution may break a neighbouring row (by more than tol): pull
        # it back along the ray from the centre onto O's boundary rather than lose that corner.
        # (Before merging copies: a broken copy must not stand in for a good one.)
        slack = offsets - normals @ center
        reach = np.ascontiguousarray(u - center) @ normals.T
        broken = np.flatnonzero(np.any(reach > slack + self.tol, axis=1))
        if len(broken):
            over = reach[broken] > slack
            ratio = np.where(over, slack / np.where(over, reach[broken], 1.0), 1.0)
            u[broken] = center + (u[broken] - center) * np.min(ratio, axis=1)[:, None]
        return u, keep

    def _solve(self, simp: NDArray[np.int64], budget: Budget | None = None) -> NDArray[np.float64]:
        u, _ = self._corners(simp, budget)
        # Rounding shrinks the many copies (one per simplex) cheaply; distinct() merges the rest.
        u = u[np.unique(np.round(u / (10 * self.tol)), axis=0, return_index=True)[1]]
        return distinct(u, 10 * self.tol)


def polar_vertices(
    normals: NDArray[np.float64], offsets: NDArray[np.float64], center: NDArray[np.float64], tol: float
) -> NDArray[np.float64]:
    r"""The vertices of :math:`\{u : a_j^T u \le b_j\}` at once (:class:`PolarHull`)."""
    return PolarHull(normals, offsets, center, tol).vertices()


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
    as :math:`\{u : a_j^T u \le b_j\}` (the same set up to ``tol``).

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
    """The facets of :func:`polish_vertices`: the least-squares plane through the points of each
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
    for i in np.flatnonzero(~apart):
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
