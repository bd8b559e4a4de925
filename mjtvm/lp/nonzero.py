r"""Products with a dense matrix restricted to its nonzero entries, without BLAS.

Problem 2's certificates multiply every answer of a state with the state's matrix (dense, so
that its last column, alpha's, can be overwritten in place). A large hand's matrix is
mostly zeros (0.9 % full at 32 fingers) and so large that OpenBLAS runs even one answer's
product on several threads, which then spin between calls (twice the CPU time for the same
wall time). [`NonzeroProducts`][mjtvm.lp.nonzero.NonzeroProducts] keeps the matrix's pattern and forms the same
sums from its nonzeros only: gathers, one multiplication and one ``np.add.reduceat`` per
product, on the calling thread. The sums are the same terms added in another order (equal to
round-off).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["NonzeroProducts"]


def _segments(keys: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """For sorted ``keys``: the start of each run of equal keys and the key of the run."""
    if not keys.size:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    starts = np.flatnonzero(np.concatenate([[True], keys[1:] != keys[:-1]]))
    return starts, keys[starts]


class NonzeroProducts:
    """The pattern of an ``(m, k)`` matrix, for products with it or with any matrix of the
    same shape whose nonzeros lie within that pattern (``|A|``, or ``|A|`` with entries
    zeroed).

    Parameters
    ----------
    pattern
        ``(m, k)`` dense; its nonzero entries are the pattern (read once, here).
    """

    def __init__(self, pattern: NDArray[np.float64]) -> None:
        rows, cols = np.nonzero(pattern)  # row-major order
        self._index(pattern.shape, rows, cols)

    @classmethod
    def from_entries(
        cls, shape: tuple[int, ...], rows: NDArray[np.integer[Any]], cols: NDArray[np.integer[Any]]
    ) -> NonzeroProducts:
        """The pattern of the entries at ``(rows, cols)``, each once, in any order: the same
        object as the dense matrix's with nonzeros there, without reading ``m x k`` entries
        (a sparse matrix's stored entries: O(nnz) instead of ``np.nonzero``'s O(m k))."""
        r, c = np.asarray(rows, dtype=np.int64), np.asarray(cols, dtype=np.int64)
        order = np.lexsort((c, r))  # row-major order, as np.nonzero's
        obj = cls.__new__(cls)
        obj._index(shape, r[order], c[order])
        return obj

    def _index(self, shape: tuple[int, ...], rows: NDArray[np.int64], cols: NDArray[np.int64]) -> None:
        """The pattern from its entries in row-major order."""
        self.shape = shape
        self.rows, self.cols = rows, cols
        self.row_starts, self.row_ids = _segments(rows)
        order = np.lexsort((rows, cols))  # column-major order
        self.t_rows, self.t_cols = rows[order], cols[order]
        self.col_starts, self.col_ids = _segments(self.t_cols)

    def right(self, values: NDArray[np.float64], xs: NDArray[np.float64]) -> NDArray[np.float64]:
        """``xs @ values.T``: ``(P, k)`` in, ``(P, m)`` out (``values`` zero off the pattern)."""
        out = np.zeros((xs.shape[0], self.shape[0]))
        if self.rows.size:
            terms = xs[:, self.cols] * values[self.rows, self.cols]
            out[:, self.row_ids] = np.add.reduceat(terms, self.row_starts, axis=1)
        return out

    def left(self, values: NDArray[np.float64], ys: NDArray[np.float64]) -> NDArray[np.float64]:
        """``ys @ values``: ``(P, m)`` in, ``(P, k)`` out (``values`` zero off the pattern)."""
        out = np.zeros((ys.shape[0], self.shape[1]))
        if self.t_rows.size:
            terms = ys[:, self.t_rows] * values[self.t_rows, self.t_cols]
            out[:, self.col_ids] = np.add.reduceat(terms, self.col_starts, axis=1)
        return out
