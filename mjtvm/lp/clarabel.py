r"""The Clarabel interior-point solver on equilibrated LPs, with its own checks: every
answer is re-solved scaled by the first solution, and refused unless every row and bound
holds (an interior point's "Solved" is not a certificate)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import SolverError
from mjtvm.lp.csc import scipy_matrix
from mjtvm.lp.lp import LinearProgram, LPSolution
from mjtvm.lp.scaling import Scaling, cost_scale, lp_scaling, pow2, scale_lp, unscale

__all__ = ["feasible_clarabel", "solve_clarabel"]

_CLARABEL_OK = {"Solved": "optimal", "PrimalInfeasible": "infeasible", "DualInfeasible": "unbounded"}


def _solve_clarabel(lp: LinearProgram) -> LPSolution:
    """Clarabel on ``lp`` as given (callers pass it equilibrated)."""
    import clarabel
    import scipy.sparse as sp  # here, not at import: Problem 2's HiGHS path never needs it (csc)

    a = sp.csc_matrix(scipy_matrix(lp.A))
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
    # Row multipliers in HiGHS' signs (c = A^T y + d; y >= 0 where a lower bound binds):
    # Clarabel's dual z of ``A_big x + s = b`` has c = -A_big^T z, so y = -z on the rows
    # written as upper bounds (and equalities), +z on those written as lower bounds. For a
    # primal infeasible LP, z is its certificate (certificate.farkas).
    z = np.array(result.z)
    k_eq, k_up, k_lo = int(eq.sum()), int(up.sum()), int(lo.sum())
    y = np.zeros(a.shape[0])
    y[eq] = -z[:k_eq]
    y[up] -= z[k_eq : k_eq + k_up]
    y[lo] += z[k_eq + k_up : k_eq + k_up + k_lo]
    if status == "infeasible":
        return LPSolution("infeasible", None, None, y)
    if status != "optimal":
        return LPSolution(status, None, None)  # type: ignore[arg-type]
    return LPSolution("optimal", np.array(result.x), float(result.obj_val), y)


def solve_clarabel(lp: LinearProgram, *, scaling: Scaling | None = None) -> LPSolution:
    """Clarabel on the equilibrated ``lp`` ([`lp_scaling()`][mjtvm.lp.scaling.lp_scaling] unless ``scaling``), unscaled."""
    import scipy.sparse as sp

    s = lp_scaling(lp) if scaling is None else scaling
    slp1 = scale_lp(lp, s)
    first = _solve_clarabel(slp1)
    if first.status == "infeasible" and first.row_dual is not None:
        return replace(first, row_dual=s.row * first.row_dual)  # a ray: the cost factor does not apply
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
    col = s.col * pow2(np.maximum(xs, 2.0**-10 * max(float(xs.max()), 1e-300)))
    a = sp.csr_matrix(abs(sp.csr_matrix(scipy_matrix(lp.A)) @ sp.diags(col)))
    row_max = a.max(axis=1).toarray().ravel() if a.shape[1] else np.zeros(a.shape[0])
    row = np.where(row_max > 0, pow2(1.0 / np.where(row_max > 0, row_max, 1.0)), 1.0)
    s2 = Scaling(row, col, cost_scale(np.asarray(lp.c, dtype=float), col))
    try:
        slp = scale_lp(lp, s2)
        sol = _solve_clarabel(slp)
        obj = 0.0 if sol.objective is None else abs(sol.objective)
        if sol.status == "optimal" and 0.0 < obj < 0.0625:
            s2 = replace(s2, cost=s2.cost * float(pow2(1.0 / obj)))
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
    ax = scipy_matrix(lp.A) @ x
    with np.errstate(invalid="ignore"):
        parts = [lp.row_lower - ax, ax - lp.row_upper, lp.col_lower - x, x - lp.col_upper]
    return float(max(np.max(np.nan_to_num(p, nan=0.0, neginf=0.0), initial=0.0) for p in parts))


def feasible_clarabel(lp: LinearProgram, s: Scaling) -> bool:
    """Whether Clarabel finds ``lp``'s constraints feasible (zero cost: no unbounded ray to
    confuse with infeasibility)."""
    zero = replace(lp, c=np.zeros_like(np.asarray(lp.c, dtype=float)))
    return solve_clarabel(zero, scaling=replace(s, cost=1.0)).status == "optimal"
