r"""HiGHS through ``highspy``: [`HighsSession`][mjtvm.lp.highs.HighsSession] holds one equilibrated LP and re-solves
it after changing one column and some row bounds from the previous basis (the LPs of one
state differ only there).

HiGHS statuses: ``kWarning`` (e.g. a dropped tiny value) is accepted, ``kError`` from any
call raises [`SolverError`][mjtvm.errors.SolverError]. A ``Highs`` is constructed by
[`new_highs()`][mjtvm.lp.highspy_start.new_highs] (``mjtvm.lp.highspy_start``; importable from here, as
[`observe_runs()`][mjtvm.lp.highspy_start.observe_runs] is).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError, SolverError
from mjtvm.lp.csc import as_csc
from mjtvm.lp.held import HeldColumn, HeldLP, basic_variables, merge_columns
from mjtvm.lp.highspy_start import acquire_highs, give_back, highspy_module, new_highs, observe_runs, ran
from mjtvm.lp.lp import DROP_REL, FEASIBILITY_TOL, LinearProgram, LPSolution
from mjtvm.lp.scaling import Scaling, cost_scale, factor_of_largest, lp_scaling, scale_lp

__all__ = ["HighsSession", "new_highs", "observe_runs"]

_HIGHS_SMALL = 1e-12  # HiGHS' smallest allowed small_matrix_value
_HIGHS_LARGE = 1e15  # HiGHS' large_matrix_value: larger entries are a kError
_HIGHS_DEFAULTS: dict[str, object] = {"simplex_strategy": 1, "solver": "choose"}
#: HiGHS' own defaults of the options a session may choose for itself at construction
#: ([`HighsSession.from_scaled()`][mjtvm.lp.highs.HighsSession.from_scaled]'s ``options``, e.g. Problem 2's): every session sets all
#: of them, so that a ``Highs`` reused from another session ([`HighsSession.release()`][mjtvm.lp.highs.HighsSession.release])
#: solves as a fresh one would.
_TUNABLE_DEFAULTS: dict[str, object] = {"simplex_dual_edge_weight_strategy": -1}


#: HiGHS' ``threads`` option of every session: 1 (the LPs are small and serial; no scheduler
#: threads to inherit across a fork), unless this process's HiGHS task scheduler was already
#: started with another count by someone else (cvxpy's or a user's own ``highspy.Highs`` with
#: HiGHS' default, ``threads = 0``): HiGHS then refuses every ``run`` with ``threads = 1``
#: (kError), and ``threads = 0`` takes the scheduler as it is (see `HighsSession._run()`).
_THREADS = [1]


class HighsSession:
    r"""A HiGHS instance holding one equilibrated LP, re-solved after small modifications.

    Every method takes and returns the LP's own (unscaled) values; the session scales
    them with its [`Scaling`][mjtvm.lp.scaling.Scaling]. Every HiGHS call's status is checked: ``kWarning`` is
    accepted, ``kError`` raises [`SolverError`][mjtvm.errors.SolverError] naming the call.

    Parameters
    ----------
    lp
        The initial LP.
    scaling
        Precomputed factors (e.g. once per state for Problem 2); default
        [`lp_scaling()`][mjtvm.lp.scaling.lp_scaling] of ``lp``.
    """

    def __init__(self, lp: LinearProgram, *, scaling: Scaling | None = None) -> None:
        s = lp_scaling(lp) if scaling is None else scaling
        self._load(scale_lp(lp, s), s, lp.c, lp.col_lower, lp.col_upper, new_highs(), {})

    @classmethod
    def from_scaled(
        cls,
        scaled: LinearProgram,
        scaling: Scaling,
        cost: NDArray[np.float64],
        col_lower: NDArray[np.float64],
        col_upper: NDArray[np.float64],
        *,
        options: Mapping[str, object] | None = None,
    ) -> HighsSession:
        """The session of an LP whose ``scale_lp(lp, scaling)`` the caller has already (the
        same arrays: Problem 2 builds it from a per-state cache, without the sparse copies),
        given with the LP's own costs and column bounds. Its HiGHS instance may be one a
        finished session gave back (`release()`). ``options`` (names of
        ``_TUNABLE_DEFAULTS`` only) are this session's, kept through `solve()`'s retries."""
        self = cls.__new__(cls)
        self._load(scaled, scaling, cost, col_lower, col_upper, acquire_highs(), options or {})
        return self

    def _load(
        self,
        slp: LinearProgram,
        s: Scaling,
        cost: NDArray[np.float64],
        col_lower: NDArray[np.float64],
        col_upper: NDArray[np.float64],
        h: Any,
        tuned: Mapping[str, object],
    ) -> None:
        """Pass the equilibrated LP ``slp`` (factors ``s``) to the HiGHS instance ``h``, with
        the session's options ``tuned`` (over ``_TUNABLE_DEFAULTS``)."""
        if not set(tuned) <= set(_TUNABLE_DEFAULTS):
            raise ParamError(
                "options", f"only {sorted(_TUNABLE_DEFAULTS)} may be chosen, got {sorted(tuned)}", tuned
            )
        highspy = highspy_module()
        self._hs = highspy
        self._error = highspy.HighsStatus.kError
        self.scaling = s
        self._col = np.array(s.col, dtype=float)  # per-column factors (set_column may change one)
        self._cost = np.array(cost, dtype=float)  # unscaled costs, bounds: re-scaled on change
        self._col_lower = np.array(col_lower, dtype=float)
        self._col_upper = np.array(col_upper, dtype=float)
        self.highs = h
        options = {
            "output_flag": False,
            "threads": _THREADS[0],
            "presolve": "off",  # the LPs are small and re-solved warm: presolve costs more than it saves
            "primal_feasibility_tolerance": FEASIBILITY_TOL,
            "dual_feasibility_tolerance": FEASIBILITY_TOL,
            # Round-off is dropped by scale_lp; HiGHS must keep every other entry.
            "small_matrix_value": _HIGHS_SMALL,
        }
        session_options = {**_HIGHS_DEFAULTS, **_TUNABLE_DEFAULTS, **tuned}
        for name, value in {**options, **session_options}.items():
            self._check(h.setOptionValue(name, value), f"option {name}={value!r} rejected")
        a = slp.A
        self._check_magnitudes(a.data, "passModel")
        m, n = a.shape
        inf = highspy.kHighsInf

        def finite(x: NDArray[np.float64], default: float) -> NDArray[np.float64]:
            return np.ascontiguousarray(np.where(np.isfinite(x), x, default), dtype=float)

        # The flat passModel: filling a highspy.HighsLp field by field costs 60 us (each
        # field a conversion), more than HiGHS' own copy of the model.
        status = h.passModel(
            n,
            m,
            a.nnz,
            int(highspy.MatrixFormat.kColwise),
            int(highspy.ObjSense.kMinimize),
            0.0,
            np.ascontiguousarray(slp.c, dtype=float),
            finite(slp.col_lower, -inf),
            finite(slp.col_upper, inf),
            finite(slp.row_lower, -inf),
            finite(slp.row_upper, inf),
            np.ascontiguousarray(a.indptr, dtype=np.int32),
            np.ascontiguousarray(a.indices, dtype=np.int32),
            np.ascontiguousarray(a.data, dtype=float),
            np.zeros(n, dtype=np.int32),  # every column continuous (HiGHS reads n entries: never empty)
        )
        self._check(status, "passModel")
        self._held = slp.A  # the matrix HiGHS holds (held()), with set_column's writes:
        self._written: dict[int, tuple[list[int], NDArray[np.float64]]] = {}
        self._sent_cost = np.array(slp.c, dtype=float)  # the scaled costs HiGHS holds
        # Largest scaled magnitude per row: the reference of set_column's round-off drop.
        self._row_max = np.zeros(a.shape[0])
        if a.nnz:
            np.maximum.at(self._row_max, a.indices, np.abs(a.data))
        self.num_col = n
        self._rows_key: bytes | None = None  # set_column's last rows, and what it keeps of them
        self._rows_of: tuple[NDArray[np.float64], NDArray[np.float64], list[int]] = (
            np.zeros(0),
            np.zeros(0),
            [],
        )
        self._options = session_options  # what the retries in solve() restore

    def release(self) -> None:
        """Give the HiGHS instance back for the next session of this process (the session is
        unusable afterwards). Only for a session without `set_option()` (the options given
        at construction are set again by every session) whose last call returned normally."""
        h, self.highs = self.highs, None
        if h is not None:
            give_back(h)

    def _check(self, status: Any, what: str) -> None:
        """kOk and kWarning pass (a warning is HiGHS informing, e.g. of a dropped tiny
        value, which scale_lp has made impossible for data); kError raises."""
        if status == self._error:
            raise SolverError("highs", f"{what}: {status}")

    @staticmethod
    def _check_magnitudes(values: NDArray[np.float64], what: str) -> None:
        """HiGHS drops scaled entries below 1e-12 with only a warning (a silent wrong
        answer) and refuses those above 1e15; after equilibration either means data
        spanning more than ~27 orders of magnitude, which is reported instead."""
        mag = np.abs(values[values != 0.0])
        if mag.size:
            HighsSession._check_range(float(mag.min()), float(mag.max()), what)

    @staticmethod
    def _check_range(smallest: float, largest: float, what: str) -> None:
        """`_check_magnitudes()` from the smallest and largest non-zero magnitudes."""
        if smallest <= _HIGHS_SMALL or largest >= _HIGHS_LARGE:
            raise SolverError(
                "highs",
                f"{what}: an equilibrated coefficient is outside [1e-12, 1e15] "
                f"({smallest:.3g} .. {largest:.3g}): the data span too many orders of magnitude",
            )

    def column_scale(self, col: int) -> float:
        """The factor of column ``col`` (its equilibrated value is ``x[col] / factor``)."""
        return float(self._col[col])

    def set_option(self, name: str, value: object) -> None:
        """Set a HiGHS option for this session's solves (kept after `solve()`'s retries)."""
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
        factor, row_list, v = self._scaled_column(col, rows, values, rescale)
        if factor != self._col[col]:
            self._col[col] = factor
            self._push_col_bounds(col)
            self._push_costs(np.array([col], dtype=np.int32))
        self._written[col] = (row_list, v)
        change, error = self.highs.changeCoeff, self._error
        for r, x in zip(row_list, v.tolist()):
            if change(r, col, x) == error:
                raise SolverError("highs", "changeCoeff: kError")

    def column_as_held(self, col: int, rows: NDArray[np.int64], values: NDArray[np.float64]) -> HeldColumn:
        """What `set_column()` with ``rescale`` would leave HiGHS holding for this column (its
        scaled entries, factor, bounds, and the costs under the cost factor it implies),
        without sending anything: another solver of the held LP
        ([`WarmRows.set_column()`][mjtvm.lp.warm.WarmRows.set_column]) takes the same LP."""
        factor, row_list, v = self._scaled_column(col, rows, values, True)
        col_scale = self._col.copy()
        col_scale[col] = factor
        g = cost_scale(self._cost, col_scale)
        return HeldColumn(
            col,
            np.asarray(row_list, dtype=np.int64),
            v,
            factor,
            float(self._col_lower[col] / factor),
            float(self._col_upper[col] / factor),
            g * col_scale * self._cost,  # as _push_costs sends them
            g,
        )

    def _scaled_column(
        self, col: int, rows: NDArray[np.int64], values: NDArray[np.float64], rescale: bool
    ) -> tuple[float, list[int], NDArray[np.float64]]:
        """`set_column()`'s column factor (the held one unless ``rescale``), rows and scaled
        entries (round-off dropped as in ``scale_lp``); nothing is changed or sent."""
        rows = np.asarray(rows, dtype=np.int64)
        key = rows.tobytes()
        if key != self._rows_key:  # the same rows LP after LP (an alpha column, a ray's t column)
            self._rows_key = key
            self._rows_of = (self.scaling.row[rows], self._row_max[rows], rows.tolist())
        row_scale, row_max, row_list = self._rows_of
        v = row_scale * np.asarray(values, dtype=float)
        mag = np.abs(v)
        big = float(mag.max(initial=0.0))  # nan or inf where an entry is
        f = float(self._col[col])
        if rescale:
            f = factor_of_largest(big) if big != 0.0 else 1.0
        v *= f
        mag *= f
        big *= f
        if not math.isfinite(big):  # row factor times datum past 1e308: never drop an inf
            raise SolverError(
                "highs", "changeCoeff: an equilibrated coefficient overflows (data span too wide)"
            )
        ref = np.maximum(row_max, max(big, 1.0))
        kept = mag > DROP_REL * ref
        v = np.where(kept, v, 0.0)  # round-off, as in scale_lp
        kept_mag = mag[kept]
        if kept_mag.size:  # _check_magnitudes, from what is known here: the largest is big
            self._check_range(float(kept_mag.min()), big, "changeCoeff")
        return f, row_list, v

    def held(self) -> HeldLP:
        """The equilibrated LP HiGHS holds now (every change sent included), with the basis
        and the primal values of its last solve: a warm start for another solver of the
        same LP ([`WarmRows`][mjtvm.lp.warm.WarmRows]). Call after an optimal `solve()`."""
        status, basic = self.highs.getBasicVariables()
        self._check(status, "getBasicVariables")
        sol = self.highs.getSolution()
        with np.errstate(invalid="ignore"):  # inf / positive stays inf
            lower, upper = self._col_lower / self._col, self._col_upper / self._col
        return HeldLP(
            merge_columns(as_csc(self._held), self._written),
            self._sent_cost.copy(),
            lower,
            upper,
            basic_variables(basic, self.num_col),
            np.concatenate([np.asarray(sol.col_value), np.asarray(sol.row_value)]),
            self._col.copy(),
            self.scaling.row,
            self.scaling.cost,
        )

    def start_basis(self, basic_cols: NDArray[np.int64], nonbasic_rows: NDArray[np.int64]) -> None:
        """Start the next solve from the basis of the slacks with ``basic_cols`` swapped in
        for the slacks of ``nonbasic_rows`` (as many), instead of HiGHS' slack basis: every
        other column nonbasic at a finite bound (at 0 when free), those rows at their lower
        bound. The caller makes it nonsingular (HiGHS would replace dependent columns by
        slacks); HiGHS restores primal and dual feasibility from there."""
        if len(basic_cols) != len(nonbasic_rows):
            raise ParamError("start_basis", "as many basic columns as nonbasic rows are needed")
        hs = self._hs
        status = hs.HighsBasisStatus
        cols = np.where(np.isfinite(self._col_lower), 0, np.where(np.isfinite(self._col_upper), 1, 2))
        cols[np.asarray(basic_cols)] = 3
        rows = np.full(len(self._row_max), 3)
        rows[np.asarray(nonbasic_rows)] = 0
        names = (status.kLower, status.kUpper, status.kZero, status.kBasic)
        basis = hs.HighsBasis()
        basis.col_status = [names[c] for c in cols.tolist()]
        basis.row_status = [names[r] for r in rows.tolist()]
        basis.valid = True
        self._check(self.highs.setBasis(basis), "setBasis")

    def set_row_bounds(
        self, rows: NDArray[np.int64], lower: NDArray[np.float64], upper: NDArray[np.float64]
    ) -> None:
        """Change the bounds of some rows."""
        f = self.scaling.row[rows]
        lo, up = f * np.asarray(lower, dtype=float), f * np.asarray(upper, dtype=float)
        with np.errstate(invalid="ignore"):  # -inf + inf: nan, not finite either
            finite = math.isfinite(float(lo.sum() + up.sum()))
        if not finite:  # rare: a free row's side (or a huge sum)
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
        """Send the scaled costs of ``cols``; when the cost factor changes, those of every
        column that differ from what HiGHS holds. A cost change costs the warm start (HiGHS
        recomputes its duals), and a column rescaled together with the cost factor (the only
        costed column, as alpha in Problem 2 and t in ray shooting) keeps its scaled cost, as
        every zero cost does: nothing is sent."""
        g = cost_scale(self._cost, self._col)
        if g != self.scaling.cost:
            self.scaling = Scaling(self.scaling.row, self.scaling.col, g)  # not replace(): 10 us
            every = g * self._col * self._cost
            moved = np.flatnonzero(every != self._sent_cost).astype(np.int32)  # zeros stay 0
            if not moved.size:
                return
            cols, cost = moved, every[moved]
        else:
            cols = np.asarray(cols, dtype=np.int32)
            cost = np.ascontiguousarray(g * self._col[cols] * self._cost[cols])
        self._sent_cost[cols] = cost
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
        t0 = time.perf_counter()
        try:
            status = h.run()
            if status == self._hs.HighsStatus.kError and _THREADS[0] == 1:
                # The scheduler may have been started by another HiGHS user of this process
                # with another thread count (see _THREADS): accept it, once for all sessions.
                self._check(h.setOptionValue("threads", 0), "option threads=0 rejected")
                status = h.run()
                if status != self._hs.HighsStatus.kError:
                    _THREADS[0] = 0
                else:
                    self._check(h.setOptionValue("threads", 1), "option threads restore")
        finally:
            ran(t0)
        if status == self._hs.HighsStatus.kError:
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
            ray = None
            if duals:  # the Farkas multipliers, when HiGHS has them (certificate.farkas)
                ok, has_ray, values = h.getDualRay()
                if ok != self._hs.HighsStatus.kError and has_ray:
                    ray = self.scaling.row * np.array(values)
            return LPSolution("infeasible", None, None, ray)
        if status == ms.kUnbounded:
            return LPSolution("unbounded", None, None)
        raise SolverError("highs", h.modelStatusToString(status))
