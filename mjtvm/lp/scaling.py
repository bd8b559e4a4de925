r"""Equilibration of an LP by powers of 2 (a documented decision: docs/result-format.md, Solver handling).

Both backends see the LP after [`equilibrate()`][mjtvm.lp.scaling.equilibrate] -- rows and columns multiplied by powers
of 2 (so the scaling itself is exact) chosen by mean-of-logs then Ruiz passes over
``|[A | b]|``, the right-hand sides taking part (their factor pinned at 1) so that a change
of force or length unit, which multiplies the solution, is undone too. Solutions,
objectives and duals are unscaled ([`unscale()`][mjtvm.lp.scaling.unscale]) before they are returned.
Coefficients are dropped only when they are round-off: in the equilibrated LP, at most
[`DROP_REL`][mjtvm.lp.lp.DROP_REL] times the largest entry of their row, of their column, or 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from types import ModuleType
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.csc import Csc, as_csc
from mjtvm.lp.lp import DROP_REL, LinearProgram, LPSolution

if TYPE_CHECKING:
    import scipy.sparse as sp

__all__ = [
    "ScaledMatrix",
    "Scaling",
    "column_factor",
    "cost_scale",
    "equilibrate",
    "factor_of_largest",
    "lp_scaling",
    "pow2",
    "scale_lp",
    "unscale",
]

_MEAN_PASSES = 8  # mean-of-logs passes before Ruiz's
_MAX_LOG2 = 400.0  # factors are clipped to [2^-400, 2^400]
_PASSES = 64  # Ruiz passes at most; each halves the remaining log2 imbalance (1e12 ~ 2^40)


@dataclass(frozen=True, eq=False)
class Scaling:
    r"""Powers of 2 that equilibrate an LP: ``A_s = diag(row) A diag(col)``, ``x = col * x_s``.

    Attributes
    ----------
    row
        ``(m,)`` row factors (row bounds are multiplied by them).
    col
        ``(n,)`` column factors (column bounds are divided by them).
    cost
        The factor ``g`` of the scaled costs ``g * col * c``.
    """

    row: NDArray[np.float64]
    col: NDArray[np.float64]
    cost: float = 1.0


def pow2(x: NDArray[np.float64] | float) -> Any:
    """The power(s) of 2 nearest to ``x`` in log2."""
    return np.exp2(np.round(np.log2(x)))


def equilibrate(
    a: Csc | sp.spmatrix,
    *,
    rhs: NDArray[np.float64] | None = None,
    passes: int = _PASSES,
    jit: ModuleType | None = None,
) -> Scaling:
    r"""Row and column powers of 2 bringing the entries of ``|[A | rhs]|`` close to 1.

    In log2 (any magnitude within floating point is fine): first ``_MEAN_PASSES``
    alternating passes setting each row's and column's factor to minus the mean of its
    logs (Curtis and Reid's least-squares scaling), then Ruiz passes, each dividing every
    row, then every column, by the square root of its largest magnitude, until the factors
    move by less than a quarter power of 2; then rounded to powers of 2 (exact). ``rhs``
    (``(m,)``, the magnitudes of the row bounds; infinite or zero entries, and rows without
    coefficients, ignored) takes part as one more column whose factor is pinned at 1, so
    that the bounds, hence the solution, come out ~1 too: a state in mN and rad/h gets the
    same scaled LP as in N and rad/s, up to the power-of-2 rounding.

    Parameters
    ----------
    a
        ``(m, n)`` constraint matrix.
    rhs
        ``(m,)`` magnitudes of the right-hand sides, or ``None``.
    jit
        [`scaling_jit`][mjtvm.lp.scaling_jit] (the batch paths): the same passes in numba,
        the same factors bit for bit.

    Returns
    -------
    Scaling
        With ``cost = 1`` (see [`cost_scale()`][mjtvm.lp.scaling.cost_scale]).
    """
    n = a.shape[1]
    e = _log_entries(a, rhs)
    rho, kappa = _mean_of_logs(e, jit)
    rho, kappa = _ruiz_passes(e, rho, kappa, passes, jit)
    # Powers of 2: the scaling is exact. Clipped at 2^+-400 (a subnormal 1e-300 beside 1 in
    # a fuzzed state drove factors past 2^1024, i.e. inf): what is still out of HiGHS' range
    # after that is reported by the session (_check_magnitudes), never silently dropped.
    rho = np.clip(np.round(rho), -_MAX_LOG2, _MAX_LOG2)
    kappa = np.clip(np.round(kappa), -_MAX_LOG2, _MAX_LOG2)
    return Scaling(np.exp2(rho), np.exp2(kappa[:n]), 1.0)


class _LogEntries(NamedTuple):
    """The non-zero entries of ``|[A | rhs]|`` in log2, in column-major order (the
    right-hand side last, as column ``n``), with their counts per row and column."""

    rows: NDArray[np.int64]
    cols: NDArray[np.int64]
    logs: NDArray[np.float64]
    m: int
    n: int  #: columns of A; the right-hand side is column n, its factor pinned at 1
    r_counts: NDArray[np.int64]
    c_counts: NDArray[np.int64]


def _log_entries(a: Csc | sp.spmatrix, rhs: NDArray[np.float64] | None) -> _LogEntries:
    """The statistics of [`equilibrate()`][mjtvm.lp.scaling.equilibrate]: the entries of ``|[A | rhs]|`` in log2."""
    m, n = a.shape
    if isinstance(a, Csc):
        csc_in: Any = a
    else:
        import scipy.sparse as sp

        csc_in = a if isinstance(a, sp.csc_matrix) else sp.csc_matrix(a)  # read only: no copy needed
    cols = np.repeat(np.arange(n), np.diff(csc_in.indptr))
    keep = csc_in.data != 0.0
    rows, cols, vals = csc_in.indices[keep], cols[keep], np.abs(csc_in.data[keep])
    has_entries = np.bincount(rows, minlength=m) > 0
    if rhs is not None:
        # The right-hand sides join as a column whose factor stays 1: a row's scale then
        # also brings its bound to ~1, and the columns follow, so that the solution (not
        # only the matrix) is ~1: forces in mN and speeds in rad/h alike. A row without
        # coefficients (0 = 1e-17 of round-off) is left out: scaling it up would make it 0 = 1.
        b = np.abs(np.asarray(rhs, dtype=float))
        ok = np.isfinite(b) & (b > 0.0) & has_entries
        rows = np.concatenate([rows, np.flatnonzero(ok)])
        cols = np.concatenate([cols, np.full(int(ok.sum()), n)])
        vals = np.concatenate([vals, b[ok]])
    r_counts = np.bincount(rows, minlength=m)
    c_counts = np.bincount(cols, minlength=n + 1)
    return _LogEntries(rows, cols, np.log2(vals), m, n, r_counts, c_counts)


def _mean_of_logs(
    e: _LogEntries, jit: ModuleType | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``_MEAN_PASSES`` alternating passes setting each row's, then each column's, log2
    factor to minus the mean of its logs (Curtis and Reid's least squares).

    Ruiz only ever lowers a row's or column's largest entry, so a row [1, 1e-12, ...] whose
    variable of coefficient 1 is itself ~1e-12 (torque rows in units of 1e-12 N m) is a
    Ruiz fixed point; the mean balances them first."""
    rows, cols, logs, m, n = e.rows, e.cols, e.logs, e.m, e.n
    if jit is not None:
        rho, kappa = jit.mean_of_logs(rows, cols, logs, e.r_counts, e.c_counts, _MEAN_PASSES)
        return rho, kappa
    rho, kappa = np.zeros(m), np.zeros(n + 1)
    r_cnt, c_cnt = np.maximum(e.r_counts, 1), np.maximum(e.c_counts, 1)
    for _ in range(_MEAN_PASSES):
        rho = -np.bincount(rows, logs + kappa[cols], minlength=m) / r_cnt
        kappa = -np.bincount(cols, logs + rho[rows], minlength=n + 1) / c_cnt
        kappa[n] = 0.0
    return rho, kappa


def _ruiz_passes(
    e: _LogEntries,
    rho: NDArray[np.float64],
    kappa: NDArray[np.float64],
    passes: int,
    jit: ModuleType | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Ruiz passes from ``(rho, kappa)`` (log2): divide every row, then every column, by
    the square root of its largest magnitude, until the factors move by less than a quarter
    power of 2 (the rounding decides then) or ``passes`` are done.

    The largest entry of every row and column tends to 1. Robust to tiny data entries (a
    1e-12 normal component from the simulator), which a geometric mean would pull towards 1
    at the expense of every other entry."""
    m, n, logs = e.m, e.n, e.logs
    # Column-major order already (CSC input, the right-hand side last); row-major by a
    # stable sort. Plain arrays: scipy's constructors cost more than the passes here.
    order = np.argsort(e.rows, kind="stable")
    r_idx, r_logs, c_idx = e.cols[order], logs[order], e.rows
    r_indptr = np.concatenate([[0], np.cumsum(e.r_counts)])
    c_indptr = np.concatenate([[0], np.cumsum(e.c_counts)])
    if jit is not None:
        rho, kappa = jit.ruiz_passes(r_indptr, r_idx, r_logs, c_indptr, c_idx, logs, rho, kappa, passes)
        return rho, kappa
    r_has, c_has = e.r_counts > 0, e.c_counts > 0
    r_starts, c_starts = r_indptr[:-1][r_has], c_indptr[:-1][c_has]
    for _ in range(passes):
        step = np.zeros(m)
        if r_starts.size:
            step[r_has] = (np.maximum.reduceat(r_logs + kappa[r_idx], r_starts) + rho[r_has]) / 2
        rho = rho - step
        cstep = np.zeros(n + 1)
        if c_starts.size:
            cstep[c_has] = (np.maximum.reduceat(logs + rho[c_idx], c_starts) + kappa[c_has]) / 2
        cstep[n] = 0.0  # the right-hand side's factor is pinned at 1
        kappa = kappa - cstep
        if max(np.max(np.abs(step), initial=0.0), np.max(np.abs(cstep), initial=0.0)) < 0.25:
            break
    return rho, kappa


def column_factor(magnitudes: NDArray[np.float64]) -> float:
    """The power of 2 bringing a column's largest non-zero magnitude to 1 (in log2: no
    overflow for entries near 1e308); 1 if none.

    The largest entry, as in Ruiz's passes, and not a mean over the column: a round-off
    entry (1.7e-18 in the z component of a tangent ``n x t1`` that is exactly 0) would pull
    a mean-based factor up by 1e9, blow the column's genuine entries up to 1e12 beside the
    O(1) rest of their rows, and [`scale_lp()`][mjtvm.lp.scaling.scale_lp]'s round-off rule would then drop those
    rows' genuine entries instead (an S-point's tangential row lost its joint speeds).
    Scaled to a largest entry of 1, round-off stays round-off and is dropped.

    Clipped at 2^+-400 as in [`equilibrate()`][mjtvm.lp.scaling.equilibrate]: a column of subnormals only (a fuzzed
    state, after its row factors) asked for more than 2^1024, and a column holding an
    overflowed entry (inf) for 2^-inf = 0; either made ``inf * 0 = nan`` coefficients and
    bounds in [`set_column()`][mjtvm.lp.highs.HighsSession.set_column]. Clipped, the entries
    still out of HiGHS' range are reported by the session's magnitude check."""
    nz = np.abs(magnitudes[magnitudes != 0.0])
    return factor_of_largest(float(nz.max())) if nz.size else 1.0


def factor_of_largest(big: float) -> float:
    """`column_factor()` of a column whose largest magnitude is ``big > 0`` (float
    arithmetic: a column rewritten for every LP, as in ray shooting, spares its numpy calls)."""
    if math.isnan(big):
        return math.nan  # a nan entry: the session's finiteness check reports it
    if big == math.inf:
        return math.ldexp(1.0, -int(_MAX_LOG2))
    return math.ldexp(1.0, int(min(max(round(-math.log2(big)), -_MAX_LOG2), _MAX_LOG2)))


def cost_scale(c: NDArray[np.float64], col: NDArray[np.float64]) -> float:
    """The power of 2 bringing the largest scaled cost ``|col * c|`` to about 1 (1 when c = 0)."""
    prod = np.abs(col * c)
    big = float(prod.max()) if prod.size else 0.0
    return _pow2_float(1.0 / big) if big > 0.0 and math.isfinite(big) else 1.0


def _pow2_float(x: float) -> float:
    """[`pow2()`][mjtvm.lp.scaling.pow2] of one float ``x > 0`` in float arithmetic (a session rescales a column LP
    after LP, where numpy's scalar calls cost more than the rest): ``inf`` past 2^1023, as
    ``np.exp2``."""
    if x == math.inf:
        return math.inf
    k = round(math.log2(x))
    return math.ldexp(1.0, k) if k < 1024 else math.inf


def lp_scaling(lp: LinearProgram) -> Scaling:
    """[`equilibrate()`][mjtvm.lp.scaling.equilibrate] on ``lp`` (its finite row bounds as the right-hand side), with the cost factor."""
    rhs = np.fmax(
        np.where(np.isfinite(lp.row_lower), np.abs(lp.row_lower), 0.0),
        np.where(np.isfinite(lp.row_upper), np.abs(lp.row_upper), 0.0),
    )
    s = equilibrate(lp.A, rhs=rhs)
    return replace(s, cost=cost_scale(lp.c, s.col))


def scale_lp(lp: LinearProgram, s: Scaling) -> LinearProgram:
    """The equilibrated LP ``(g col c, diag(row) A diag(col), row * bounds, bounds / col)``,
    round-off dropped (module docstring)."""
    import scipy.sparse as sp

    a = lp.A.to_scipy() if isinstance(lp.A, Csc) else sp.csc_matrix(lp.A)
    a.sum_duplicates()
    counts = np.diff(a.indptr)
    cols = np.repeat(np.arange(a.shape[1]), counts)
    data = a.data * s.row[a.indices] * s.col[cols]
    mag = np.abs(data)
    row_max = np.zeros(a.shape[0])
    np.maximum.at(row_max, a.indices, mag)
    col_max = np.zeros(a.shape[1])
    np.maximum.at(col_max, cols, mag)
    # In the equilibrated LP (rows, columns and solution ~1) an entry at most DROP_REL times
    # the largest of its row or of its column, or than 1, changes no row by more than
    # round-off; HiGHS could not hold it anyway (its smallest value is 1e-12).
    ref = np.maximum(np.maximum(row_max[a.indices], col_max[cols]), 1.0)
    keep = (mag > DROP_REL * ref) & (data != 0.0)
    if keep.all():
        scaled = sp.csc_matrix((data, a.indices.copy(), a.indptr.copy()), shape=a.shape)
    else:
        scaled = sp.csc_matrix((data[keep], (a.indices[keep], cols[keep])), shape=a.shape)
    with np.errstate(invalid="ignore"):  # inf * positive stays inf
        return LinearProgram(
            s.cost * s.col * np.asarray(lp.c, dtype=float),
            scaled,
            s.row * lp.row_lower,
            s.row * lp.row_upper,
            lp.col_lower / s.col,
            lp.col_upper / s.col,
        )


def unscale(sol: LPSolution, s: Scaling) -> LPSolution:
    r"""The solution of the original LP from that of [`scale_lp()`][mjtvm.lp.scaling.scale_lp]'s: ``x = col x_s``,
    objective ``/ g`` and row duals ``row y_s / g`` (from ``g col c = col A^T row y_s``)."""
    if sol.status != "optimal" or sol.x is None:
        return sol
    y = None if sol.row_dual is None else s.row * sol.row_dual / s.cost
    obj = None if sol.objective is None else sol.objective / s.cost
    return LPSolution("optimal", s.col * sol.x, obj, y)


class ScaledMatrix:
    """``diag(row) A diag(col)`` of one state, computed once, and the scaled ``[A | a]`` of each
    alpha column ``a`` with [`scale_lp()`][mjtvm.lp.scaling.scale_lp]'s round-off rule (an entry at
    most DROP_REL times the largest of its row, of its column, or 1 is dropped; the rows'
    largest entries include the alpha column's)."""

    def __init__(self, a: Csc | sp.csc_matrix, s: Scaling) -> None:
        a = as_csc(a)  # canonical (the assembly's matrix is already)
        m, n = a.shape
        self.shape = (m, n)
        self.indptr, self.indices = a.indptr, a.indices
        self.cols = np.repeat(np.arange(n), np.diff(a.indptr))
        self.data = a.data * s.row[a.indices] * s.col[self.cols]
        self.mag = np.abs(self.data)
        self.row_max = np.zeros(m)
        np.maximum.at(self.row_max, a.indices, self.mag)
        col_max = np.zeros(n)
        np.maximum.at(col_max, self.cols, self.mag)
        self.col_max_at = col_max[self.cols]
        self.row = s.row

    def with_column(self, rows: NDArray[np.int64], values: NDArray[np.float64], factor: float) -> Csc:
        """The scaled ``[A | a]`` with ``a[rows] = values`` (sorted rows, non-zero values)."""
        m, n = self.shape
        data_a = values * self.row[rows] * factor
        mag_a = np.abs(data_a)
        row_max = self.row_max.copy()
        np.maximum.at(row_max, rows, mag_a)
        ref = np.maximum(np.maximum(row_max[self.indices], self.col_max_at), 1.0)
        keep = (self.mag > DROP_REL * ref) & (self.data != 0.0)
        ref_a = np.maximum(np.maximum(row_max[rows], mag_a.max(initial=0.0)), 1.0)
        keep_a = (mag_a > DROP_REL * ref_a) & (data_a != 0.0)
        counts = np.append(np.bincount(self.cols[keep], minlength=n), np.count_nonzero(keep_a))
        indptr = np.concatenate([[0], np.cumsum(counts)]).astype(self.indptr.dtype)
        data = np.concatenate([self.data[keep], data_a[keep_a]])
        indices = np.concatenate([self.indices[keep], rows[keep_a]]).astype(self.indices.dtype)
        return Csc(data, indices, indptr, (m, n + 1))
