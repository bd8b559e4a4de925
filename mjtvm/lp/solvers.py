r"""Linear-program backends called through their direct APIs, on equilibrated LPs.

A [`LinearProgram`][mjtvm.lp.lp.LinearProgram] is ``min c^T x`` s.t. ``row_lower <= A x <= row_upper``,
``col_lower <= x <= col_upper`` with a sparse CSC ``A``. Two backends:

* ``"highs"`` (default): HiGHS dual simplex through ``highspy``. Simplex returns a
  vertex, so alphas are exact to the solver's feasibility tolerance, infeasible and
  unbounded LPs are certified, and a [`HighsSession`][mjtvm.lp.highs.HighsSession] re-solves after changing
  one column and some row bounds from the previous basis (the LPs of one state differ
  only there).
* ``"clarabel"``: the Clarabel interior-point solver, used as an independent
  cross-check and as the fallback when HiGHS cannot settle an LP.

Scaling (a documented decision): both backends see the LP after
[`equilibrate()`][mjtvm.lp.scaling.equilibrate] -- rows and columns multiplied by powers of 2 (so the scaling itself
is exact) chosen by mean-of-logs then Ruiz passes over ``|[A | b]|``, the right-hand
sides taking part (their factor pinned at 1) so that a change of force or length unit,
which multiplies the solution, is undone too. Problem 2 computes it once per state. The solvers' absolute tolerances (1e-9) then mean the same thing in
every unit system; solutions, objectives and duals are unscaled before they are
returned. Coefficients are dropped only when they are round-off: in the equilibrated LP,
at most [`DROP_REL`][mjtvm.lp.solvers.DROP_REL] times the largest entry of their row, of their column, or 1.

HiGHS statuses: ``kWarning`` (e.g. a dropped tiny value) is accepted, ``kError`` from
any call raises [`SolverError`][mjtvm.errors.SolverError]. LP statuses are ``"optimal"``,
``"infeasible"`` or ``"unbounded"``; anything else raises
[`SolverError`][mjtvm.errors.SolverError]. [`solve_settled()`][mjtvm.lp.solvers.solve_settled] / [`fallback()`][mjtvm.lp.solvers.fallback] /
[`clarabel_checked()`][mjtvm.lp.solvers.clarabel_checked] settle an LP across both backends (HiGHS' cold retries, then
Clarabel; Clarabel's verdicts checked by HiGHS and a feasibility re-solve) and return a
[`Settled`][mjtvm.lp.solvers.Settled] with a note whenever a backend failed or they disagreed.
"""

from __future__ import annotations

from dataclasses import dataclass

from mjtvm.errors import ParamError, SolverError
from mjtvm.lp.clarabel import feasible_clarabel, solve_clarabel
from mjtvm.lp.highs import HighsSession, new_highs
from mjtvm.lp.lp import DROP_REL, FEASIBILITY_TOL, LinearProgram, LPSolution, LPStatus
from mjtvm.lp.scaling import Scaling, column_factor, cost_scale, equilibrate, lp_scaling, scale_lp, unscale

__all__ = [
    "DROP_REL",
    "FEASIBILITY_TOL",
    "SOLVERS",
    "HighsSession",
    "LPSolution",
    "LPStatus",
    "LinearProgram",
    "Scaling",
    "Settled",
    "clarabel_checked",
    "column_factor",
    "cost_scale",
    "equilibrate",
    "fallback",
    "lp_scaling",
    "new_highs",
    "scale_lp",
    "solve_clarabel",
    "solve_lp",
    "solve_settled",
    "unscale",
]

SOLVERS = ("highs", "clarabel")


def solve_lp(lp: LinearProgram, *, solver: str = "highs", scaling: Scaling | None = None) -> LPSolution:
    """Solve one LP with the named backend (``"highs"`` or ``"clarabel"``), equilibrated."""
    if solver == "highs":
        return HighsSession(lp, scaling=scaling).solve(duals=True)
    if solver == "clarabel":
        return solve_clarabel(lp, scaling=scaling)
    raise ParamError("solver", f"expected one of {SOLVERS}, got {solver!r}", solver)


@dataclass(frozen=True, eq=False)
class Settled:
    """An LP's solution, the backend whose verdict it is, and a note when the backends
    disagreed or one of them failed (``None`` otherwise)."""

    solution: LPSolution
    solver: str
    note: str | None = None


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
            rescue = HighsSession(lp, scaling=s).solve(duals=True)
        except SolverError as e2:
            raise SolverError("clarabel", f"{e.status}; fallback highs: {e2.status}") from e
        return Settled(rescue, "highs", f"clarabel: {e.status}; settled by highs: {rescue.status}")
    if sol.status == "optimal":
        # Near a feasibility limit (a weight within 1e-7 of the largest a hand holds) the
        # interior point can call feasible what the simplex certifies infeasible: a HiGHS
        # solve checks every verdict, and a disagreement is noted (the answer stays
        # Clarabel's, which was asked for).
        try:
            check = HighsSession(lp, scaling=s).solve(duals=True)
        except SolverError as e:
            return Settled(sol, "clarabel", f"highs could not check it ({e.status})")
        if check.status != "optimal":
            return Settled(sol, "clarabel", f"clarabel: optimal; highs: {check.status}")
        return Settled(sol, "clarabel")
    checked: LPSolution | None = None
    try:
        checked = HighsSession(lp, scaling=s).solve(duals=True)
    except SolverError as e:
        err = e
    other = checked
    if other is not None and other.status == sol.status:
        return Settled(sol, "clarabel")
    try:
        feasible = feasible_clarabel(lp, s)
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
    """One LP settled as [`clarabel_checked()`][mjtvm.lp.solvers.clarabel_checked] (``"clarabel"``) or by HiGHS with its cold
    retries and then Clarabel as the fallback (``"highs"``); SolverError, chained to
    HiGHS' own, only when neither settles it."""
    if solver == "clarabel":
        return clarabel_checked(lp, scaling=scaling)
    if solver != "highs":
        raise ParamError("solver", f"expected one of {SOLVERS}, got {solver!r}", solver)
    try:
        return Settled(HighsSession(lp, scaling=scaling).solve(duals=True), "highs")
    except SolverError as e:
        return fallback(lp, e, scaling=scaling)


def fallback(lp: LinearProgram, error: SolverError, *, scaling: Scaling | None = None) -> Settled:
    """After HiGHS failed with ``error``: Clarabel's checked verdict, noted; SolverError
    (chained to ``error``) when Clarabel fails too."""
    s = lp_scaling(lp) if scaling is None else scaling
    try:
        sol = solve_clarabel(lp, scaling=s)
        if sol.status != "optimal":  # an interior-point verdict alone is not enough: re-solve
            feasible = feasible_clarabel(lp, s)
            if feasible != (sol.status == "unbounded"):
                raise SolverError("clarabel", f"{sol.status}, contradicted by its feasibility re-solve")
    except SolverError as e2:
        raise SolverError("highs", f"{error.status}; fallback clarabel: {e2.status}") from error
    return Settled(sol, "clarabel", f"highs: {error.status}; settled by clarabel: {sol.status}")
