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

from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.highs import HighsSession
from mjtvm.lp.lp import FEASIBILITY_TOL, LPSolution

__all__ = ["WarmRows", "kernels"]


def kernels() -> ModuleType | None:
    """`mjtvm.lp.dual_jit` (imported on first use: numba's import and the cached kernels'
    load, ~0.5 s), or ``None`` where numba does not import."""
    try:
        from mjtvm.lp import dual_jit
    except ImportError:
        return None
    return dual_jit


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
        self._a = (a.indptr, a.indices, a.data)
        self._cost = held.cost
        self._col_lower, self._col_upper = held.col_lower, held.col_upper
        self._basic = held.basic.copy()
        self._row, self._col, self._g = held.row_scale, held.col_scale, held.cost_scale
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
