r"""Compiled kernels of the growing hull ([`GrowingHull`][mjtvm.measures.hull.GrowingHull]):
the beneath-beyond insertion, the expanding polytope's rounds of
[`epsilon_linf()`][mjtvm.measures.wrenches.epsilon_linf] and the hull's check, in numba.

The numpy insertion of `mjtvm.measures.hull` costs ~40 array calls a point, ~0.5 ms on the
five-finger Shadow grasps (2,000-4,000 facets, 50 points a grasp), almost all of it call
overhead on arrays of a few hundred rows; compiled, a point costs a tenth of that. The
insertion finds the same visible facets, horizon ridges and new facets, in the same order,
with the same degeneracy tests as the numpy one; a new facet's hyperplane is the rotation of
the hidden facet's about the horizon ridge (D flops, not a D x D solve, `insert()`), so the
facets agree with the numpy ones to round-off, and `GrowingHull.verify()` checks them (every
point held, every facet through its vertices, closed up) before any epsilon is read.

Imported lazily by the hull (numba's import and the kernels' load take ~0.5 s; the compiled
code is cached on disk, ``cache=True``; the first compile ~10 s), so that ``import mjtvm``
and single grasps pay nothing. Status codes returned: `OK`, `FULL` (no room in the arrays:
nothing written; make room and call again), `DEGENERATE` (the point is appended but not
inserted: rebuild with Qhull) and, from `expand()`, `CONVERGED` and `ROUNDS`.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["CONVERGED", "DEGENERATE", "FULL", "OK", "ROUNDS", "closed_and_holding", "expand", "insert"]

OK = 0
"""Status: the point inserted (or inside the hull: nothing else changed)."""
FULL = 1
"""Status: no row left for the point or its facets; nothing written."""
DEGENERATE = 2
"""Status: the point appended, not inserted (an unmatched ridge or a nearly flat facet)."""
CONVERGED = 3
"""Status of `expand()`: the bracket closed, or no support point beyond the nearest facet."""
ROUNDS = 4
"""Status of `expand()`: the rounds ran out."""


@numba.njit(cache=True)
def insert(
    points: np.ndarray,
    npts: int,
    p: np.ndarray,
    simp: np.ndarray,
    nbr: np.ndarray,
    eq: np.ndarray,
    alive: np.ndarray,
    nf: int,
    inside: np.ndarray,
    size: float,
    visible_rel: float,
    flat_rel: float,
) -> tuple[int, int, int]:
    """Append ``p`` as point ``npts`` and replace the facets it sees (beyond their hyperplane by
    more than ``visible_rel * size``) by the cone from it over their horizon ridges.

    Returns ``(status, npts, nf)``: `OK` (inserted, or inside: nothing else changes),
    `FULL` (no row left in ``points`` or the facet arrays: nothing written) or `DEGENERATE`
    (appended, not inserted: an unmatched ridge or a nearly flat new facet, the cases where
    the numpy insertion raises)."""
    d = points.shape[1]
    if npts >= points.shape[0]:
        return FULL, npts, nf
    if d < 3:  # no ridge faces to pair: Qhull's
        points[npts] = p
        return DEGENERATE, npts + 1, nf
    tol = visible_rel * size
    vis = np.zeros(nf, dtype=np.bool_)
    seen = np.empty(nf, dtype=np.int64)
    slack = np.empty(nf)
    nvis = 0
    for f in range(nf):
        if alive[f]:
            s = eq[f, d]
            for k in range(d):
                s += eq[f, k] * p[k]
            slack[f] = s
            if s > tol:
                vis[f] = True
                seen[nvis] = f
                nvis += 1
    idx = npts
    if nvis == 0:
        points[idx] = p
        return OK, npts + 1, nf
    # Horizon ridges, in the numpy code's order (visible facet ascending, then its slot).
    hf = np.empty(nvis * d, dtype=np.int64)
    hs = np.empty(nvis * d, dtype=np.int64)
    hg = np.empty(nvis * d, dtype=np.int64)
    h = 0
    for a in range(nvis):
        f = seen[a]
        for j in range(d):
            g = nbr[f, j]
            if not vis[g]:
                hf[h], hs[h], hg[h] = f, j, g
                h += 1
    if nf + h > simp.shape[0]:
        return FULL, npts, nf
    points[idx] = p
    if h == 0:
        return DEGENERATE, npts + 1, nf  # every facet visible
    new_simp = np.empty((h, d), dtype=np.int64)
    new_nbr = np.empty((h, d), dtype=np.int64)
    g_slot = np.empty(h, dtype=np.int64)
    for k in range(h):
        f, j, g = hf[k], hs[k], hg[k]
        c = 0
        for q in range(d):
            if q != j:
                new_simp[k, c] = simp[f, q]
                c += 1
        new_simp[k, d - 1] = idx
        new_nbr[k, d - 1] = g  # across from the new point: the hidden facet of the ridge
        g_slot[k] = -1
        for q in range(d):
            if nbr[g, q] == f:
                g_slot[k] = q
                break
        if g_slot[k] < 0:
            return DEGENERATE, npts + 1, nf  # a horizon ridge without its facet
    # New facets meet across the faces (D - 2 ridge vertices) through the new point, each
    # shared by exactly two of them: keyed by its sorted vertices as digits in base npts + 1.
    base = npts + 1
    nfaces = h * (d - 1)
    keys = np.empty(nfaces, dtype=np.int64)
    owner = np.empty(nfaces, dtype=np.int64)
    slot = np.empty(nfaces, dtype=np.int64)
    sub = np.empty(d - 1, dtype=np.int64)
    for k in range(h):
        for r in range(d - 1):  # insertion sort of the ridge's few vertices
            v, q = new_simp[k, r], r
            while q > 0 and sub[q - 1] > v:
                sub[q] = sub[q - 1]
                q -= 1
            sub[q] = v
        for q in range(d - 1):
            key = 0
            for r in range(d - 1):
                if r != q:
                    key = key * base + sub[r]
            e = k * (d - 1) + q
            keys[e], owner[e] = key, k
            for r in range(d):
                if new_simp[k, r] == sub[q]:
                    slot[e] = r  # the new facet's slot across from the dropped vertex
                    break
    # Pair the faces by an open-addressing table of their keys (a sort cost 3x more).
    bits = 1
    while (1 << bits) < 2 * nfaces:
        bits += 1
    mask = (1 << bits) - 1
    table = np.full(1 << bits, -1, dtype=np.int64)
    mate = np.full(nfaces, -1, dtype=np.int64)
    for e in range(nfaces):
        slot_t = ((keys[e] * 0x9E3779B1) >> 7) & mask
        while True:
            o = table[slot_t]
            if o < 0:
                table[slot_t] = e
                break
            if keys[o] == keys[e]:
                if mate[o] >= 0:
                    return DEGENERATE, npts + 1, nf  # a third facet on one face
                mate[o], mate[e] = e, o
                break
            slot_t = (slot_t + 1) & mask
    for e in range(nfaces):
        if mate[e] < 0:
            return DEGENERATE, npts + 1, nf  # a ridge through the new point not shared by two
        new_nbr[owner[e], slot[e]] = nf + owner[mate[e]]
    # Planes: the new facet's hyperplane contains the ridge, as do the visible facet's
    # (a_f, slack s_f > 0 at p) and the hidden one's (a_g, s_g <= 0): its normal is the
    # combination of a_f and a_g orthogonal to p - x for x on the ridge,
    # n ~ s_f a_g - s_g a_f, which points outwards. D flops instead of a D x D solve; the
    # planes then hold their vertices only to round-off of earlier planes, which
    # `closed_and_holding()` checks. A normal nearly orthogonal to a_f (the ridge's two
    # facets nearly coplanar) is as degenerate as in the numpy insertion.
    new_eq = np.empty((h, d + 1))
    n = np.empty(d)
    for k in range(h):
        f, g = hf[k], hg[k]
        sf, sg = slack[f], slack[g]
        length = 0.0
        for c in range(d):
            n[c] = sf * eq[g, c] - sg * eq[f, c]
            length += n[c] * n[c]
        length = np.sqrt(length)
        if not (np.isfinite(length) and length > 0.0):
            return DEGENERATE, npts + 1, nf
        offset, at_inside, cos = 0.0, 0.0, 0.0
        for c in range(d):
            n[c] /= length
            offset -= n[c] * p[c]
            at_inside += n[c] * inside[c]
            cos += n[c] * eq[f, c]
        if abs(cos) < flat_rel:
            return DEGENERATE, npts + 1, nf
        sign = -1.0 if at_inside + offset > 0.0 else 1.0
        for c in range(d):
            new_eq[k, c] = n[c] * sign
        new_eq[k, d] = offset * sign
    for k in range(h):
        nbr[hg[k], g_slot[k]] = nf + k
    for a in range(nvis):
        alive[seen[a]] = False
    for k in range(h):
        simp[nf + k] = new_simp[k]
        nbr[nf + k] = new_nbr[k]
        eq[nf + k] = new_eq[k]
        alive[nf + k] = True
    return OK, npts + 1, nf + h


@numba.njit(cache=True)
def _compact(simp: np.ndarray, nbr: np.ndarray, eq: np.ndarray, alive: np.ndarray, nf: int) -> int:
    """Move the live facets to the first rows, in order, renumbering the neighbours
    (`GrowingHull._compact()` in place); returns their number."""
    new_id = np.empty(nf, dtype=np.int64)
    live = 0
    for f in range(nf):
        new_id[f] = live
        live += alive[f]
    for f in range(nf):
        if alive[f]:
            r = new_id[f]
            simp[r] = simp[f]
            eq[r] = eq[f]
            for j in range(simp.shape[1]):
                nbr[r, j] = new_id[nbr[f, j]]
    alive[:live] = True
    alive[live:nf] = False
    return live


@numba.njit(cache=True)
def expand(
    points: np.ndarray,
    npts: int,
    simp: np.ndarray,
    nbr: np.ndarray,
    eq: np.ndarray,
    alive: np.ndarray,
    nf: int,
    wrenches: np.ndarray,
    starts: np.ndarray,
    inside: np.ndarray,
    size: float,
    tol: float,
    rounds: int,
    visible_rel: float,
    flat_rel: float,
) -> tuple[int, int, int, float, float, int, int]:
    r"""Up to ``rounds`` rounds of the expanding polytope: the support point of the
    Minkowski sum of the sets conv(0, W_i) (``W_i`` the columns ``starts[i]:starts[i + 1]``
    of ``(D, n)`` ``wrenches``) along the nearest facet's normal ``u``,
    $h(u) = \sum_i \max(0, \max_k u^T w_{ik})$, inserted (`insert()`) when it lies beyond
    that facet by more than ``tol``.

    Returns ``(status, npts, nf, size, upper, rounds_done, inserted)``: `CONVERGED` (the
    nearest facet's distance within ``tol`` of the smallest ``h(u)`` of these rounds, ``upper``,
    or no point beyond it), `ROUNDS`, or an insertion's `FULL` or `DEGENERATE`; ``inserted``
    the points that changed the facets."""
    d = points.shape[1]
    upper = np.inf
    inserted = 0
    p = np.empty(d)
    for r in range(rounds):
        live = 0
        for f in range(nf):
            live += alive[f]
        if nf > 2 * live + 64:  # mostly dead rows: drop them (the scans run over all rows)
            nf = _compact(simp, nbr, eq, alive, nf)
        best_f, dist = -1, np.inf
        for f in range(nf):
            if alive[f] and -eq[f, d] < dist:
                best_f, dist = f, -eq[f, d]
        lower = max(0.0, dist)
        value = 0.0
        p[:] = 0.0
        for i in range(len(starts) - 1):
            top, kbest = -np.inf, -1
            for k in range(starts[i], starts[i + 1]):
                s = 0.0
                for c in range(d):
                    s += eq[best_f, c] * wrenches[c, k]
                if s > top:
                    top, kbest = s, k
            if top > 0.0:
                value += top
                for c in range(d):
                    p[c] += wrenches[c, kbest]
        upper = min(upper, value)
        if upper - lower <= tol or not value > dist + tol:
            return CONVERGED, npts, nf, size, upper, r, inserted
        big = 0.0
        for c in range(d):
            big = max(big, abs(p[c]))
        size = max(size, big)
        status, npts2, nf2 = insert(
            points, npts, p, simp, nbr, eq, alive, nf, inside, size, visible_rel, flat_rel
        )
        if status == FULL:
            return FULL, npts, nf, size, upper, r, inserted
        if nf2 != nf:
            inserted += 1
        npts, nf = npts2, nf2
        if status == DEGENERATE:
            return DEGENERATE, npts, nf, size, upper, r + 1, inserted
    return ROUNDS, npts, nf, size, upper, rounds, inserted


@numba.njit(cache=True)
def closed_and_holding(
    points: np.ndarray,
    npts: int,
    simp: np.ndarray,
    nbr: np.ndarray,
    eq: np.ndarray,
    alive: np.ndarray,
    nf: int,
    tol: float,
) -> bool:
    """`GrowingHull.verify()`'s test: every live facet's hyperplane finite, through its
    vertices and holding every point within ``tol``, every neighbour alive and naming the
    facet back."""
    d = points.shape[1]
    at = np.empty(npts)
    points_t = np.ascontiguousarray(points[:npts].T)
    for f in range(nf):
        if not alive[f]:
            continue
        for c in range(d + 1):
            if not np.isfinite(eq[f, c]):
                return False
        for j in range(d):
            s = eq[f, d]
            for c in range(d):
                s += eq[f, c] * points[simp[f, j], c]
            if abs(s) > tol:
                return False
        for j in range(d):
            g = nbr[f, j]
            if g < 0 or g >= nf or not alive[g]:
                return False
            named = False
            for q in range(d):
                named = named or nbr[g, q] == f
            if not named:
                return False
        at[:] = eq[f, d]
        for c in range(d):  # point index innermost: SIMD over the points
            e = eq[f, c]
            for i in range(npts):
                at[i] += e * points_t[c, i]
        for i in range(npts):
            if at[i] > tol:
                return False
    return True
