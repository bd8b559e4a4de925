r"""Vertex enumeration of a bounded polytope given by inequalities, by its polar hull.

[`PolarHull`][mjtvm.polytopes.polar.PolarHull] keeps Qhull's hull of the polar points as cutting planes are added
(Problem 1); [`polar_vertices()`][mjtvm.polytopes.polar.polar_vertices] enumerates at once. The facets and exact vertices
([`polish_vertices()`][mjtvm.polytopes.hull.polish_vertices]) and the point-set geometry are in
[`hull`][mjtvm.polytopes.hull].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError

from mjtvm.errors import SolverError
from mjtvm.polytopes.budget import Budget
from mjtvm.polytopes.hull import JOGGLE, distinct
from mjtvm.polytopes.lattice import FaceLattice

__all__ = ["FLAT", "PolarHull", "polar_vertices"]

FLAT = 1e-11  #: Hadamard ratio below which a simplex of the polar hull is flat


class PolarHull:
    r"""Vertices of the bounded polytope $O = \{u : a_j^T u \le b_j\}$ around an
    interior point, as rows are added (the cutting planes of Problem 1).

    Vertex enumeration by duality: with ``c`` = ``center`` inside O, the polar points
    $y_j = a_j / (b_j - a_j^T c)$ have a hull whose facets $\{y : w^T y = 1\}$
    are O's vertices $c + w$. Qhull on joggled points (each moved by [`JOGGLE`][mjtvm.polytopes.polar.JOGGLE]
    x its size, seeded, so that the many coplanar polar points of a degenerate O never stop
    it) gives the simplices, and keeps its hull between calls: added rows are added points
    (a hull from scratch where Qhull's incremental mode fails, then on points joggled anew).
    Each simplex's ``k`` inequalities are then solved exactly on the unperturbed rows (flat
    simplices, see [`FLAT`][mjtvm.polytopes.polar.FLAT],
    skipped); a solution that breaks some inequality (an ill-conditioned corner) is pulled
    back along the ray from ``c`` onto O's boundary. Every vertex of O is found: its polar
    facet is covered by the triangulation's simplices, at least one of them
    full-dimensional in it.

    Parameters
    ----------
    normals, offsets
        ``(m, k)`` and ``(m,)``: the inequalities, ``m >= k + 1``, O bounded.
    center
        ``(k,)`` a point with $a_j^T c < b_j$ for all ``j``.
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
        r"""Add the rows $a^T u \le b$ (``(m, k)``, ``(m,)``; ``c`` strictly inside)."""
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
        # Our own joggle spares Qhull its "QJ" retries and lets it add points to its hull.
        # Qhull's incremental mode can still stop on a precision error (scipy issue #4974:
        # facets with the same vertex set after a "dupridge"): the hull is then made again
        # from scratch on the same points, and where that fails too, on all points joggled
        # anew, 10 and 100 times as much (`_rejoggle()`), never by Qhull's own "QJ",
        # whose joggled points the face lattice (`lattice()`) would not know.
        try:
            if self._hull is None:
                self._hull = ConvexHull(self._joggled, incremental=True)
            elif self._added < len(self._joggled):
                self._hull.add_points(self._joggled[self._added :])
            self._added = len(self._joggled)
            return self._keep(np.asarray(self._hull.simplices))
        except QhullError:
            self._hull, self._added = None, 0  # the next rows start a new incremental hull
        error: QhullError | None = None
        for factor in (0.0, 10.0, 100.0):
            if factor:
                self._rejoggle(factor)
            try:
                return self._keep(np.asarray(ConvexHull(self._joggled).simplices))
            except QhullError as e:
                error = e
        text = str(error).splitlines()[0] if str(error) else "QhullError"
        raise SolverError("qhull", text) from error

    def _keep(self, simp: NDArray[np.int64]) -> NDArray[np.int64]:
        self._count = len(simp)
        return simp

    def _rejoggle(self, factor: float) -> None:
        """All polar points joggled anew by ``factor`` x [`JOGGLE`][mjtvm.polytopes.polar.JOGGLE] x their size (seeded)."""
        size = np.max(np.abs(self._polar), axis=1, keepdims=True)
        noise = self._rng.uniform(-1.0, 1.0, self._polar.shape)
        self._joggled = self._polar + noise * factor * JOGGLE * size

    def vertices(self, budget: Budget | None = None) -> NDArray[np.float64]:
        """``(n, k)`` the vertices of O, clusters closer than ``10 tol`` merged (near-parallel
        rows can leave spurious points on O's boundary: `polish_vertices()` sorts them out)."""
        return self._solve(self._simplices(budget), budget)

    def new_vertices(self, budget: Budget | None = None) -> NDArray[np.float64]:
        """The vertices of O as `vertices()`, less those of simplices of Qhull's hull that
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
        r"""The face lattice of the joggled polytope $O'$ that Qhull's simplices describe
        exactly ([`FaceLattice`][mjtvm.polytopes.lattice.FaceLattice]: O's volume, uniform points).

        $O' = \{u : y'^T_j (u - c) \le 1\}$ with the joggled polar points $y'_j$
        is simple, and its vertices $c + w$, $Y'_S w = 1$, belong to every
        simplex, flat ones too: on O's own rows a flat simplex has no vertex, and dropping it
        loses the flags through it (the 4-D cross-polytope came out 0.50 instead of 2/3). The
        volumes of O and O' differ by the joggle's order ([`JOGGLE`][mjtvm.polytopes.polar.JOGGLE], relative)."""
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
    r"""The vertices of $\{u : a_j^T u \le b_j\}$ at once ([`PolarHull`][mjtvm.polytopes.polar.PolarHull])."""
    return PolarHull(normals, offsets, center, tol).vertices()
