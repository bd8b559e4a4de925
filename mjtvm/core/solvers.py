r"""Linear-program backends called through their direct APIs, on equilibrated LPs.

A :class:`LinearProgram` is ``min c^T x`` s.t. ``row_lower <= A x <= row_upper``,
``col_lower <= x <= col_upper`` with a sparse CSC ``A``. Two backends:

* ``"highs"`` (default): HiGHS dual simplex through ``highspy``. Simplex returns a
  vertex, so alphas are exact to the solver's feasibility tolerance, infeasible and
  unbounded LPs are certified, and a :class:`HighsSession` re-solves after changing
  one column and some row bounds from the previous basis (the LPs of one state differ
  only there).
* ``"clarabel"``: the Clarabel interior-point solver, used as an independent
  cross-check and as the fallback when HiGHS cannot settle an LP.

Scaling (a documented decision, issue 12): both backends see the LP after
:func:`equilibrate` -- rows and columns multiplied by powers of 2 (so the scaling itself
is exact) chosen by mean-of-logs then Ruiz passes over ``|[A | b]|``, the right-hand
sides taking part (their factor pinned at 1) so that a change of force or length unit,
which multiplies the solution, is undone too. Problem 2 computes it once per state. The solvers' absolute tolerances (1e-9) then mean the same thing in
every unit system; solutions, objectives and duals are unscaled before they are
returned. Coefficients are dropped only when they are round-off: in the equilibrated LP,
at most :data:`DROP_REL` times the largest entry of their row, of their column, or 1.

HiGHS statuses: ``kWarning`` (e.g. a dropped tiny value) is accepted, ``kError`` from
any call raises :class:`~mjtvm.errors.SolverError`. LP statuses are ``"optimal"``,
``"infeasible"`` or ``"unbounded"``; anything else raises
:class:`~mjtvm.errors.SolverError`. :func:`solve_settled` / :func:`fallback` /
:func:`clarabel_checked` settle an LP across both backends (HiGHS' cold retries, then
Clarabel; Clarabel's verdicts checked by HiGHS and a feasibility re-solve) and return a
:class:`Settled` with a note whenever a backend failed or they disagreed.
"""

from __future__ import annotations

import os
import sys
import threading
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..errors import SolverError

#: Round-off: a product's entry at most DROP_REL times the sum of its terms' magnitudes
#: (assembly), or an equilibrated entry at most DROP_REL times the largest of its row, of its
#: column, or 1 (scale_lp) is dropped.
DROP_REL = 1e-12
_HIGHS_SMALL = 1e-12  # HiGHS' smallest allowed small_matrix_value
_HIGHS_LARGE = 1e15  # HiGHS' large_matrix_value: larger entries are a kError
_HIGHS_DEFAULTS: dict[str, object] = {"simplex_strategy": 1, "solver": "choose"}
_MEAN_PASSES = 8  # mean-of-logs passes before Ruiz's
_PASSES = 64  # Ruiz passes at most; each halves the remaining log2 imbalance (1e12 ~ 2^40)

__all__ = [
    "DROP_REL",
    "SOLVERS",
    "HighsSession",
    "LPSolution",
    "LinearProgram",
    "Scaling",
    "equilibrate",
    "new_highs",
    "solve_lp",
    "solve_settled",
]

SOLVERS = ("highs", "clarabel")
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


# ----------------------------------------------------------------- equilibration
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


def _pow2(x: NDArray[np.float64] | float) -> Any:
    return np.exp2(np.round(np.log2(x)))


def equilibrate(a: sp.spmatrix, *, rhs: NDArray[np.float64] | None = None, passes: int = _PASSES) -> Scaling:
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

    Returns
    -------
    Scaling
        With ``cost = 1`` (see :func:`cost_scale`).
    """
    m, n = a.shape
    csc_in = sp.csc_matrix(a)
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
    n_aug = n + 1
    logs = np.log2(vals)
    # Column-major order already (CSC input, the right-hand side last); row-major by a
    # stable sort. Plain arrays: scipy's constructors cost more than the passes here.
    c_counts = np.bincount(cols, minlength=n_aug)
    order = np.argsort(rows, kind="stable")
    r_counts = np.bincount(rows, minlength=m)
    r_idx, r_logs, c_idx = cols[order], logs[order], rows
    r_indptr = np.concatenate([[0], np.cumsum(r_counts)])
    c_indptr = np.concatenate([[0], np.cumsum(c_counts)])
    rho, kappa = np.zeros(m), np.zeros(n_aug)
    # Start from the mean of the logs (Curtis-Reid's least squares, by alternating passes):
    # Ruiz only ever lowers a row's or column's largest entry, so a row [1, 1e-12, ...] whose
    # variable of coefficient 1 is itself ~1e-12 (torque rows in units of 1e-12 N m) is a
    # Ruiz fixed point; the mean balances them first.
    r_cnt, c_cnt = np.maximum(r_counts, 1), np.maximum(c_counts, 1)
    for _ in range(_MEAN_PASSES):
        rho = -np.bincount(rows, logs + kappa[cols], minlength=m) / r_cnt
        kappa = -np.bincount(cols, logs + rho[rows], minlength=n_aug) / c_cnt
        kappa[n] = 0.0
    r_has, c_has = r_counts > 0, c_counts > 0
    r_starts, c_starts = r_indptr[:-1][r_has], c_indptr[:-1][c_has]
    for _ in range(passes):
        # Ruiz: divide every row, then every column, by the square root of its largest
        # magnitude (in log2); the largest entry of every row and column tends to 1. Robust
        # to tiny data entries (a 1e-12 normal component from the simulator), which a
        # geometric mean would pull towards 1 at the expense of every other entry.
        step = np.zeros(m)
        if r_starts.size:
            step[r_has] = (np.maximum.reduceat(r_logs + kappa[r_idx], r_starts) + rho[r_has]) / 2
        rho = rho - step
        cstep = np.zeros(n_aug)
        if c_starts.size:
            cstep[c_has] = (np.maximum.reduceat(logs + rho[c_idx], c_starts) + kappa[c_has]) / 2
        cstep[n] = 0.0  # the right-hand side's factor is pinned at 1
        kappa = kappa - cstep
        # within a quarter of a power of 2 of the fixed point: the rounding below decides
        if max(np.max(np.abs(step), initial=0.0), np.max(np.abs(cstep), initial=0.0)) < 0.25:
            break
    # Powers of 2: the scaling is exact. Clipped at 2^+-400 (a subnormal 1e-300 beside 1 in
    # a fuzzed state drove factors past 2^1024, i.e. inf): what is still out of HiGHS' range
    # after that is reported by the session (_check_magnitudes), never silently dropped.
    rho = np.clip(np.round(rho), -400.0, 400.0)
    kappa = np.clip(np.round(kappa), -400.0, 400.0)
    return Scaling(np.exp2(rho), np.exp2(kappa[:n]), 1.0)


def column_factor(magnitudes: NDArray[np.float64]) -> float:
    """The power of 2 bringing the geometric mean of a column's largest and smallest
    non-zero magnitudes to 1 (in log2: no overflow for entries near 1e308); 1 if none."""
    nz = np.abs(magnitudes[magnitudes != 0.0])
    if not nz.size:
        return 1.0
    return float(np.exp2(np.round(-(np.log2(nz.min()) + np.log2(nz.max())) / 2)))


def cost_scale(c: NDArray[np.float64], col: NDArray[np.float64]) -> float:
    """The power of 2 bringing the largest scaled cost ``|col * c|`` to about 1 (1 when c = 0)."""
    big = float(np.max(np.abs(col * c), initial=0.0))
    return float(_pow2(1.0 / big)) if big > 0.0 and np.isfinite(big) else 1.0


def lp_scaling(lp: LinearProgram) -> Scaling:
    """:func:`equilibrate` on ``lp`` (its finite row bounds as the right-hand side), with the cost factor."""
    rhs = np.fmax(np.where(np.isfinite(lp.row_lower), np.abs(lp.row_lower), 0.0),
                  np.where(np.isfinite(lp.row_upper), np.abs(lp.row_upper), 0.0))  # fmt: skip
    s = equilibrate(lp.A, rhs=rhs)
    return replace(s, cost=cost_scale(lp.c, s.col))


def scale_lp(lp: LinearProgram, s: Scaling) -> LinearProgram:
    """The equilibrated LP ``(g col c, diag(row) A diag(col), row * bounds, bounds / col)``,
    round-off dropped (module docstring)."""
    a = sp.csc_matrix(lp.A)
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
    r"""The solution of the original LP from that of :func:`scale_lp`'s: ``x = col x_s``,
    objective ``/ g`` and row duals ``row y_s / g`` (from ``g col c = col A^T row y_s``)."""
    if sol.status != "optimal" or sol.x is None:
        return sol
    y = None if sol.row_dual is None else s.row * sol.row_dual / s.cost
    obj = None if sol.objective is None else sol.objective / s.cost
    return LPSolution("optimal", s.col * sol.x, obj, y)


# ----------------------------------------------------------------------- HiGHS
def _highs():  # type: ignore[no-untyped-def]
    import highspy

    return highspy


_FD_LOCK = threading.Lock()


def new_highs():  # type: ignore[no-untyped-def]
    """A new ``highspy.Highs`` whose start-up banner does not reach standard output.

    highspy >= 1.16 writes "Running HiGHS ..." to file descriptor 1 from C++ when the first
    ``Highs`` of a process is constructed, before any option (``output_flag``) can be set;
    that breaks every JSON consumer of ``mjtvm solve``. File descriptor 1 is pointed at
    ``/dev/null`` for the construction only (Python's own buffered output is flushed first,
    so nothing of ours is lost); where descriptors cannot be duplicated it is left alone.
    """
    highspy = _highs()
    with _FD_LOCK:
        try:
            sys.stdout.flush()
        except (OSError, ValueError):  # closed or broken stdout: nothing of ours to keep
            pass
        try:
            saved = os.dup(1)
        except OSError:  # no descriptor 1 at all: nothing to protect
            return highspy.Highs()
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            try:
                os.dup2(devnull, 1)
            finally:
                os.close(devnull)
            return highspy.Highs()
        finally:
            os.dup2(saved, 1)
            os.close(saved)


class HighsSession:
    r"""A HiGHS instance holding one equilibrated LP, re-solved after small modifications.

    Every method takes and returns the LP's own (unscaled) values; the session scales
    them with its :class:`Scaling`. Every HiGHS call's status is checked: ``kWarning`` is
    accepted, ``kError`` raises :class:`~mjtvm.errors.SolverError` naming the call.

    Parameters
    ----------
    lp
        The initial LP.
    scaling
        Precomputed factors (e.g. once per state for Problem 2); default
        :func:`lp_scaling` of ``lp``.
    """

    def __init__(self, lp: LinearProgram, *, scaling: Scaling | None = None) -> None:
        highspy = _highs()
        self._hs = highspy
        s = lp_scaling(lp) if scaling is None else scaling
        self.scaling = s
        self._col = np.array(s.col, dtype=float)  # per-column factors (set_column may change one)
        self._cost = np.array(lp.c, dtype=float)  # unscaled costs, bounds: re-scaled on change
        self._col_lower = np.array(lp.col_lower, dtype=float)
        self._col_upper = np.array(lp.col_upper, dtype=float)
        slp = scale_lp(lp, s)
        h = new_highs()
        self.highs = h
        options = {
            "output_flag": False,
            "threads": 1,
            "presolve": "off",  # the LPs are small and re-solved warm: presolve costs more than it saves
            "primal_feasibility_tolerance": FEASIBILITY_TOL,
            "dual_feasibility_tolerance": FEASIBILITY_TOL,
            # Round-off is dropped by scale_lp; HiGHS must keep every other entry.
            "small_matrix_value": _HIGHS_SMALL,
        }
        for name, value in options.items():
            self._check(h.setOptionValue(name, value), f"option {name}={value!r} rejected")
        a = slp.A
        self._check_magnitudes(a.data, "passModel")
        model = highspy.HighsLp()
        n = a.shape[1]
        model.num_col_ = n
        model.num_row_ = a.shape[0]
        inf = highspy.kHighsInf
        model.col_cost_ = np.asarray(slp.c, dtype=float)
        model.col_lower_ = np.where(np.isfinite(slp.col_lower), slp.col_lower, -inf)
        model.col_upper_ = np.where(np.isfinite(slp.col_upper), slp.col_upper, inf)
        model.row_lower_ = np.where(np.isfinite(slp.row_lower), slp.row_lower, -inf)
        model.row_upper_ = np.where(np.isfinite(slp.row_upper), slp.row_upper, inf)
        model.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        model.a_matrix_.start_ = a.indptr
        model.a_matrix_.index_ = a.indices
        model.a_matrix_.value_ = a.data
        model.a_matrix_.num_col_ = n
        model.a_matrix_.num_row_ = a.shape[0]
        self._check(h.passModel(model), "passModel")
        # Largest scaled magnitude per row: the reference of set_column's round-off drop.
        self._row_max = np.zeros(a.shape[0])
        if a.nnz:
            np.maximum.at(self._row_max, a.indices, np.abs(a.data))
        self.num_col = n
        self._options = dict(_HIGHS_DEFAULTS)  # what the retries in solve() restore

    def _check(self, status: Any, what: str) -> None:
        """kOk and kWarning pass (a warning is HiGHS informing, e.g. of a dropped tiny
        value, which scale_lp has made impossible for data); kError raises."""
        if status == self._hs.HighsStatus.kError:
            raise SolverError("highs", f"{what}: {status}")

    @staticmethod
    def _check_magnitudes(values: NDArray[np.float64], what: str) -> None:
        """HiGHS drops scaled entries below 1e-12 with only a warning (a silent wrong
        answer) and refuses those above 1e15; after equilibration either means data
        spanning more than ~27 orders of magnitude, which is reported instead."""
        mag = np.abs(values[values != 0.0])
        if mag.size and (mag.min() <= _HIGHS_SMALL or mag.max() >= _HIGHS_LARGE):
            raise SolverError(
                "highs",
                f"{what}: an equilibrated coefficient is outside [1e-12, 1e15] "
                f"({mag.min():.3g} .. {mag.max():.3g}): the data span too many orders of magnitude",
            )

    def column_scale(self, col: int) -> float:
        """The factor of column ``col`` (its equilibrated value is ``x[col] / factor``)."""
        return float(self._col[col])

    def set_option(self, name: str, value: object) -> None:
        """Set a HiGHS option for this session's solves (kept after :meth:`solve`'s retries)."""
        self._check(self.highs.setOptionValue(name, value), f"option {name}={value!r} rejected")
        self._options[name] = value

    def set_column(
        self, col: int, rows: NDArray[np.int64], values: NDArray[np.float64], *, rescale: bool = False
    ) -> None:
        """Overwrite ``A[rows, col]`` (entries outside ``rows`` are left as they are).

        With ``rescale``, ``rows`` must hold every non-zero of the column: its factor is
        chosen again from ``values`` (and its bounds and cost re-scaled), so that a column
        1e15 times larger than the first one is as well conditioned.
        """
        rows = np.asarray(rows, dtype=np.int64)
        v = self.scaling.row[rows] * np.asarray(values, dtype=float)
        if rescale:
            nz = np.abs(v[v != 0.0])
            factor = column_factor(nz)
            if factor != self._col[col]:
                self._col[col] = factor
                self._push_col_bounds(col)
                self._push_costs(np.array([col], dtype=np.int32))
        v = v * self._col[col]
        mag = np.abs(v)
        ref = np.maximum(np.maximum(self._row_max[rows], float(mag.max(initial=0.0))), 1.0)
        v[mag <= DROP_REL * ref] = 0.0  # round-off, as in scale_lp
        self._check_magnitudes(v, "changeCoeff")
        change, check = self.highs.changeCoeff, self._check
        for r, x in zip(rows.tolist(), v.tolist()):
            check(change(r, col, x), "changeCoeff")

    def set_row_bounds(
        self, rows: NDArray[np.int64], lower: NDArray[np.float64], upper: NDArray[np.float64]
    ) -> None:
        """Change the bounds of some rows."""
        f = self.scaling.row[rows]
        lo, up = f * np.asarray(lower, dtype=float), f * np.asarray(upper, dtype=float)
        inf = self._hs.kHighsInf
        lo = np.where(np.isfinite(lo), lo, -inf)
        up = np.where(np.isfinite(up), up, inf)
        status = self.highs.changeRowsBounds(len(rows), np.asarray(rows, dtype=np.int32), lo, up)
        self._check(status, "changeRowsBounds")

    def _push_col_bounds(self, col: int) -> None:
        inf = self._hs.kHighsInf
        lo, up = self._col_lower[col] / self._col[col], self._col_upper[col] / self._col[col]
        lo = lo if np.isfinite(lo) else -inf
        up = up if np.isfinite(up) else inf
        self._check(self.highs.changeColBounds(col, lo, up), "changeColBounds")

    def _push_costs(self, cols: NDArray[np.int32]) -> None:
        """Send the scaled costs of ``cols`` (of every column when the cost factor changes:
        a full cost change costs the warm start more)."""
        g = cost_scale(self._cost, self._col)
        if g != self.scaling.cost:
            self.scaling = replace(self.scaling, cost=g)
            cols = np.arange(len(self._cost), dtype=np.int32)
        cols = np.asarray(cols, dtype=np.int32)
        cost = np.ascontiguousarray(g * self._col[cols] * self._cost[cols])
        self._check(self.highs.changeColsCost(len(cols), cols, cost), "changeColsCost")

    def set_col_bounds(self, col: int, lower: float, upper: float) -> None:
        """Change one variable's bounds."""
        self._col_lower[col], self._col_upper[col] = lower, upper
        self._push_col_bounds(col)

    def set_costs(self, cols: NDArray[np.int32], values: NDArray[np.float64]) -> None:
        """Change some costs (the cost factor is chosen again from all of them)."""
        self._cost[np.asarray(cols)] = values
        self._push_costs(np.asarray(cols, dtype=np.int32))

    def _run(self) -> Any:
        """``run`` and the model status; a kError run counts as a solve error (retried)."""
        h, ms = self.highs, self._hs.HighsModelStatus
        if h.run() == self._hs.HighsStatus.kError:
            return ms.kSolveError
        return h.getModelStatus()

    def solve(self, *, duals: bool = False) -> LPSolution:
        """Run HiGHS from the current basis and classify the outcome (with the row duals if
        ``duals`` and optimal), in the LP's own units."""
        h, ms = self.highs, self._hs.HighsModelStatus
        status = self._run()
        # A warm-started dual simplex can stop without a verdict: dual infeasibility
        # (unbounded or infeasible) or, seen on infeasible lift states, "Unknown" with a stuck
        # basis. Settle it from cold starts: dual simplex, primal simplex, interior point (each
        # failed alone on some lift LP that the next one certified); otherwise raise (the
        # callers that can fall back to Clarabel do: solve_settled, tvmmp).
        retries: tuple[dict[str, object], ...] = ({}, {"simplex_strategy": 4}, {"solver": "ipm"})
        for options in retries:
            if status not in (ms.kUnboundedOrInfeasible, ms.kUnknown, ms.kSolveError):
                break
            self._check(h.clearSolver(), "clearSolver")
            for name, value in options.items():
                self._check(h.setOptionValue(name, value), f"option {name}={value!r} rejected")
            status = self._run()
            for name in options:
                self._check(h.setOptionValue(name, self._options[name]), f"option {name} restore")
        if status == ms.kOptimal:
            sol = h.getSolution()
            y = np.array(sol.row_dual) if duals else None
            g = self.scaling.cost
            return LPSolution(
                "optimal",
                self._col * np.array(sol.col_value),
                float(h.getObjectiveValue()) / g,
                None if y is None else self.scaling.row * y / g,
            )
        if status == ms.kInfeasible:
            return LPSolution("infeasible", None, None)
        if status == ms.kUnbounded:
            return LPSolution("unbounded", None, None)
        raise SolverError("highs", h.modelStatusToString(status))


# -------------------------------------------------------------------- Clarabel
_CLARABEL_OK = {"Solved": "optimal", "PrimalInfeasible": "infeasible", "DualInfeasible": "unbounded"}


def _solve_clarabel(lp: LinearProgram) -> LPSolution:
    """Clarabel on ``lp`` as given (callers pass it equilibrated)."""
    import clarabel

    a = sp.csc_matrix(lp.A)
    eq = np.isfinite(lp.row_lower) & np.isfinite(lp.row_upper) & (lp.row_lower == lp.row_upper)
    up = np.isfinite(lp.row_upper) & ~eq
    lo = np.isfinite(lp.row_lower) & ~eq
    n = a.shape[1]
    eye = sp.identity(n, format="csr")
    cu, cl = np.isfinite(lp.col_upper), np.isfinite(lp.col_lower)
    # A x + s = b with s in {0} for equalities, s >= 0 for the rest (Clarabel's form).
    blocks = [a[eq], a[up], -a[lo], eye[cu], -eye[cl]]
    b = np.concatenate(
        [lp.row_upper[eq], lp.row_upper[up], -lp.row_lower[lo], lp.col_upper[cu], -lp.col_lower[cl]]
    )
    big_a = sp.vstack(blocks, format="csc")
    cones = []
    if eq.any():
        cones.append(clarabel.ZeroConeT(int(eq.sum())))
    n_ineq = int(up.sum() + lo.sum() + cu.sum() + cl.sum())
    if n_ineq:
        cones.append(clarabel.NonnegativeConeT(n_ineq))
    p = sp.csc_matrix((n, n))
    c = np.asarray(lp.c, float)
    # Tighter than Clarabel's defaults (1e-8) so that alphas agree with the simplex to ~1e-9.
    # Where that stalls short of them (AlmostSolved, ~1 % of random LPs), solve again at
    # the defaults; any status still not in _CLARABEL_OK is reported as a SolverError.
    name = ""
    for tol in (1e-9, None):
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        if tol is not None:
            settings.tol_gap_abs = settings.tol_gap_rel = tol
            settings.tol_feas = tol
        result = clarabel.DefaultSolver(p, c, big_a, b, cones, settings).solve()
        name = str(result.status).split(".")[-1]
        if name in _CLARABEL_OK:
            break
    if name not in _CLARABEL_OK:
        raise SolverError("clarabel", name)
    status = _CLARABEL_OK[name]
    if status != "optimal":
        return LPSolution(status, None, None)  # type: ignore[arg-type]
    return LPSolution("optimal", np.array(result.x), float(result.obj_val))


def solve_clarabel(lp: LinearProgram, *, scaling: Scaling | None = None) -> LPSolution:
    """Clarabel on the equilibrated ``lp`` (:func:`lp_scaling` unless ``scaling``), unscaled."""
    s = lp_scaling(lp) if scaling is None else scaling
    slp1 = scale_lp(lp, s)
    first = _solve_clarabel(slp1)
    if first.status != "optimal" or first.x is None:
        return first
    # An interior point's "Solved" is not a certificate: on Case 1 in odd units it returned
    # alphas 27 times too large. Every row and bound of the scaled LP must hold to 1e-7
    # (entries ~1), or the answer is refused (callers fall back to HiGHS, noted).
    viol1 = _violation(slp1, first.x)  # reported when the second solve fails
    # It also stops at tolerances relative to the whole LP: where the variables differ by
    # 1e6 in size (a load in mN, speeds in rad/h) alpha was off by up to 1e-3. Solve again
    # scaled by the first solution: every variable ~1 (floored at 2^-10 of the largest, for
    # the ones at 0), every row's largest entry ~1, the objective ~1 (Clarabel's
    # duality-gap test is absolute below 1). Measured on the unit-test states: within 9e-8
    # of HiGHS, against 1e-3 for the first solve. Where that second solve stalls (alpha = 0
    # on a degenerate face, Case 1-S) it is an error. (No retry on the unscaled LP: its
    # "optimal" can be off by 1e-2.)
    xs = np.abs(first.x)
    col = s.col * _pow2(np.maximum(xs, 2.0**-10 * max(float(xs.max()), 1e-300)))
    a = sp.csr_matrix(abs(sp.csr_matrix(lp.A) @ sp.diags(col)))
    row_max = a.max(axis=1).toarray().ravel() if a.shape[1] else np.zeros(a.shape[0])
    row = np.where(row_max > 0, _pow2(1.0 / np.where(row_max > 0, row_max, 1.0)), 1.0)
    s2 = Scaling(row, col, cost_scale(np.asarray(lp.c, dtype=float), col))
    try:
        slp = scale_lp(lp, s2)
        sol = _solve_clarabel(slp)
        obj = 0.0 if sol.objective is None else abs(sol.objective)
        if sol.status == "optimal" and 0.0 < obj < 0.0625:
            s2 = replace(s2, cost=s2.cost * float(_pow2(1.0 / obj)))
            slp = scale_lp(lp, s2)
            sol = _solve_clarabel(slp)
        viol = _violation(slp, sol.x) if sol.status == "optimal" and sol.x is not None else 0.0
        if sol.status != "optimal" or viol > 1e-7:
            raise SolverError("clarabel", f"second solve: {sol.status}, violation {viol:.1e}")
    except SolverError as e:
        # The first answer alone can be 1e-2 off while feasible: not reported (callers
        # fall back to HiGHS, noted).
        raise SolverError("clarabel", f"{e.status}; first solve's violation {viol1:.1e}") from e
    return unscale(sol, s2)


def _violation(lp: LinearProgram, x: NDArray[np.float64]) -> float:
    """Largest violation of ``lp``'s rows and bounds by ``x``."""
    ax = lp.A @ x
    with np.errstate(invalid="ignore"):
        parts = [lp.row_lower - ax, ax - lp.row_upper, lp.col_lower - x, x - lp.col_upper]
    return float(max(np.max(np.nan_to_num(p, nan=0.0, neginf=0.0), initial=0.0) for p in parts))


def solve_lp(lp: LinearProgram, *, solver: str = "highs", scaling: Scaling | None = None) -> LPSolution:
    """Solve one LP with the named backend (``"highs"`` or ``"clarabel"``), equilibrated."""
    if solver == "highs":
        return HighsSession(lp, scaling=scaling).solve()
    if solver == "clarabel":
        return solve_clarabel(lp, scaling=scaling)
    raise ValueError(f"solver: expected one of {SOLVERS}, got {solver!r}")


@dataclass(frozen=True, eq=False)
class Settled:
    """An LP's solution, the backend whose verdict it is, and a note when the backends
    disagreed or one of them failed (``None`` otherwise)."""

    solution: LPSolution
    solver: str
    note: str | None = None


def _feasible_clarabel(lp: LinearProgram, s: Scaling) -> bool:
    """Whether Clarabel finds ``lp``'s constraints feasible (zero cost: no unbounded ray to
    confuse with infeasibility)."""
    zero = replace(lp, c=np.zeros_like(np.asarray(lp.c, dtype=float)))
    return solve_clarabel(zero, scaling=replace(s, cost=1.0)).status == "optimal"


def clarabel_checked(lp: LinearProgram, *, scaling: Scaling | None = None) -> Settled:
    """Clarabel, with a verdict of ``infeasible`` or ``unbounded`` cross-checked before it is
    reported: an interior-point method can mistake one for the other on badly scaled data,
    so a cold HiGHS solve must agree; otherwise a Clarabel feasibility re-solve decides
    between them (and the disagreement is noted); if nothing settles it, SolverError."""
    s = lp_scaling(lp) if scaling is None else scaling
    try:
        sol = solve_clarabel(lp, scaling=s)
    except SolverError as e:  # Clarabel could not settle it: HiGHS, noted
        try:
            rescue = HighsSession(lp, scaling=s).solve()
        except SolverError as e2:
            raise SolverError("clarabel", f"{e.status}; fallback highs: {e2.status}") from e
        return Settled(rescue, "highs", f"clarabel: {e.status}; settled by highs: {rescue.status}")
    if sol.status == "optimal":
        # Near a feasibility limit (a weight within 1e-7 of the largest a hand holds) the
        # interior point can call feasible what the simplex certifies infeasible: a HiGHS
        # solve checks every verdict, and a disagreement is noted (the answer stays
        # Clarabel's, which was asked for).
        try:
            check = HighsSession(lp, scaling=s).solve()
        except SolverError as e:
            return Settled(sol, "clarabel", f"highs could not check it ({e.status})")
        if check.status != "optimal":
            return Settled(sol, "clarabel", f"clarabel: optimal; highs: {check.status}")
        return Settled(sol, "clarabel")
    checked: LPSolution | None = None
    try:
        checked = HighsSession(lp, scaling=s).solve()
    except SolverError as e:
        err = e
    other = checked
    if other is not None and other.status == sol.status:
        return Settled(sol, "clarabel")
    try:
        feasible = _feasible_clarabel(lp, s)
    except SolverError as e3:
        if other is None:
            raise SolverError(
                "clarabel", f"{sol.status}; highs: {err.status}; feasibility re-solve: {e3.status}"
            ) from e3
        return Settled(
            other,
            "highs",
            f"clarabel said {sol.status}, its feasibility re-solve failed ({e3.status}); highs: {other.status}",
        )
    if other is None:
        if feasible == (sol.status == "unbounded"):
            return Settled(
                sol, "clarabel", f"highs failed ({err.status}); clarabel's feasibility re-solve agrees"
            )
        raise SolverError(
            "clarabel", f"{sol.status}, contradicted by its feasibility re-solve; highs: {err.status}"
        ) from err
    if feasible == (other.status != "infeasible"):
        return Settled(
            other,
            "highs",
            f"clarabel said {sol.status}; highs and clarabel's feasibility re-solve: {other.status}",
        )
    raise SolverError("clarabel", f"{sol.status}; highs: {other.status}; feasibility re-solve: {feasible}")


def solve_settled(lp: LinearProgram, *, solver: str = "highs", scaling: Scaling | None = None) -> Settled:
    """One LP settled as :func:`clarabel_checked` (``"clarabel"``) or by HiGHS with its cold
    retries and then Clarabel as the fallback (``"highs"``); SolverError, chained to
    HiGHS' own, only when neither settles it."""
    if solver == "clarabel":
        return clarabel_checked(lp, scaling=scaling)
    if solver != "highs":
        raise ValueError(f"solver: expected one of {SOLVERS}, got {solver!r}")
    try:
        return Settled(HighsSession(lp, scaling=scaling).solve(), "highs")
    except SolverError as e:
        return fallback(lp, e, scaling=scaling)


def fallback(lp: LinearProgram, error: SolverError, *, scaling: Scaling | None = None) -> Settled:
    """After HiGHS failed with ``error``: Clarabel's checked verdict, noted; SolverError
    (chained to ``error``) when Clarabel fails too."""
    s = lp_scaling(lp) if scaling is None else scaling
    try:
        sol = solve_clarabel(lp, scaling=s)
        if sol.status != "optimal":  # an interior-point verdict alone is not enough: re-solve
            feasible = _feasible_clarabel(lp, s)
            if feasible != (sol.status == "unbounded"):
                raise SolverError("clarabel", f"{sol.status}, contradicted by its feasibility re-solve")
    except SolverError as e2:
        raise SolverError("highs", f"{error.status}; fallback clarabel: {e2.status}") from error
    return Settled(sol, "clarabel", f"highs: {error.status}; settled by clarabel: {sol.status}")
