"""The LP form shared by the backends: :class:`LinearProgram` and :class:`LPSolution`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from .roundoff import DROP_REL

__all__ = ["DROP_REL", "FEASIBILITY_TOL", "LPSolution", "LPStatus", "LinearProgram"]

LPStatus = Literal["optimal", "infeasible", "unbounded"]
FEASIBILITY_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class LinearProgram:
    """``min c^T x`` s.t. ``row_lower <= A x <= row_upper`` and ``col_lower <= x <= col_upper``."""

    c: NDArray[np.float64]
    A: sp.csc_matrix
    row_lower: NDArray[np.float64]
    row_upper: NDArray[np.float64]
    col_lower: NDArray[np.float64]
    col_upper: NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class LPSolution:
    """Status, primal solution (``None`` unless optimal) and objective of an LP.

    ``x``, ``objective`` and ``row_dual`` are in the LP's own (unscaled) units.
    """

    status: LPStatus
    x: NDArray[np.float64] | None
    objective: float | None
    row_dual: NDArray[np.float64] | None = None  #: HiGHS' row duals, when asked for
