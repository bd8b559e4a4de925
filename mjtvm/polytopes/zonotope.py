r"""Zonotopes: the image of a box under a linear map, by its generators' combinations.

A box $\{x : x_{min} \le x \le x_{max}\}$ through a matrix ``A`` is the zonotope
$Z = c + \sum_i [-1, 1]\, g_i$ with centre $c = A (x_{min} + x_{max}) / 2$ and
generators $g_i = A_i (x_{max,i} - x_{min,i}) / 2$. Its faces come from the generators
alone (McMullen 1971; Ziegler, *Lectures on Polytopes*, 1995, section 7.3): in the
k-dimensional linear span of the generators,

* every facet lies in a hyperplane spanned by k - 1 generators: with ``n`` its normal and
  ``H`` the generators in it, the facet is $c \pm \sum_{i \notin H}
  \mathrm{sign}(n^T g_i)\, g_i + \sum_{i \in H} [-1, 1]\, g_i$, a (k-1)-zonotope at offset
  $n^T c \pm \sum_{i} |n^T g_i|$ (the facets of "hyperplane shifting": Gouttefarde and
  Krut 2010, which pycapacity implements);
* every vertex is $c + \sum_i \sigma_i g_i$ for the sign vector
  $\sigma_i = \mathrm{sign}(u^T g_i)$ of a generic direction ``u``, and lies on a facet:
  the vertices are those of the facets, i.e. for a facet with ``|H| = k - 1`` its
  $2^{k-1}$ sign choices on ``H`` (otherwise the facet's own vertices, by recursion);
* the volume is $2^k \sum_{|S| = k} |\det g_S|$ (Shephard 1974), computed here as the
  pyramids over the facets, $\frac{1}{k} \sum_F h_F A_F$, whose areas
  $A_F = 2^{k-1} |\det g_S|$ the facets' normals already hold (cofactor normals).

No LP, no Qhull: numpy on $\binom{n}{k-1}$ generator subsets, exact up to round-off.
Vertices are found as distinct sign vectors (integers), so none is found twice. Zero
generators are dropped and parallel ones merged first (their segments add up).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from itertools import combinations, product

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import ParamError

__all__ = ["MAX_CANDIDATES", "PLANE_TOL", "RANK_TOL", "Zonotope", "zonotope"]

RANK_TOL = 1e-12  #: singular values below this x the largest are round-off (the span's rank)
PLANE_TOL = 1e-10  #: a generator within this angle (rad) of a facet's hyperplane lies in it
MAX_CANDIDATES = 2**24  #: (k-1)-subsets x 2^(k-1) sign choices x generators the enumeration may hold


@dataclass(frozen=True, eq=False)
class Zonotope:
    r"""A zonotope $c + \sum_i [-1, 1]\, g_i$ in $R^m$, with its faces and volume.

    Attributes
    ----------
    center
        ``(m,)`` the centre ``c``.
    generators
        ``(m, n)`` the generators after dropping zero ones and merging parallel ones.
    dimension
        ``k``, the dimension of its affine hull (0 for a point).
    basis
        ``(k, m)`` orthonormal basis of the linear span of the generators.
    vertices
        ``(v, m)`` the vertices.
    signs
        ``(v, n)`` int8: vertex ``j`` is ``center + generators @ signs[j]``.
    normals, offsets
        ``(f, m)`` unit rows and ``(f,)``: the facets $n^T x \le o$ inside the affine
        hull (the normals lie in the span; none when ``k < 2``, the segment's ends bound it).
    affine_volume
        ``k``-dimensional volume inside the affine hull (the length for ``k = 1``, 0 for a point).
    """

    center: NDArray[np.float64]
    generators: NDArray[np.float64]
    dimension: int
    basis: NDArray[np.float64]
    vertices: NDArray[np.float64]
    signs: NDArray[np.int8]
    normals: NDArray[np.float64]
    offsets: NDArray[np.float64]
    affine_volume: float

    @property
    def volume(self) -> float:
        """The m-dimensional volume: ``affine_volume`` when full-dimensional, else 0."""
        return self.affine_volume if self.dimension == self.center.shape[0] else 0.0


def _merged(gens: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(m, n')``: zero columns dropped (below `RANK_TOL` x the largest), parallel ones added
    (aligned to the first of their direction)."""
    norms = np.sqrt(np.einsum("ij,ij->j", gens, gens))
    big = float(norms.max(initial=0.0))
    if big == 0.0:
        return np.zeros((gens.shape[0], 0))
    keep = norms > RANK_TOL * big
    g, norms = gens[:, keep], norms[keep]
    unit = g / norms
    cos = unit.T @ unit
    parallel = np.abs(cos) >= 1.0 - PLANE_TOL**2 / 2  # angle below PLANE_TOL
    np.fill_diagonal(parallel, True)
    if np.count_nonzero(parallel) == len(norms):  # only the diagonal: nothing to merge
        return g
    out, taken = [], np.zeros(len(norms), dtype=bool)
    for i in range(len(norms)):
        if not taken[i]:
            group = parallel[i] & ~taken
            taken |= group
            out.append(g[:, group] @ np.sign(cos[i, group]))
    return np.array(out).T


def _cofactor_normals(sub: NDArray[np.float64]) -> NDArray[np.float64]:
    r"""``(C, k)``: for ``(C, k, k-1)`` column sets, the vector orthogonal to each set whose norm
    is the (k-1)-volume of the parallelotope they span (the generalised cross product)."""
    k = sub.shape[1]
    if k == 2:
        return np.stack([sub[:, 1, 0], -sub[:, 0, 0]], axis=1)
    if k == 3:  # the cross product, written out (np.cross moves axes: slower on small arrays)
        a, b = sub[:, :, 0], sub[:, :, 1]
        return np.stack(
            [
                a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
                a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
            ],
            axis=1,
        )
    rows = np.arange(k)
    return np.stack(
        [(-1) ** j * np.linalg.det(sub[:, rows != j, :]) for j in range(k)], axis=1
    )  # Laplace expansion of det([x, sub]) along x


@lru_cache(maxsize=64)
def _subsets(n: int, size: int) -> tuple[NDArray[np.intp], NDArray[np.int8]]:
    """The ``size``-subsets of ``range(n)`` as rows, and the ``2^size`` sign choices (cached:
    a hand's fingers ask for the same few)."""
    subsets = np.array(list(combinations(range(n), size)), dtype=np.intp).reshape(-1, size)
    choices = np.array(list(product((-1, 1), repeat=size)), dtype=np.int8).reshape(-1, size)
    subsets.setflags(write=False)
    choices.setflags(write=False)
    return subsets, choices


def _faces(
    g: NDArray[np.float64],
) -> tuple[NDArray[np.int8], NDArray[np.float64], NDArray[np.float64], float]:
    r"""Sign vectors of the vertices, the facets' unit normals and half-widths
    $\sum_i |n^T g_i|$ (one row per pair of opposite facets), and the volume of
    $\sum_i [-1, 1] g_i$ for ``(k, n)`` generators of rank k, none zero, none parallel."""
    k, n = g.shape
    if k == 1:
        s = np.sign(g[0]).astype(np.int8)
        return (
            np.vstack([s, -s]),
            np.ones((1, 1)),
            np.abs(g[0]).sum(keepdims=True),
            2.0 * float(np.abs(g).sum()),
        )
    if n == k:  # a parallelepiped: every sign vector, facets along the dual basis
        dual = np.linalg.inv(g)  # dual[i] . g_j = delta_ij
        size = np.sqrt(np.einsum("ij,ij->i", dual, dual))
        return (
            _subsets(k, k)[1].copy(),
            dual / size[:, None],
            1.0 / size,
            2.0**k * abs(float(np.linalg.det(g))),
        )
    subsets, choices = _subsets(n, k - 1)
    normals = _cofactor_normals(np.transpose(g[:, subsets], (1, 0, 2)))
    area = np.sqrt(np.einsum("ij,ij->i", normals, normals))
    gnorm = np.sqrt(np.einsum("ij,ij->j", g, g))
    spans = area > RANK_TOL * gnorm[subsets].prod(axis=1)  # the k - 1 span a hyperplane
    if not spans.all():
        subsets, normals, area = subsets[spans], normals[spans], area[spans]
    normals = normals / area[:, None]
    dots = normals @ g
    size = np.abs(dots)
    inside = size <= PLANE_TOL * gnorm
    generic = inside.sum(axis=1) == k - 1
    width = size.sum(axis=1)
    # Generic facets: the signs off the hyperplane, then the 2^(k-1) choices on its generators.
    base = np.where(inside[generic], 0, np.sign(dots[generic])).astype(np.int8)
    signs = np.repeat(base, len(choices), axis=0)
    rows = np.arange(len(signs))[:, None]
    signs[rows, np.repeat(subsets[generic], len(choices), axis=0)] = np.tile(choices, (len(base), 1))
    # The pyramids over the facet pair: 2 x (1/k) x width x 2^(k-1) area.
    volume = 2.0**k / k * float(width[generic] @ area[generic])
    parts, kept_normals, kept_width = [signs], [normals[generic]], [width[generic]]
    if not generic.all():
        # A hyperplane with more than k - 1 generators: its facets are (k-1)-zonotopes of them,
        # found once per (k-1)-subset: one each.
        planes, first = np.unique(inside[~generic], axis=0, return_index=True)
        for plane, j in zip(planes, np.flatnonzero(~generic)[first], strict=True):
            frame = np.linalg.svd(normals[j][None, :])[2][1:]  # orthonormal basis of the hyperplane
            sub_signs, _, _, sub_volume = _faces(frame @ g[:, plane])
            outer = np.where(plane, 0, np.sign(dots[j])).astype(np.int8)
            block = np.repeat(outer[None, :], len(sub_signs), axis=0)
            block[:, plane] = sub_signs
            parts.append(block)
            kept_normals.append(normals[j][None, :])
            kept_width.append(width[j : j + 1])
            volume += 2.0 / k * float(width[j]) * sub_volume
    half = np.vstack(parts)
    return (
        _distinct_rows(half),
        np.vstack(kept_normals),
        np.concatenate(kept_width),
        volume,
    )


def _distinct_rows(half: NDArray[np.int8]) -> NDArray[np.int8]:
    """The distinct rows of the +-1 rows ``half`` and of their negatives (as integer keys when
    ``n <= 62``, a negative's key being the complement of the row's: a sort of integers
    instead of rows)."""
    n = half.shape[1]
    if n > 62:
        return np.unique(np.vstack([half, -half]), axis=0)
    bits = np.int64(1) << np.arange(n, dtype=np.int64)
    keys = (half > 0).astype(np.int64) @ bits
    keys = np.unique(np.concatenate([keys, (bits.sum() - keys)]))
    return (((keys[:, None] & bits) != 0) * 2 - 1).astype(np.int8)


def _check_size(n: int, k: int) -> None:
    """Refuse an enumeration that would hold more than `MAX_CANDIDATES` entries."""
    size = math.comb(n, k - 1) * 2 ** (k - 1) * n if k >= 2 else n
    if size > MAX_CANDIDATES:
        raise ParamError(
            "generators",
            f"expected at most {MAX_CANDIDATES} enumeration entries, got {size} "
            f"({n} generators in dimension {k}: C({n}, {k - 1}) facet pairs)",
        )


def zonotope(center: ArrayLike, generators: ArrayLike) -> Zonotope:
    r"""The zonotope $c + \sum_i [-1, 1]\, g_i$: vertices, facets and volume (module docstring).

    Parameters
    ----------
    center
        ``(m,)`` the centre ``c``.
    generators
        ``(m, n)`` one generator per column (a half-extent: the segment is ``[-g, g]``).

    Returns
    -------
    Zonotope

    Raises
    ------
    ParamError
        Non-finite or mis-shaped arrays, or an enumeration larger than `MAX_CANDIDATES`.
    """
    c = np.asarray(center, dtype=float)
    g = np.asarray(generators, dtype=float)
    if c.ndim != 1 or g.ndim != 2 or g.shape[0] != c.shape[0] or not c.size:
        raise ParamError("generators", f"expected an (m, n) array with m = len(center) >= 1, got {g.shape}")
    if not (np.isfinite(c).all() and np.isfinite(g).all()):
        raise ParamError("generators", "expected finite numbers")
    m = c.shape[0]
    merged = _merged(g)
    if merged.shape[1]:
        u, sv, _ = np.linalg.svd(merged, full_matrices=False)
        k = int(np.sum(sv > RANK_TOL * sv[0]))
    else:
        u, k = np.zeros((m, 0)), 0
    basis = u[:, :k].T
    if k == 0:
        no_facets = np.zeros((0, m)), np.zeros(0)
        return Zonotope(
            c, merged, 0, basis, c[None, :], np.zeros((1, merged.shape[1]), np.int8), *no_facets, 0.0
        )
    _check_size(merged.shape[1], k)
    local = basis @ merged
    signs, normals, width, volume = _faces(local)
    vertices = c + (merged @ signs.T).T
    if k == 1:
        return Zonotope(c, merged, 1, basis, vertices, signs, np.zeros((0, m)), np.zeros(0), volume)
    n_amb = normals @ basis
    centre = n_amb @ c
    return Zonotope(
        center=c,
        generators=merged,
        dimension=k,
        basis=basis,
        vertices=vertices,
        signs=signs,
        normals=np.vstack([n_amb, -n_amb]),
        offsets=np.concatenate([centre + width, -centre + width]),
        affine_volume=volume,
    )
