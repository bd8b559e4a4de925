r"""A compressed-sparse-column matrix as HiGHS takes it: three arrays and a shape.

Problem 2 builds, equilibrates and passes one constraint matrix per state and reads nothing
else of it, so its path does not import `scipy.sparse`: that import alone is about
0.12 s of a ``mjtvm solve`` process (scipy's array-API layer clones numpy's namespace,
which imports ``numpy.testing`` and ``numpy.f2py``), more than the solve itself. Everything
else (the polytopes, the fallbacks, Clarabel) gets a scipy matrix from [`Csc.to_scipy()`][mjtvm.lp.csc.Csc.to_scipy].
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    import scipy.sparse as sp

__all__ = ["Csc", "as_csc", "from_triplets", "scipy_matrix"]


@dataclass(frozen=True, eq=False)
class Csc:
    """An ``(m, n)`` matrix in canonical compressed-sparse-column form: the row indices of
    each column sorted, no duplicates (what scipy calls ``has_canonical_format``).

    Parameters
    ----------
    data
        ``(nnz,)`` the values, column by column.
    indices
        ``(nnz,)`` int32, their rows.
    indptr
        ``(n + 1,)`` int32, column ``j``'s entries at ``indptr[j]:indptr[j + 1]``.
    shape
        ``(m, n)``.
    """

    data: NDArray[np.float64]
    indices: NDArray[np.int32]
    indptr: NDArray[np.int32]
    shape: tuple[int, int]

    def __post_init__(self) -> None:
        m, n = self.shape
        if self.indptr.shape != (n + 1,) or self.data.shape != self.indices.shape:
            raise ValueError(f"inconsistent CSC arrays for shape {self.shape}")
        if self.indptr[0] != 0 or self.indptr[-1] != self.data.size:
            raise ValueError("indptr must run from 0 to nnz")
        if self.indices.size and (self.indices.min() < 0 or self.indices.max() >= m):
            raise ValueError(f"row index outside 0..{m - 1}")

    @property
    def nnz(self) -> int:
        """The number of stored entries."""
        return int(self.data.size)

    def columns(self) -> NDArray[np.int64]:
        """``(nnz,)`` each stored entry's column."""
        return np.repeat(np.arange(self.shape[1]), np.diff(self.indptr))

    def toarray(self) -> NDArray[np.float64]:
        """The dense ``(m, n)`` matrix."""
        out = np.zeros(self.shape)
        out[self.indices, self.columns()] = self.data
        return out

    def to_scipy(self) -> sp.csc_matrix:
        """The same matrix as a ``scipy.sparse.csc_matrix`` (arrays shared, not copied)."""
        import scipy.sparse as sp

        out = sp.csc_matrix((self.data, self.indices, self.indptr), shape=self.shape)
        out.has_canonical_format = True
        return out


def from_triplets(
    rows: NDArray[np.int64], cols: NDArray[np.int64], vals: NDArray[np.float64], shape: tuple[int, int]
) -> Csc:
    """The canonical [`Csc`][mjtvm.lp.csc.Csc] of ``(row, col, value)`` triplets; repeated positions are
    summed (as scipy's COO conversion does)."""
    order = np.lexsort((rows, cols))
    rows, cols, vals = rows[order], cols[order], np.asarray(vals, dtype=float)[order]
    if rows.size > 1:
        new = np.concatenate([[True], (np.diff(cols) != 0) | (np.diff(rows) != 0)])
        if not new.all():
            starts = np.flatnonzero(new)
            vals = np.add.reduceat(vals, starts)
            rows, cols = rows[starts], cols[starts]
    indptr = np.zeros(shape[1] + 1, dtype=np.int32)
    np.cumsum(np.bincount(cols, minlength=shape[1]), out=indptr[1:])
    return Csc(vals, rows.astype(np.int32), indptr, (int(shape[0]), int(shape[1])))


def as_csc(a: Any) -> Csc:
    """``a`` (a [`Csc`][mjtvm.lp.csc.Csc], a scipy sparse matrix or a dense array) as a canonical [`Csc`][mjtvm.lp.csc.Csc]."""
    if isinstance(a, Csc):
        return a
    import scipy.sparse as sp

    c = sp.csc_matrix(a, dtype=float)  # a copy only when a is not csc already
    if not c.has_canonical_format:
        c = c.copy()
        c.sum_duplicates()
    return Csc(
        np.asarray(c.data, dtype=float),
        c.indices.astype(np.int32),
        c.indptr.astype(np.int32),
        (int(c.shape[0]), int(c.shape[1])),
    )


def scipy_matrix(a: Any) -> Any:
    """``a`` as scipy takes it: a [`Csc`][mjtvm.lp.csc.Csc] converted ([`Csc.to_scipy()`][mjtvm.lp.csc.Csc.to_scipy]), anything else as it is."""
    return a.to_scipy() if isinstance(a, Csc) else a
