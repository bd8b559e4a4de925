"""The rows of a sparse constraint system as they are appended ([`mjtvm.problem2.assembly`][mjtvm.problem2.assembly])."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.csc import Csc, from_triplets

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

    def build(self, shape: tuple[int, int]) -> Csc:
        """The canonical CSC matrix of the triplets (a repeated position summed)."""
        if not self.rows:
            return from_triplets(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0), shape)
        return from_triplets(
            np.concatenate(self.rows), np.concatenate(self.cols), np.concatenate(self.vals), shape
        )


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
        `mjtvm.problem2.assembly.Assembly.row_groups`); with ``join`` they join the last group."""
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
