r"""Re-solves of an LP whose row bounds alone change, from the basis HiGHS left, in the
compiled dual simplex of [`dual_jit`][mjtvm.lp.dual_jit] instead of another HiGHS ``run()``.

[`WarmRows`][mjtvm.lp.warm.WarmRows] takes the equilibrated LP a
[`HighsSession`][mjtvm.lp.highs.HighsSession] holds and its basis after an optimal solve
([`HighsSession.held()`][mjtvm.lp.highs.HighsSession.held]), inverts the basis matrix once,
and re-solves for new row bounds from its own last basis; the answer is unscaled as the
session's are (``x = col * x_s``, ``y = row * y_s / g``), so that the caller certifies it on
the unscaled LP exactly as it certifies HiGHS'. Where the kernel gives up (module
[`dual_jit`][mjtvm.lp.dual_jit]) `WarmRows.solve()` returns ``None`` and the caller asks HiGHS.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.held import HeldColumn, merge_columns
from mjtvm.lp.highs import HighsSession
from mjtvm.lp.lp import FEASIBILITY_TOL, LPSolution

__all__ = ["WarmBasis", "WarmRows", "kernels"]


def kernels() -> ModuleType | None:
    """`mjtvm.lp.dual_jit` (imported on first use: numba's import and the cached kernels'
    load, ~0.5 s), or ``None`` where numba does not import."""
    try:
        from mjtvm.lp import dual_jit
    except ImportError:
        return None
    return dual_jit


@dataclass(frozen=True, eq=False)
class WarmBasis:
    """A basis of [`WarmRows`][mjtvm.lp.warm.WarmRows] ([`WarmRows.basis()`][mjtvm.lp.warm.WarmRows.basis]).

    Attributes
    ----------
    basic
        ``(m,)`` the basic variables (``j < n`` a column, ``n + i`` row ``i``'s activity).
    at_upper
        ``(n + m,)`` bool: a nonbasic variable is at its upper bound.
    binv
        ``(m, m)`` the basis matrix's inverse (row ``p`` belongs to ``basic[p]``).
    """

    basic: NDArray[np.int64]
    at_upper: NDArray[np.bool_]
    binv: NDArray[np.float64]


class WarmRows:
    """The LP of ``session`` re-solved for new row bounds (same matrix, same costs, same
    column bounds) by the compiled dual simplex, from the session's last basis.

    Parameters
    ----------
    session
        A session whose last `solve()` was optimal; it is not changed.
    jit
        `kernels()`'s module.
    row_lower, row_upper
        ``(m,)`` the (unscaled) row bounds of the session's last solve: a nonbasic row
        activity is at the nearer one.

    Raises
    ------
    ValueError
        Where the session's basis matrix is singular to the kernel's pivot tolerance.
    """

    def __init__(
        self,
        session: HighsSession,
        jit: ModuleType,
        row_lower: NDArray[np.float64],
        row_upper: NDArray[np.float64],
    ) -> None:
        from mjtvm.lp.basis_jit import invert  # numba imports: jit is the compiled module

        held = session.held()
        self._jit = jit
        a = held.a
        m, n = a.shape
        self._csc = a
        self._a = (a.indptr, a.indices, a.data)
        self._cost = held.cost
        self._col_lower, self._col_upper = held.col_lower.copy(), held.col_upper.copy()
        self._basic = held.basic.copy()
        self._row, self._col, self._g = held.row_scale, held.col_scale.copy(), held.cost_scale
        upper_of = np.concatenate([held.col_upper, self._row * row_upper])
        lower_of = np.concatenate([held.col_lower, self._row * row_lower])
        # A nonbasic variable sits at one bound; the nearer one (HiGHS puts it exactly there).
        self._at_upper = np.isfinite(upper_of) & (
            ~np.isfinite(lower_of) | (np.abs(held.value - upper_of) < np.abs(held.value - lower_of))
        )
        self._binv: NDArray[np.float64] | None = np.empty((m, m))
        if not invert(*self._a, self._basic, self._binv):
            raise ValueError("singular basis")
        self._value = np.empty(n + m)
        self._y = np.empty(m)
        self._x_b = np.empty(m)
        self._d = np.empty(n + m)
        self._fresh = True  # the first re-solve computes the values and duals afresh
        self.iterations = 0  #: dual simplex iterations of the last `solve()`

    def basis(self) -> WarmBasis:
        """A copy of the current basis (optimal for the last `solve()`), for a later
        `set_column()` to start from."""
        assert self._binv is not None
        return WarmBasis(self._basic.copy(), self._at_upper.copy(), self._binv.copy())

    def set_column(self, column: HeldColumn, others: Sequence[WarmBasis] = ()) -> bool:
        """Take the LP with one column as [`HighsSession.column_as_held()`][mjtvm.lp.highs.HighsSession.column_as_held]
        gives it (the LP HiGHS would hold after ``set_column(rescale=True)``), and a basis
        to re-solve it from: the current one, else the one of ``others`` (bases `basis()`
        gave for earlier columns) with the largest relative pivot. A basic column's inverse
        is updated (`replace_column()`); the next `solve()` computes the values and reduced
        costs afresh and gives up unless the basis is dual feasible.

        Where the column is the only costed one and basic, replacing it scales the row
        duals (and so every reduced cost) by ``1 / u_p`` (`column_pivot()`): the basis stays
        dual feasible exactly when ``u_p > 0``; the current basis is kept then, else the
        best of ``others`` with ``u_p > 0``. Returns ``False`` (the object unusable) where
        the chosen basis matrix is singular."""
        from mjtvm.lp.basis_jit import column_pivot, replace_column

        if self._binv is None:
            return False
        j = column.col
        self._csc = merge_columns(self._csc, {j: (column.rows, column.values)})
        self._a = (self._csc.indptr, self._csc.indices, self._csc.data)
        pos = np.flatnonzero(self._basic == j)
        if pos.size and column_pivot(*self._a, j, int(pos[0]), self._binv) <= 0.0:
            best, best_pivot = None, 0.0
            for b in others:
                at = np.flatnonzero(b.basic == j)
                if at.size:
                    pivot = column_pivot(*self._a, j, int(at[0]), b.binv)
                    if pivot > best_pivot:
                        best, best_pivot = b, pivot
            if best is not None:
                self._basic, self._at_upper = best.basic.copy(), best.at_upper.copy()
                self._binv = best.binv.copy()
                pos = np.flatnonzero(self._basic == j)
        if pos.size and not replace_column(*self._a, j, int(pos[0]), self._binv):
            self._binv = None
            return False
        self._col[j] = column.factor
        self._col_lower[j], self._col_upper[j] = column.col_lower, column.col_upper
        self._cost, self._g = column.cost, column.cost_scale
        self._fresh = True
        return True

    def solve(self, row_lower: NDArray[np.float64], row_upper: NDArray[np.float64]) -> LPSolution | None:
        """The optimal solution for these (unscaled) row bounds, unscaled; ``None`` where the
        kernel gave up (then the object is unusable: its basis may be half-updated)."""
        if self._binv is None:
            return None
        lower = np.concatenate([self._col_lower, self._row * row_lower])
        upper = np.concatenate([self._col_upper, self._row * row_upper])
        status, self.iterations = self._jit.resolve(
            *self._a,
            self._cost,
            lower,
            upper,
            self._basic,
            self._at_upper,
            self._binv,
            self._value,
            self._y,
            self._x_b,
            self._d,
            self._fresh,
            FEASIBILITY_TOL,
            self._jit.CAP,
        )
        if status != self._jit.OPTIMAL:
            self._binv = None
            return None
        self._fresh = False
        n = len(self._cost)
        x = self._value[:n]
        g = self._g
        return LPSolution("optimal", self._col * x, float(self._cost @ x) / g, self._row * self._y / g)
