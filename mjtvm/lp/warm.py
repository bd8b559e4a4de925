r"""Re-solves of an LP whose row bounds change, and one of whose columns may change, from
the basis HiGHS left, in the compiled dual simplex of [`dual_jit`][mjtvm.lp.dual_jit] instead
of another HiGHS ``run()``.

[`WarmRows`][mjtvm.lp.warm.WarmRows] takes the equilibrated LP a
[`HighsSession`][mjtvm.lp.highs.HighsSession] holds and its basis after an optimal solve
([`HighsSession.held()`][mjtvm.lp.highs.HighsSession.held]), inverts the basis matrix once,
and re-solves for new row bounds from its own last basis; the answer is unscaled as the
session's are (``x = col * x_s``, ``y = row * y_s / g``), so that the caller certifies it on
the unscaled LP exactly as it certifies HiGHS'. A column replaced as HiGHS would hold it
([`HighsSession.column_as_held()`][mjtvm.lp.highs.HighsSession.column_as_held]) is taken by
[`WarmRows.set_column()`][mjtvm.lp.warm.WarmRows.set_column], from a dual feasible basis (its
inverse updated by one pivot, not inverted again). Where the kernel gives up (module
[`dual_jit`][mjtvm.lp.dual_jit]) `WarmRows.solve()` returns ``None`` and the caller asks HiGHS.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.held import HeldColumn
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
    column bounds, but for `set_column()`) by the compiled dual simplex, from the
    session's last basis.

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
        self._a = (a.indptr, a.indices, a.data)
        self._cost = held.cost
        self._basic = held.basic.copy()
        self._row, self._col, self._g = held.row_scale, held.col_scale.copy(), held.cost_scale
        upper_of = np.concatenate([held.col_upper, self._row * row_upper])
        lower_of = np.concatenate([held.col_lower, self._row * row_lower])
        # The kernel's bounds, the columns' then the rows' (scaled): kept and overwritten in
        # place by each solve (its rows) and set_column (its column), not built per solve.
        self._lower, self._upper = lower_of, upper_of
        self._n = n
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
        self._capped: tuple[int, float] | None = None  # set_column's cap (column, scaled)
        self.iterations = 0  #: dual simplex iterations of the last `solve()`

    def basis(self) -> WarmBasis:
        """A copy of the current basis (optimal for the last `solve()`), for a later
        `set_column()` to start from."""
        assert self._binv is not None
        return WarmBasis(self._basic.copy(), self._at_upper.copy(), self._binv.copy())

    def set_column(
        self, column: HeldColumn, others: Sequence[WarmBasis] = (), *, cap: float = np.inf
    ) -> bool:
        """Take the LP with one column as [`HighsSession.column_as_held()`][mjtvm.lp.highs.HighsSession.column_as_held]
        gives it (the LP HiGHS would hold after ``set_column(rescale=True)``), and a basis
        to re-solve it from, dual feasible; the next `solve()` computes the values and
        reduced costs afresh and gives up unless the basis is dual feasible.

        Where the column is the only costed one and basic, replacing it scales the row
        duals (and so every reduced cost) by ``1 / u_p`` (`column_pivot()`): the basis stays
        dual feasible exactly when ``u_p > 0``. The current basis is kept then (its inverse
        updated, `replace_column()`), else the latest of ``others`` (bases `basis()` gave
        for earlier columns) with ``u_p > 0``. Where none has, and ``cap`` (unscaled, at
        least the column's optimal value for the LP's answer to stand) is finite: the column
        leaves the basis for the row activity whose swap is the best conditioned, and starts
        nonbasic at ``cap``; every other reduced cost is then 0 and the column's is its cost
        (< 0, at its upper bound: dual feasible). The next `solve()` takes ``cap`` as the
        column's upper bound and gives up if the column ends there; ended basic (or at 0),
        the basis is optimal for the LP without the cap too (the cap binds no basic
        variable's bound and no reduced cost's sign). Returns ``False`` (the object unusable)
        where the chosen basis matrix is singular or no start is found."""
        from mjtvm.lp.basis_jit import column_pivot, replace_column, with_column

        if self._binv is None:
            return False
        j = column.col
        self._a = with_column(*self._a, len(self._row), j, column.rows, column.values)
        n = len(self._cost)
        self._capped = None
        pos = np.flatnonzero(self._basic == j)
        if pos.size and not self._swap_in(j, int(pos[0]), self._binv):
            for b in reversed(others):  # the latest first
                at = np.flatnonzero(b.basic == j)
                # `_swap_in()` on a copy of b's inverse, copied only once u_p > 0 (read only).
                if not at.size or column_pivot(*self._a, j, int(at[0]), b.binv) <= 0.0:
                    continue
                binv = b.binv.copy()
                if replace_column(*self._a, j, int(at[0]), binv):
                    self._basic, self._at_upper, self._binv = b.basic.copy(), b.at_upper.copy(), binv
                    break
            else:
                only = column.cost[j] < 0.0 and np.count_nonzero(column.cost) == 1
                p = int(pos[0])
                i = int(np.argmax(np.abs(self._binv[p])))  # a basic row's activity has 0 there
                if not (only and np.isfinite(cap)) or not replace_column(*self._a, n + i, p, self._binv):
                    self._binv = None
                    return False
                self._basic[p] = n + i
                self._at_upper[j] = True
                self._capped = (j, cap / column.factor)
        self._col[j] = column.factor
        self._lower[j], self._upper[j] = column.col_lower, column.col_upper
        self._cost, self._g = column.cost, column.cost_scale
        self._fresh = True
        return True

    def _swap_in(self, j: int, p: int, binv: NDArray[np.float64]) -> bool:
        """Whether column ``j``, at position ``p`` of the basis of ``binv``, has its new
        entries swapped in with ``u_p > 0`` (`column_pivot()`; ``binv`` updated) rather
        than ``u_p <= 0`` or a singular new basis (``binv`` unchanged)."""
        from mjtvm.lp.basis_jit import column_pivot, replace_column

        return column_pivot(*self._a, j, p, binv) > 0.0 and replace_column(*self._a, j, p, binv)

    def solve(self, row_lower: NDArray[np.float64], row_upper: NDArray[np.float64]) -> LPSolution | None:
        """The optimal solution for these (unscaled) row bounds, unscaled; ``None`` where the
        kernel gave up (then the object is unusable: its basis may be half-updated)."""
        if self._binv is None:
            return None
        n, lower, upper = self._n, self._lower, self._upper
        np.multiply(self._row, row_lower, out=lower[n:])
        np.multiply(self._row, row_upper, out=upper[n:])
        capped, self._capped = self._capped, None
        held_upper = 0.0
        if capped is not None:  # set_column's start: the column at its cap, this solve only
            held_upper = upper[capped[0]]
            upper[capped[0]] = min(held_upper, capped[1])
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
        if capped is not None:
            upper[capped[0]] = held_upper
        if status != self._jit.OPTIMAL or (
            capped is not None and self._at_upper[capped[0]] and capped[0] not in self._basic
        ):  # not optimal, or the cap binds: the LP's optimum may lie beyond it
            self._binv = None
            return None
        self._fresh = False
        x = self._value[:n]
        g = self._g
        y = np.multiply(self._row, self._y)
        y /= g
        return LPSolution("optimal", self._col * x, float(self._cost @ x) / g, y)
