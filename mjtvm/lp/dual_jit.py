r"""A warm bounded dual simplex in numba, for an LP re-solved after its row bounds changed
(the same matrix, the same costs): [`resolve()`][mjtvm.lp.dual_jit.resolve].

Problem 2's LPs of one RVDS vertex differ only in the right-hand side of the balance rows
(``-w_k``, [`StateLPs`][mjtvm.problem2.lps.StateLPs]); from the basis HiGHS left for the
previous one they take 0-12 dual simplex iterations, while a HiGHS ``run()`` costs ~160 us
of per-call set-up (its model checks, its solver initialisation, its KKT check) whatever
the iterations. Here the basis matrix is inverted once (Gauss-Jordan with partial pivoting,
dense, a few hundred rows: [`basis_jit`][mjtvm.lp.basis_jit]) and kept with its basis across the re-solves, each a few
textbook dual simplex iterations (Koberstein 2005, Algorithm 2, with Harris' two-pass ratio
test and exact dual steepest-edge pricing, which the dense inverse gives for free).

The LP is the one HiGHS holds (equilibrated), in HiGHS' form: ``min c^T x`` subject to
``row_lower <= A x <= row_upper`` and ``col_lower <= x <= col_upper``. The variables are the
``n`` columns then the ``m`` row activities ``r = A x`` (the columns of ``[A | -I]``,
``[A | -I] (x, r) = 0``); the row duals ``y = B^{-T} c_B`` have HiGHS' sign (the reduced
costs are ``c - A^T y``). Nothing is returned unless it is verified here: after the last
iteration ``x_B`` and ``y`` are computed afresh from the inverse and must be primal and dual
feasible within the tolerance; any trouble (iteration cap, a tiny pivot, a singular basis,
primal infeasibility: no entering candidate) returns a status other than `OPTIMAL`, and the
caller solves with HiGHS instead. The caller certifies every answer on the unscaled LP as
it certifies HiGHS' ([`Certifier`][mjtvm.lp.certifier.Certifier]).

Imported lazily (numba's import and the kernels' load ~0.5 s; compiled code cached on disk,
``cache=True``), on the batch paths only.
"""

from __future__ import annotations

import numba
import numpy as np

from mjtvm.lp.basis_jit import column_dot, ftran, pivot_update, values_and_duals

__all__ = ["CAP", "INFEASIBLE", "ITERATIONS", "NUMERICS", "OPTIMAL", "SINGULAR", "resolve"]

OPTIMAL = 0
"""Status: optimal, verified primal and dual feasible from a fresh solve with the inverse."""
INFEASIBLE = 1
"""Status: a row is infeasible and no nonbasic variable can enter (the LP is infeasible: the
caller asks HiGHS, which gives the Farkas multipliers)."""
ITERATIONS = 2
"""Status: the iteration cap was reached."""
SINGULAR = 3
"""Status: the basis matrix is singular (or a pivot below the pivot tolerance)."""
NUMERICS = 4
"""Status: the basis did not start dual feasible, or the final check failed."""

CAP = 50  #: dual simplex iterations per re-solve at most
_PIVOT_TOL = 1e-9  # a pivot row entry smaller than this (relative to the row's largest) cannot enter


@numba.njit(cache=True)
def resolve(
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    cost: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    basic: np.ndarray,
    at_upper: np.ndarray,
    binv: np.ndarray,
    value: np.ndarray,
    y: np.ndarray,
    x_b: np.ndarray,
    d: np.ndarray,
    fresh: bool,
    tol: float,
    cap: int,
) -> tuple[int, int]:
    """Re-solve from the basis ``basic`` (its inverse ``binv``) after bounds changed.

    Parameters
    ----------
    indptr, indices, data
        ``A`` (``(m, n)``), CSC.
    cost
        ``(n,)`` costs (the row activities cost 0).
    lower, upper
        ``(n + m,)`` bounds of the columns, then of the row activities (``+-inf`` where none).
    basic
        ``(m,)`` the basic variables (``>= n``: a row activity); updated in place.
    at_upper
        ``(n + m,)`` bool: a nonbasic variable is at its upper bound (else at its lower bound,
        at 0 where it has none; ignored for basic ones); updated in place.
    binv
        ``(m, m)`` the inverse of the basis matrix
        ([`invert()`][mjtvm.lp.basis_jit.invert]); updated in place.
    value, y
        ``(n + m,)`` and ``(m,)``: the variables' values and the row duals, written; kept
        by the caller between re-solves of one basis.
    x_b, d
        ``(m,)`` and ``(n + m,)``: the basic variables' values and the reduced costs, kept
        by the caller between re-solves (only the values of nonbasic variables whose bounds
        moved are then sent through the inverse: ``m`` flops each).
    fresh
        Whether ``value``, ``y``, ``x_b`` and ``d`` are to be computed afresh (the first
        re-solve after [`invert()`][mjtvm.lp.basis_jit.invert]), rather than carried over from the last re-solve.
    tol
        The primal and dual feasibility tolerance (HiGHS': 1e-9).
    cap
        Iterations at most.

    Returns
    -------
    (status, iterations)
        `OPTIMAL` or why not (module docstring). Where not optimal, ``basic``, ``at_upper``
        and ``binv`` may have moved and must be rebuilt by the caller.
    """
    m = binv.shape[0]
    n = indptr.shape[0] - 1
    nv = n + m
    isbasic = np.zeros(nv, dtype=np.bool_)
    for p in range(m):
        isbasic[basic[p]] = True
    for j in range(nv):  # nonbasic values at their (new) bounds
        if not isbasic[j]:
            if at_upper[j] and upper[j] < np.inf:
                v = upper[j]
            elif lower[j] > -np.inf:
                v = lower[j]
                at_upper[j] = False
            elif upper[j] < np.inf:
                v = upper[j]
                at_upper[j] = True
            else:
                v = 0.0
            if not fresh and v != value[j]:  # x_B -= B^{-1} a_j (v - old)
                step = v - value[j]
                if j >= n:
                    for p in range(m):
                        x_b[p] += step * binv[p, j - n]
                else:
                    for t in range(indptr[j], indptr[j + 1]):
                        k, a = indices[t], data[t]
                        for p in range(m):
                            x_b[p] -= step * a * binv[p, k]
            value[j] = v
    if fresh:
        values_and_duals(indptr, indices, data, cost, basic, value, binv, x_b, y)
        for j in range(nv):
            if not isbasic[j]:
                c = cost[j] if j < n else 0.0
                d[j] = c - column_dot(indptr, indices, data, n, j, y)
                if not _dual_ok(d[j], lower[j], upper[j], at_upper[j], tol):
                    return NUMERICS, 0
    alpha_r = np.zeros(nv)
    col = np.zeros(m)
    it = 0
    while True:
        # Pricing: the most infeasible basic variable in dual steepest-edge measure.
        r, score = -1, 0.0
        for p in range(m):
            j = basic[p]
            v = x_b[p]
            inf = 0.0
            if v < lower[j] - tol:
                inf = lower[j] - v
            elif v > upper[j] + tol:
                inf = v - upper[j]
            if inf > 0.0:
                w = 0.0
                for i in range(m):
                    w += binv[p, i] * binv[p, i]
                s = inf * inf / w
                if s > score:
                    r, score = p, s
        if r < 0:
            break
        if it >= cap:
            return ITERATIONS, it
        leave = basic[r]
        to_lower = x_b[r] < lower[leave]
        delta = x_b[r] - (lower[leave] if to_lower else upper[leave])
        # The pivot row alpha_r = e_r^T B^{-1} [A | -I] over the nonbasic variables.
        big = 0.0
        for j in range(nv):
            if isbasic[j] or lower[j] == upper[j]:
                alpha_r[j] = 0.0
            else:
                a = column_dot(indptr, indices, data, n, j, binv[r])
                alpha_r[j] = a
                if abs(a) > big:
                    big = abs(a)
        # Harris' ratio test: the largest step keeping every reduced cost within tol of
        # feasible, then among the candidates within it the largest pivot.
        piv_tol = _PIVOT_TOL * max(big, 1.0)
        bound = np.inf
        for j in range(nv):
            a = -alpha_r[j] if to_lower else alpha_r[j]
            if _eligible(a, lower[j], upper[j], at_upper[j], piv_tol):
                t = (d[j] + (tol if a > 0.0 else -tol)) / a
                if t < bound:
                    bound = t
        if bound == np.inf:
            return INFEASIBLE, it
        q, best = -1, 0.0
        for j in range(nv):
            a = -alpha_r[j] if to_lower else alpha_r[j]
            if _eligible(a, lower[j], upper[j], at_upper[j], piv_tol) and d[j] / a <= bound:
                if abs(a) > best:
                    q, best = j, abs(a)
        if q < 0:
            return NUMERICS, it
        a_q = -alpha_r[q] if to_lower else alpha_r[q]
        if d[q] / a_q < 0.0:  # within tol of infeasible: step 0 (the reduced cost taken as 0)
            d[q] = 0.0
        theta_d = d[q] / alpha_r[q]
        # FTRAN: B^{-1} a_q.
        ftran(indptr, indices, data, n, q, binv, col)
        pivot = col[r]
        if abs(pivot) <= piv_tol or abs(pivot - alpha_r[q]) > 1e-7 * max(1.0, abs(pivot)):
            return NUMERICS, it
        theta_p = delta / pivot
        for p in range(m):
            x_b[p] -= theta_p * col[p]
        entering_value = value[q] + theta_p
        for j in range(nv):
            if not isbasic[j] and alpha_r[j] != 0.0:
                d[j] -= theta_d * alpha_r[j]
        d[q] = 0.0
        d[leave] = -theta_d
        value[leave] = lower[leave] if to_lower else upper[leave]
        at_upper[leave] = not to_lower
        isbasic[leave], isbasic[q] = False, True
        basic[r] = q
        x_b[r] = entering_value
        pivot_update(binv, col, r)  # the inverse's update: one Gauss-Jordan step
        it += 1
    # Verified: the basic values within their bounds and [A | -I] (x, r) = 0 to round-off (a
    # residual check, nnz flops), else recomputed afresh from the inverse once; then the row
    # duals afresh (B^{-T} c_B) and every reduced cost feasible within tol.
    for p in range(m):
        value[basic[p]] = x_b[p]
    if not _primal_ok(indptr, indices, data, basic, value, lower, upper, tol):
        values_and_duals(indptr, indices, data, cost, basic, value, binv, x_b, y)
        for p in range(m):
            value[basic[p]] = x_b[p]
        if not _primal_ok(indptr, indices, data, basic, value, lower, upper, tol):
            return NUMERICS, it
    y[:] = 0.0
    for p in range(m):
        j = basic[p]
        cb = cost[j] if j < n else 0.0
        if cb != 0.0:
            for i in range(m):
                y[i] += cb * binv[p, i]
    for j in range(nv):
        c = cost[j] if j < n else 0.0
        dj = c - column_dot(indptr, indices, data, n, j, y)
        if isbasic[j]:
            if abs(dj) > tol:
                return NUMERICS, it
            d[j] = 0.0
        else:
            if not _dual_ok(dj, lower[j], upper[j], at_upper[j], tol):
                return NUMERICS, it
            d[j] = dj
    return OPTIMAL, it


@numba.njit(cache=True)
def _primal_ok(indptr, indices, data, basic, value, lower, upper, tol):  # type: ignore[no-untyped-def]
    """Whether the basic values are within their bounds (``tol``) and the rows' residuals
    ``|A x - r|`` within ``tol`` of the magnitudes they are computed from."""
    n = indptr.shape[0] - 1
    m = basic.shape[0]
    for p in range(m):
        j = basic[p]
        if value[j] < lower[j] - tol or value[j] > upper[j] + tol:
            return False
    res = np.zeros(m)
    mag = np.zeros(m)
    for j in range(n):
        v = value[j]
        if v != 0.0:
            for t in range(indptr[j], indptr[j + 1]):
                res[indices[t]] += data[t] * v
                mag[indices[t]] += abs(data[t] * v)
    for i in range(m):
        if abs(res[i] - value[n + i]) > tol * max(1.0, mag[i]):
            return False
    return True


@numba.njit(cache=True)
def _dual_ok(d, lower, upper, at_upper, tol):  # type: ignore[no-untyped-def]
    """Whether a nonbasic variable's reduced cost ``d`` is feasible within ``tol``."""
    if lower == upper:
        return True
    if at_upper and upper < np.inf:
        return d <= tol
    if lower > -np.inf:
        return d >= -tol
    if upper < np.inf:
        return d <= tol
    return abs(d) <= tol


@numba.njit(cache=True)
def _eligible(a, lower, upper, at_upper, piv_tol):  # type: ignore[no-untyped-def]
    """Whether a nonbasic variable with (signed) pivot row entry ``a`` may enter."""
    if lower == upper:
        return False
    free = lower == -np.inf and upper == np.inf
    if free:
        return abs(a) > piv_tol
    if (at_upper and upper < np.inf) or lower == -np.inf:
        return a < -piv_tol
    return a > piv_tol
