r"""Linear-program backends called through their direct APIs.

A :class:`LinearProgram` is ``min c^T x`` s.t. ``row_lower <= A x <= row_upper``,
``col_lower <= x <= col_upper`` with a sparse CSC ``A``. Two backends:

* ``"highs"`` (default): HiGHS dual simplex through ``highspy``. Simplex returns a
  vertex, so alphas are exact to the solver's feasibility tolerance, infeasible and
  unbounded LPs are certified, and a :class:`HighsSession` re-solves after changing
  one column and some row bounds from the previous basis (the LPs of one state differ
  only there).
* ``"clarabel"``: the Clarabel interior-point solver, used as an independent
  cross-check.

Statuses are ``"optimal"``, ``"infeasible"`` or ``"unbounded"``; anything else
raises :class:`~mjtvm.errors.SolverError`.
"""

from __future__ import annotations

import os
import sys
import threading
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from .errors import SolverError

DROP_TOL = 1e-12  # coefficients at or below this are round-off (see assembly._Coo.add)
_HIGHS_DEFAULTS: dict[str, object] = {"simplex_strategy": 1, "solver": "choose"}

__all__ = ["SOLVERS", "HighsSession", "LPSolution", "LinearProgram", "new_highs", "solve_lp"]

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
    """Status, primal solution (``None`` unless optimal) and objective of an LP."""

    status: LPStatus
    x: NDArray[np.float64] | None
    objective: float | None
    row_dual: NDArray[np.float64] | None = None  #: HiGHS' row duals, when asked for


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
    r"""A HiGHS instance holding one LP, re-solved after small modifications.

    Parameters
    ----------
    lp
        The initial LP.
    """

    def __init__(self, lp: LinearProgram) -> None:
        highspy = _highs()
        self._hs = highspy
        h = new_highs()
        options = {
            "output_flag": False,
            "threads": 1,
            "presolve": "off",  # the LPs are small and re-solved warm: presolve costs more than it saves
            "primal_feasibility_tolerance": FEASIBILITY_TOL,
            "dual_feasibility_tolerance": FEASIBILITY_TOL,
            # HiGHS drops smaller entries with a warning; the assembly drops the same ones.
            "small_matrix_value": DROP_TOL,
        }
        for name, value in options.items():
            if h.setOptionValue(name, value) != highspy.HighsStatus.kOk:
                raise SolverError("highs", f"option {name}={value!r} rejected")
        model = highspy.HighsLp()
        n = lp.A.shape[1]
        model.num_col_ = n
        model.num_row_ = lp.A.shape[0]
        inf = highspy.kHighsInf
        model.col_cost_ = np.asarray(lp.c, dtype=float)
        model.col_lower_ = np.where(np.isfinite(lp.col_lower), lp.col_lower, -inf)
        model.col_upper_ = np.where(np.isfinite(lp.col_upper), lp.col_upper, inf)
        model.row_lower_ = np.where(np.isfinite(lp.row_lower), lp.row_lower, -inf)
        model.row_upper_ = np.where(np.isfinite(lp.row_upper), lp.row_upper, inf)
        a = sp.csc_matrix(lp.A)
        model.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        model.a_matrix_.start_ = a.indptr
        model.a_matrix_.index_ = a.indices
        model.a_matrix_.value_ = a.data
        model.a_matrix_.num_col_ = n
        model.a_matrix_.num_row_ = a.shape[0]
        status = h.passModel(model)
        if status != highspy.HighsStatus.kOk:
            raise SolverError("highs", f"passModel: {status}")
        self.highs = h
        self.num_col = n
        self._options = dict(_HIGHS_DEFAULTS)  # what the retries in solve() restore

    def set_option(self, name: str, value: object) -> None:
        """Set a HiGHS option for this session's solves (kept after :meth:`solve`'s retries)."""
        if self.highs.setOptionValue(name, value) != self._hs.HighsStatus.kOk:
            raise SolverError("highs", f"option {name}={value!r} rejected")
        self._options[name] = value

    def set_column(self, col: int, rows: NDArray[np.int64], values: NDArray[np.float64]) -> None:
        """Overwrite ``A[rows, col]`` (entries outside ``rows`` are left as they are)."""
        change = self.highs.changeCoeff
        for r, v in zip(rows.tolist(), values.tolist()):
            change(r, col, v if abs(v) > DROP_TOL else 0.0)

    def set_row_bounds(
        self, rows: NDArray[np.int64], lower: NDArray[np.float64], upper: NDArray[np.float64]
    ) -> None:
        """Change the bounds of some rows."""
        self.highs.changeRowsBounds(len(rows), np.asarray(rows, dtype=np.int32), lower, upper)

    def set_col_bounds(self, col: int, lower: float, upper: float) -> None:
        """Change one variable's bounds."""
        self.highs.changeColBounds(col, lower, upper)

    def solve(self, *, duals: bool = False) -> LPSolution:
        """Run HiGHS from the current basis and classify the outcome (with the row duals if
        ``duals`` and optimal)."""
        h, ms = self.highs, self._hs.HighsModelStatus
        h.run()
        status = h.getModelStatus()
        # A warm-started dual simplex can stop without a verdict: dual infeasibility
        # (unbounded or infeasible) or, seen on infeasible lift states, "Unknown" with a stuck
        # basis. Settle it from cold starts: dual simplex, primal simplex, interior point (each
        # failed alone on some lift LP that the next one certified); otherwise raise.
        retries: tuple[dict[str, object], ...] = ({}, {"simplex_strategy": 4}, {"solver": "ipm"})
        for options in retries:
            if status not in (ms.kUnboundedOrInfeasible, ms.kUnknown, ms.kSolveError):
                break
            h.clearSolver()
            for name, value in options.items():
                h.setOptionValue(name, value)
            h.run()
            status = h.getModelStatus()
            for name in options:
                h.setOptionValue(name, self._options[name])
        if status == ms.kOptimal:
            sol = h.getSolution()
            y = np.array(sol.row_dual) if duals else None
            return LPSolution("optimal", np.array(sol.col_value), float(h.getObjectiveValue()), y)
        if status == ms.kInfeasible:
            return LPSolution("infeasible", None, None)
        if status == ms.kUnbounded:
            return LPSolution("unbounded", None, None)
        raise SolverError("highs", h.modelStatusToString(status))


# -------------------------------------------------------------------- Clarabel
_CLARABEL_OK = {"Solved": "optimal", "PrimalInfeasible": "infeasible", "DualInfeasible": "unbounded"}


def _solve_clarabel(lp: LinearProgram) -> LPSolution:
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


def solve_lp(lp: LinearProgram, *, solver: str = "highs") -> LPSolution:
    """Solve one LP with the named backend (``"highs"`` or ``"clarabel"``)."""
    if solver == "highs":
        return HighsSession(lp).solve()
    if solver == "clarabel":
        return _solve_clarabel(lp)
    raise ValueError(f"solver: expected one of {SOLVERS}, got {solver!r}")
