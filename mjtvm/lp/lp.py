"""The LP form shared by the backends: [`LinearProgram`][mjtvm.lp.lp.LinearProgram] and [`LPSolution`][mjtvm.lp.lp.LPSolution]."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.roundoff import DROP_REL

if TYPE_CHECKING:
    import scipy.sparse as sp

    from mjtvm.lp.csc import Csc

__all__ = ["DROP_REL", "FEASIBILITY_TOL", "LPSolution", "LPStatus", "LinearProgram"]

LPStatus = Literal["optimal", "infeasible", "unbounded"]
FEASIBILITY_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class LinearProgram:
    """``min c^T x`` s.t. ``row_lower <= A x <= row_upper`` and ``col_lower <= x <= col_upper``.

    ``A`` is a scipy sparse matrix, or a [`Csc`][mjtvm.lp.csc.Csc] where only HiGHS reads
    it (Problem 2's session)."""

    c: NDArray[np.float64]
    A: sp.csc_matrix | Csc
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
