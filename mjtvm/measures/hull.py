r"""A growing point set's convex hull for the epsilons' expanding polytope
([`epsilon_linf()`][mjtvm.measures.wrenches.epsilon_linf]): points inserted one by one by
beneath-beyond on a simplicial hull, checked against Qhull before an answer is read.

Rebuilding the hull with Qhull after every round is what cost: the support points of five
fingertip pyramids in 6-D reach ~3,000 facets by 60 points, 8 ms a rebuild, 25 rebuilds a
grasp. Inserting a point touches only the facets it sees: a few numpy calls, or in a batch a
compiled kernel's (`mjtvm.measures.hull_jit`). Before an answer is read, `GrowingHull.verify()`
checks the inserted facets by the test Qhull's own unmerged hull must pass here (every point
inside every facet's hyperplane and each facet through its vertices within round-off, every
facet closed up by its neighbours), or rebuilds the hull of every point with Qhull (`hull_of()`).

Qhull's own incremental mode is not used: on nearly degenerate input (facets wider than its
precision allows, ``qh_ERRwide``) ``add_points`` ends the process with exit code 7 instead of
raising, which a batch over thousands of grasps meets (a Shadow grasp of ``mjtvm rank``'s mesh
dataset did). Here a degenerate insertion raises `_Degenerate` and the caller rebuilds with Qhull.
"""

from __future__ import annotations

from types import ModuleType

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError

from mjtvm.errors import SolverError

__all__ = ["GrowingHull", "hull_of"]


def _kernels(compiled: bool | None) -> ModuleType | None:
    """`mjtvm.measures.hull_jit` (imported on first use: numba's import and the cached kernels'
    load, ~0.5 s, on the batch paths only), or ``None`` for the numpy insertion: ``compiled``
    ``False``, or ``None`` where numba does not import. ``None`` never depends on what the
    process did before, so that a grasp's epsilons are the same bits in any process (serial,
    pool, Dask worker): the two insertions agree only to round-off."""
    if compiled is False:
        return None
    try:
        from mjtvm.measures import hull_jit
    except ImportError:
        return None
    return hull_jit


# Qhull's round-off allowance for the unmerged hull's check (`hull_of()`), relative to the
# largest point: the facets of a hull built without merging must hold every point within it.
_UNMERGED_REL_TOL = 1e-10
# A point sees a facet when it lies beyond the facet's hyperplane by more than this, relative
# to the largest point; a point within it of a hyperplane leaves the facet in place.
_VISIBLE_REL_TOL = 1e-12
# A new facet's normal, found with unit length along a nearby normal, longer than 1 / this:
# the facet is nearly flat (or turned away from that normal) and the insertion `_Degenerate`.
_FLAT_REL_TOL = 1e-6
# Facet rows held at least: the five-finger Shadow grasps' L-infinity hulls reach 2,000-8,000.
_MIN_ROWS = 4096


def _dropping_one(n: int) -> NDArray[np.int64]:
    """``(n, n - 1)`` row i: the indices ``0 .. n - 1`` without i."""
    return np.array([[j for j in range(n) if j != i] for i in range(n)], dtype=np.int64)


def _keys(rows: NDArray[np.int64], base: int) -> NDArray[np.int64]:
    """``(r,)`` one integer per row of point indices below ``base``, equal exactly when the rows
    are: the rows as digits in ``base`` (one argsort instead of a lexsort, 2x faster), or the
    rows' lexicographic rank where the digits would not fit in 63 bits."""
    if rows.shape[1] * np.log2(max(base, 2)) >= 62:
        _, rank = np.unique(rows, axis=0, return_inverse=True)
        return rank.reshape(-1).astype(np.int64)
    key = np.zeros(len(rows), dtype=np.int64)
    for col in rows.T:
        key = key * base + col
    return key


class _Degenerate(Exception):
    """An insertion met a nearly flat facet or an unmatched ridge: rebuild with Qhull."""


def _unmerged_hull(points: NDArray[np.float64]) -> ConvexHull | None:
    """Qhull's hull without facet merging ("Q0"), or ``None`` when Qhull refuses it or its
    facets fail the check.

    Merging (Qhull's default "Qx" in 6-D) is what costs on the friction pyramids' wrenches:
    each contact's edges lie on one ellipse, so many facets are nearly coplanar; without it
    the 48 wrenches of a three-finger grasp take 4 ms instead of 13 ms. Without merging
    Qhull may keep a facet that is not convex within round-off, so the result is accepted
    only if every facet's hyperplane holds all the points (within `_UNMERGED_REL_TOL` x the
    largest point: a supporting hyperplane through D input points is a facet of the hull)
    and every facet has its D neighbours (the facets close up around the origin: none is
    missing)."""
    try:
        hull = ConvexHull(points, qhull_options="Q0")
    except QhullError:
        return None
    eq = hull.equations
    size = float(np.max(np.abs(points))) if points.size else 0.0
    # Row by row (einsum, not BLAS): OpenBLAS would run this product of a few thousand
    # facets on two threads, doubling the CPU time for no gain in wall time.
    slack = np.einsum("fd,nd->fn", eq[:, :-1], points) + eq[:, -1:]
    if not (
        np.all(np.isfinite(eq)) and float(slack.max(initial=0.0)) <= _UNMERGED_REL_TOL * max(size, 1e-300)
    ):
        return None
    if np.any(hull.neighbors < 0):
        return None
    return hull


def hull_of(points: NDArray[np.float64]) -> ConvexHull:
    """Qhull's hull: unmerged and checked (`_unmerged_hull()`) where that holds, else Qhull's
    default; where that gives up on nearly degenerate input (many wrenches of the
    pyramids' edges lie on common facets), joggled by Qhull's "QJ" (about 1e-11 relative,
    more on its retries). The facets' smallest distance from the origin, all that the
    epsilons read, agrees between the unmerged and the merged hull to round-off (1e-15
    relative on the example dataset)."""
    fast = _unmerged_hull(points)
    if fast is not None:
        return fast
    try:
        return ConvexHull(points)
    except QhullError:
        pass
    try:
        return ConvexHull(points, qhull_options="QJ")
    except QhullError as e:
        raise SolverError("qhull", " ".join(str(e).split())[:200] or "QhullError") from e


class GrowingHull:
    """The hull of a growing point set in ``D >= 2`` dimensions.

    Facets are simplices, each held as its point indices, the facet across from each vertex
    (Qhull's convention: ``neighbors[f, j]`` shares every vertex of ``f`` but its j-th) and
    its hyperplane ``[a, b]`` (`equations`), ``a.x + b <= 0`` inside, ``|a| = 1``.

    Parameters
    ----------
    points
        ``(n, D)`` the first points, full-dimensional, ``D >= 3``; their hull is Qhull's
        (`hull_of()`).
    compiled
        Insert in the compiled kernels (`mjtvm.measures.hull_jit`, ``True``; a
        [`SolverError`][mjtvm.errors.SolverError] without numba) or with numpy (``False``);
        ``None``: compiled where numba imports, else numpy. Both give the same facets to
        round-off, checked alike by `verify()`.
    """

    def __init__(self, points: NDArray[np.float64], *, compiled: bool | None = None) -> None:
        first = np.array(points, dtype=float)
        self._pts = np.zeros((2 * len(first) + 64, first.shape[1]))
        self._pts[: len(first)] = first
        self._npts = len(first)
        self._size = max(float(np.max(np.abs(first))), 1e-300)
        self._kernels = _kernels(compiled)
        if compiled and self._kernels is None:
            raise SolverError("numba", "the compiled hull kernels need numba, which does not import")
        self._rebuild()
        self._inside = first.mean(axis=0)  # interior of the first hull: inside every later one

    @property
    def points(self) -> NDArray[np.float64]:
        """``(n, D)`` every point so far (a view)."""
        return self._pts[: self._npts]

    @property
    def compiled(self) -> bool:
        """Whether insertions run in the compiled kernels (`mjtvm.measures.hull_jit`)."""
        return self._kernels is not None

    def _rebuild(self) -> None:
        hull = hull_of(self.points)
        self._set(np.array(hull.simplices), np.array(hull.neighbors), np.array(hull.equations))
        self._qhull = True  # the facets are Qhull's own: checked

    def _set(self, simp: NDArray[np.int64], nbr: NDArray[np.int64], eq: NDArray[np.float64]) -> None:
        """Hold these facets, in arrays with room to grow: a facet keeps its row (its id)
        until `_compact()`; a removed one is marked dead (distance inf)."""
        n, d = simp.shape
        cap = max(2 * n + 64, _MIN_ROWS)
        self._simp = np.empty((cap, d), dtype=np.int64)  # rows past _n are never read
        self._nbr = np.empty((cap, d), dtype=np.int64)
        self._eq = np.empty((cap, d + 1))
        self._alive = np.zeros(cap, dtype=bool)
        self._simp[:n], self._nbr[:n], self._eq[:n], self._alive[:n] = simp, nbr, eq, True
        self._n = n  # rows in use, dead ones included

    def _compact(self) -> None:
        alive = self._alive[: self._n]
        renumber = np.cumsum(alive) - 1
        self._set(
            self._simp[: self._n][alive], renumber[self._nbr[: self._n][alive]], self._eq[: self._n][alive]
        )

    def _grow(self, rows: int) -> None:
        cap = 2 * (self._n + rows)
        for name in ("_simp", "_nbr", "_eq", "_alive"):
            old = getattr(self, name)
            new = np.zeros((cap, *old.shape[1:]), dtype=old.dtype)
            new[: self._n] = old[: self._n]
            setattr(self, name, new)

    @property
    def equations(self) -> NDArray[np.float64]:
        """``(f, D + 1)`` the facets' hyperplanes (rows of removed facets included: their
        `distances()` are inf)."""
        return self._eq[: self._n]

    def distances(self) -> NDArray[np.float64]:
        """``(f,)`` each facet's signed distance from the origin (positive: origin inside),
        inf for a removed facet's row."""
        return np.where(self._alive[: self._n], -self._eq[: self._n, -1], np.inf)

    @property
    def verified(self) -> bool:
        """Whether the facets are checked to be the hull of every point so far (`verify()`)."""
        return self._qhull

    def verify(self) -> None:
        """Make the facets the checked hull of every point so far.

        The inserted facets pass when they pass the test Qhull's unmerged hull passes
        (`_unmerged_hull()`) and hold their own vertices: every facet's hyperplane holds
        every point and passes through its D vertices within `_UNMERGED_REL_TOL` x the
        largest point, and every facet has its D neighbours, each naming it back. Then each
        facet lies in a supporting hyperplane of the hull (its distance is at least the
        hull's inradius about the origin) and the closed surface the simplices form lies on
        the hull's boundary, so the ray from the origin along the nearest hull facet's
        normal meets a simplex at most the inradius away, whose hyperplane is at most that
        far (the smallest distance is the inradius, within the tolerance). Otherwise the
        hull is Qhull's (`hull_of()`), rebuilt from every point. Both the numpy and the
        compiled insertion (`mjtvm.measures.hull_jit`) are checked so."""
        if self._qhull:
            return
        if self._kernels is not None:
            if self._kernels.closed_and_holding(
                self._pts,
                self._npts,
                self._simp,
                self._nbr,
                self._eq,
                self._alive,
                self._n,
                _UNMERGED_REL_TOL * self._size,
            ):
                self._qhull = True
            else:
                self._rebuild()
            return
        n = self._n
        alive = self._alive[:n]
        eq, nbr = self._eq[:n][alive], self._nbr[:n][alive]
        ids = np.flatnonzero(alive)
        slack = np.einsum("fd,nd->fn", eq[:, :-1], self.points) + eq[:, -1:]
        on = np.einsum("fd,fkd->fk", eq[:, :-1], self.points[self._simp[:n][alive]]) + eq[:, -1:]
        named_back = np.any(self._nbr[nbr] == ids[:, None, None], axis=2)
        if (
            np.all(np.isfinite(eq))
            and float(slack.max(initial=0.0)) <= _UNMERGED_REL_TOL * self._size
            and float(np.abs(on).max(initial=0.0)) <= _UNMERGED_REL_TOL * self._size
            and np.all(self._alive[nbr])
            and np.all(named_back)
        ):
            self._qhull = True
            return
        self._rebuild()

    def add(self, new: NDArray[np.float64]) -> None:
        """Insert the rows of ``new`` one by one; rebuild with Qhull when an insertion is
        `_Degenerate`."""
        for p in np.asarray(new, dtype=float).reshape(-1, self._pts.shape[1]):
            self._size = max(self._size, float(np.max(np.abs(p))))
            if self._kernels is not None:
                self._insert_compiled(p)
                continue
            self._append(p)
            try:
                self._insert(self._npts - 1)
            except _Degenerate:
                self._rebuild()

    def _append(self, p: NDArray[np.float64]) -> None:
        if self._npts == len(self._pts):
            self._pts = np.vstack([self._pts, np.zeros_like(self._pts)])
        self._pts[self._npts] = p
        self._npts += 1

    def _make_room(self) -> None:
        """After a kernel's ``FULL``: room for another point, or else for more facets (the
        dead rows dropped when they are the most, else the arrays doubled)."""
        if self._npts == len(self._pts):
            self._pts = np.vstack([self._pts, np.zeros_like(self._pts)])
        elif 2 * int(self._alive[: self._n].sum()) < self._n:
            self._compact()
        else:
            self._grow(self._n + 64)

    def _insert_compiled(self, p: NDArray[np.float64]) -> None:
        k = self._kernels
        assert k is not None
        while True:
            status, npts, nf = k.insert(
                self._pts, self._npts, p, self._simp, self._nbr, self._eq, self._alive, self._n,
                self._inside, self._size, _VISIBLE_REL_TOL, _FLAT_REL_TOL,
            )  # fmt: skip
            if status != k.FULL:
                break
            self._make_room()
        changed = nf != self._n
        self._npts, self._n = npts, nf
        if status == k.DEGENERATE:
            self._rebuild()
        elif changed:
            self._qhull = False

    def expand(
        self, wrenches: NDArray[np.float64], starts: NDArray[np.int64], tol: float, rounds: int
    ) -> tuple[float, int]:
        r"""The expanding polytope's rounds on the Minkowski sum of the sets conv(0, W_i),
        ``W_i`` the columns ``starts[i]:starts[i + 1]`` of ``(D, n)`` ``wrenches``: insert the
        support point along the nearest facet's normal ``u`` while it lies beyond that facet
        by more than ``tol`` and the facet's distance is more than ``tol`` below the smallest
        support value $h(u)$ seen, for at most ``rounds`` rounds, and leave the facets checked
        (`verify()`).

        Returns
        -------
        (upper, rounds)
            The smallest ``h(u)`` seen (``inf`` when none) and the rounds run (a
            `verify()` counts as one)."""
        k = self._kernels
        if k is None:
            raise SolverError("numba", "expand() needs the compiled hull kernels")
        w = np.ascontiguousarray(wrenches, dtype=float)
        upper, done = np.inf, 0
        while done < rounds:
            status, npts, nf, size, up, ran, inserted = k.expand(
                self._pts, self._npts, self._simp, self._nbr, self._eq, self._alive, self._n,
                w, starts, self._inside, self._size, tol, rounds - done, _VISIBLE_REL_TOL, _FLAT_REL_TOL,
            )  # fmt: skip
            self._npts, self._n, self._size = npts, nf, size
            upper, done = min(upper, up), done + ran
            if inserted:
                self._qhull = False
            if status == k.FULL:
                self._make_room()
            elif status == k.DEGENERATE:
                self._rebuild()
            elif status == k.CONVERGED:
                if self._qhull:
                    return upper, done
                self.verify()  # then one more look: a rebuilt hull may need more rounds
                done += 1
        self.verify()
        return upper, done

    def _insert(self, idx: int) -> None:
        """Beneath-beyond: replace the facets point ``idx`` sees by the cone from it over
        their horizon ridges."""
        d = self.points.shape[1]
        if d < 3:
            raise _Degenerate("insertion needs D >= 3")
        if 2 * int(self._alive[: self._n].sum()) < self._n:
            self._compact()
        p, n = self.points[idx], self._n
        eq, simp, nbr, alive = self._eq[:n], self._simp[:n], self._nbr[:n], self._alive[:n]
        visible = (eq[:, :-1] @ p + eq[:, -1] > _VISIBLE_REL_TOL * self._size) & alive
        seen = np.flatnonzero(visible)
        if not len(seen):
            return  # inside (or on) the hull: nothing changes
        across = nbr[seen]  # (v, D)
        fv, slot = np.nonzero(~visible[across])  # horizon: a visible facet's ridge to a hidden one
        if not len(fv):
            raise _Degenerate("every facet visible")
        f, g = seen[fv], across[fv, slot]
        keep_cols = np.arange(d)[None, :] != slot[:, None]
        ridge = simp[f][keep_cols].reshape(len(f), d - 1)  # (h, D - 1)
        h = len(f)
        new_ids = n + np.arange(h)
        new_simp = np.hstack([ridge, np.full((h, 1), idx)])
        new_nbr = np.empty((h, d), dtype=np.int64)
        new_nbr[:, d - 1] = g  # across from the new point: the hidden facet of the ridge
        # The hidden facet's slot that pointed at the visible one now points at the new facet.
        g_slot = np.argmax(nbr[g] == f[:, None], axis=1)
        if not np.all(nbr[g, g_slot] == f):
            raise _Degenerate("a horizon ridge without its facet")
        # New facets meet across the ridges through the new point: the D - 2 ridge vertices
        # left after dropping one, shared by exactly two horizon ridges.
        sub = np.sort(ridge, axis=1)
        faces = sub[:, _dropping_one(d - 1)].reshape(-1, d - 2)
        owner = np.repeat(np.arange(h), d - 1)
        dropped = sub.reshape(-1)  # the vertex each face leaves out, in the faces' order
        own_slot = np.argmax(new_simp[owner] == dropped[:, None], axis=1)
        order = np.argsort(_keys(faces, len(self.points)), kind="stable")
        paired = faces[order]
        if len(paired) % 2 or not np.all(paired[0::2] == paired[1::2]):
            raise _Degenerate("a ridge through the new point not shared by two facets")
        a, b = order[0::2], order[1::2]
        new_nbr[owner[a], own_slot[a]] = new_ids[owner[b]]
        new_nbr[owner[b], own_slot[b]] = new_ids[owner[a]]
        new_eq = self._planes(new_simp, eq[f, :-1])
        if n + h > len(self._alive):
            self._grow(h)
        self._nbr[g, g_slot] = new_ids
        self._alive[seen] = False
        self._simp[n : n + h], self._nbr[n : n + h], self._eq[n : n + h] = new_simp, new_nbr, new_eq
        self._alive[n : n + h] = True
        self._n = n + h
        self._qhull = False

    def _planes(self, simp: NDArray[np.int64], near: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(h, D + 1)`` the outward unit hyperplanes through the simplices' vertices.

        Each normal ``n`` solves ``E n = 0`` (``E`` the simplex's D - 1 edge vectors) with
        ``near . n = 1``, ``near`` a unit vector close to it (the normal of the visible facet
        it replaces): one LU per facet, a third of an SVD's time. A simplex that is nearly
        flat, or whose normal is nearly orthogonal to ``near``, is `_Degenerate`."""
        pts = self.points[simp]  # (h, D, D)
        h, d = len(simp), pts.shape[2]
        m = np.empty((h, d, d))
        m[:, :-1, :] = pts[:, :-1, :] - pts[:, -1:, :]
        m[:, -1, :] = near
        rhs = np.zeros((h, d, 1))
        rhs[:, -1, 0] = 1.0
        try:
            normal = np.linalg.solve(m, rhs)[:, :, 0]
        except np.linalg.LinAlgError as e:
            raise _Degenerate("a flat new facet") from e
        length = np.sqrt(np.einsum("hd,hd->h", normal, normal))
        # |n| >= 1 from near . n = 1; past 1e6 the facet is nearly flat or turned away.
        if not np.all(np.isfinite(length)) or float(length.max()) > 1.0 / _FLAT_REL_TOL:
            raise _Degenerate("a nearly flat new facet")
        normal /= length[:, None]
        offset = -np.einsum("hd,hd->h", normal, pts[:, -1, :])
        sign = np.where(normal @ self._inside + offset > 0.0, -1.0, 1.0)
        return np.hstack([normal * sign[:, None], (offset * sign)[:, None]])
