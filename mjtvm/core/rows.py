"""The rows of a sparse constraint system as they are appended (:mod:`mjtvm.core.assembly`)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

__all__ = ["Coo", "Rows"]


class Coo:
    """Accumulates (row, col, value) triplets block by block."""

    def __init__(self) -> None:
        self.rows: list[NDArray[np.int64]] = []
        self.cols: list[NDArray[np.int64]] = []
        self.vals: list[NDArray[np.float64]] = []

    def add(self, row0: int, col0: int, block: NDArray[np.float64]) -> None:
        block = np.atleast_2d(block)
        # Only exact zeros are left out: which tiny entries are round-off depends on the
        # scale of their row and column, decided after equilibration (solvers.scale_lp).
        r, c = np.nonzero(block)
        self.rows.append(r + row0)
        self.cols.append(c + col0)
        self.vals.append(block[r, c])

    def add_entries(
        self, rows: NDArray[np.int64], cols: NDArray[np.int64], values: NDArray[np.float64]
    ) -> None:
        keep = values != 0.0
        self.rows.append(rows[keep])
        self.cols.append(cols[keep])
        self.vals.append(values[keep])

    def build(self, shape: tuple[int, int]) -> sp.csc_matrix:
        if not self.rows:
            return sp.csc_matrix(shape)
        rows, cols, vals = np.concatenate(self.rows), np.concatenate(self.cols), np.concatenate(self.vals)
        # The blocks never overlap, so the canonical CSC is a sort by (column, row): built
        # directly, it costs a tenth of scipy's COO conversion (Problem 2 assembles per state).
        # Should an entry repeat, scipy sums the duplicates as before.
        order = np.lexsort((rows, cols))
        rows, cols = rows[order], cols[order]
        if rows.size > 1 and np.any((np.diff(cols) == 0) & (np.diff(rows) == 0)):
            return sp.csc_matrix((vals[order], (rows, cols)), shape=shape)
        indptr = np.zeros(shape[1] + 1, dtype=np.int32)
        np.cumsum(np.bincount(cols, minlength=shape[1]), out=indptr[1:])
        out = sp.csc_matrix((vals[order], rows.astype(np.int32), indptr), shape=shape)
        out.has_canonical_format = True
        return out


class Rows:
    """The rows of the system as they are appended: their triplets in ``A`` and ``A_twist``
    and their bounds."""

    def __init__(self) -> None:
        self.coo, self.twist = Coo(), Coo()
        self.lower: list[NDArray[np.float64]] = []
        self.upper: list[NDArray[np.float64]] = []
        self.groups: list[NDArray[np.int64]] = []
        self.count = 0
        self.num_groups = 0

    def add(
        self,
        lo: NDArray[np.float64] | float,
        hi: NDArray[np.float64] | float,
        count: int,
        *,
        vector: bool = False,
        join: bool = False,
    ) -> int:
        """Append ``count`` rows bounded by ``lo`` and ``hi``; the index of the first. With
        ``vector`` the rows are the components of one vector (one row group, see
        :attr:`mjtvm.core.assembly.Assembly.row_groups`); with ``join`` they join the last group."""
        bounds = np.empty((2, count))
        bounds[0], bounds[1] = lo, hi
        self.lower.append(bounds[0])
        self.upper.append(bounds[1])
        if join:
            self.groups.append(np.full(count, self.num_groups - 1))
        elif vector:
            self.groups.append(np.full(count, self.num_groups))
            self.num_groups += 1
        else:
            self.groups.append(self.num_groups + np.arange(count))
            self.num_groups += count
        start = self.count
        self.count += count
        return start
