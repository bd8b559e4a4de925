"""Certificates of LP answers (mjtvm.lp.certificate) on LPs solved by hand."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from mjtvm.lp.certificate import (
    BATCH_ENTRIES,
    DUAL_TOL,
    GAP_TOL,
    PRIMAL_TOL,
    Certifier,
    certify,
    farkas,
    primal_violation,
)
from mjtvm.lp.highs import HighsSession
from mjtvm.lp.lp import LinearProgram

INF = np.inf

# max x1 + 2 x2  s.t.  x1 + x2 <= 4,  x1 + 3 x2 <= 6,  x >= 0: optimum (3, 1), value 5, and
# the dual y = (1/2, 1/2) (both rows bind; -c = A^T (-y) in HiGHS' signs: y <= 0 on upper rows).
C = np.array([-1.0, -2.0])
A = np.array([[1.0, 1.0], [1.0, 3.0]])
LO, UP = np.array([-INF, -INF]), np.array([4.0, 6.0])
CL, CU = np.zeros(2), np.array([INF, INF])
X_OPT = np.array([3.0, 1.0])
Y_OPT = np.array([-0.5, -0.5])


def check(x, y, **kw):  # type: ignore[no-untyped-def]
    return certify(C, A, LO, UP, CL, CU, x, y, **kw)


def test_the_optimum_by_hand_is_certified():
    cert = check(X_OPT, Y_OPT)
    assert cert.ok
    assert cert.primal == 0.0 and cert.dual == 0.0 and cert.gap == 0.0
    assert cert.bound == pytest.approx(-5.0)  # weak duality: a lower bound of min c^T x = -5


def test_highs_own_answer_and_duals_are_certified_in_the_same_signs():
    lp = LinearProgram(C, sp.csc_matrix(A), LO, UP, CL, CU)
    sol = HighsSession(lp).solve(duals=True)
    assert sol.x is not None and sol.row_dual is not None
    np.testing.assert_allclose(sol.row_dual, Y_OPT, atol=1e-12)
    assert check(sol.x, sol.row_dual).ok


def test_a_feasible_but_suboptimal_point_fails_on_the_gap():
    """(2, 1) is feasible with value 4; the optimum's multipliers bound the optimum by 5: the
    gap is 1/5 relative."""
    cert = check(np.array([2.0, 1.0]), Y_OPT)
    assert cert.primal == 0.0 and cert.dual == 0.0
    assert cert.gap == pytest.approx(0.2)
    assert not cert.ok


def test_an_infeasible_point_fails_on_the_primal_check():
    """(3, 1.1): row 2 reads 6.3 > 6, a violation of 0.3 against terms |1| 3 + |3| 1.1 + 6."""
    cert = check(np.array([3.0, 1.1]), Y_OPT)
    assert cert.primal == pytest.approx(0.3 / (3.0 + 3.3 + 6.0))
    assert not cert.ok


def test_a_point_outside_its_bounds_is_clipped_first():
    """x2 = -1e-13 (a solver's round-off below alpha >= 0) is clipped to 0, and the clipped
    point is what the rows are checked with: (4, 0) is feasible and, with value 4, not optimal."""
    cert = check(np.array([4.0, -1e-13]), Y_OPT)
    assert cert.primal == 0.0
    assert cert.gap == pytest.approx(0.2)


def test_multipliers_of_the_wrong_sign_fail_on_the_dual_check():
    """y = (+1/2, -1/2): the first row has no lower bound, so a positive multiplier there has
    no bound to pair with; taken as 0 it leaves d = c - A^T y = (-1/2, -1/2), negative on
    columns without an upper bound."""
    cert = check(X_OPT, np.array([0.5, -0.5]))
    assert cert.dual > DUAL_TOL and not cert.ok


def test_without_multipliers_nothing_but_the_primal_is_certified():
    cert = check(X_OPT, None)
    assert cert.primal == 0.0 and cert.dual == np.inf and not cert.ok


def test_an_objective_below_the_floor_is_certified_absolutely():
    """An alpha of 0 is certified by a bound within ``floor`` of 0 (the reporting threshold),
    not relative to 0. max x s.t. x <= 1e-12: with floor 1e-9 the answer 0 passes the gap,
    with floor 0 it does not."""
    c, a = np.array([-1.0]), np.array([[1.0]])
    args = (c, a, np.array([-INF]), np.array([1e-12]), np.array([0.0]), np.array([INF]), np.array([0.0]))
    assert certify(*args, np.array([-1.0]), floor=1e-9).ok
    assert not certify(*args, np.array([-1.0]), floor=0.0).ok


def test_tolerances_are_documented_values():
    assert (PRIMAL_TOL, DUAL_TOL, GAP_TOL) == (1e-8, 1e-7, 1e-7)


def test_primal_violation_is_relative_to_the_rows_terms():
    a = np.array([[1e6, -1e6]])
    # 1e6 x1 - 1e6 x2 = 0 at x = (1, 1 + 1e-12): violation 1e-6 against terms 2e6
    rel = primal_violation(a, np.array([1.0, 1.0 + 1e-12]), np.zeros(1), np.zeros(1))
    assert rel == pytest.approx(1e-6 / 2e6, rel=1e-3)


def test_a_row_cap_keeps_a_large_coefficient_from_hiding_a_residual():
    """1e12 x1 + x2 - x3 = 0, x3 = 1, with sizes 1 for every variable: x = (0, 1.03, 1)
    misses the first row by 0.03, 3 % of its other terms. At x1's size the row's scale is
    1e12 and the miss passes for round-off; with the row's terms capped at 2 (a physical
    size of the row) x1 counts 2, the scale is 2 + 1.03 + 1 and the miss fails. The
    solution's own term is never capped: at x1 = 1e-12 the row is 1 + 1.03 - 1 and the
    scale counts max(1e12 x1, 2) = 2 beside the others."""
    a = np.array([[1e12, 1.0, -1.0], [0.0, 0.0, 1.0]])
    lo = up = np.array([0.0, 1.0])
    cl, cu, c = np.full(3, -INF), np.full(3, INF), np.zeros(3)
    ref, cap = np.ones(3), np.array([2.0, INF])
    wrong = np.array([0.0, 1.03, 1.0])
    assert certify(c, a, lo, up, cl, cu, wrong, None, col_ref=ref).primal < PRIMAL_TOL  # the defect
    cert = certify(c, a, lo, up, cl, cu, wrong, None, col_ref=ref, row_cap=cap)
    assert cert.primal == pytest.approx(0.03 / (2.0 + 1.03 + 1.0), rel=1e-9)
    right = np.array([0.0, 1.0, 1.0])
    assert certify(c, a, lo, up, cl, cu, right, None, col_ref=ref, row_cap=cap).primal == 0.0
    big = np.array([1e-9, 1.03 - 1e3, 1.0])  # 1e12 x1 = 1e3 in this solution: counted in full
    cert = certify(c, a, lo, up, cl, cu, big, None, col_ref=ref, row_cap=cap)
    assert cert.primal == pytest.approx(0.03 / (1e3 + abs(1.03 - 1e3) + 1.0), rel=1e-6)
    # sparse and dense matrices cap the same terms
    sparse = certify(c, sp.csc_matrix(a), lo, up, cl, cu, wrong, None, col_ref=ref, row_cap=cap)
    assert sparse.primal == pytest.approx(0.03 / 4.03, rel=1e-9)


def test_farkas_proves_an_infeasible_lp_and_refuses_a_feasible_one():
    """x1 + x2 >= 2 with 0 <= x <= 0.5 is infeasible: y = 1 on the row gives the dual bound
    2 - 0.5 - 0.5 = 1 > 0. HiGHS' dual ray proves it too; with x <= 1 (feasible) no ray does."""
    a = np.array([[1.0, 1.0]])
    lo, up = np.array([2.0]), np.array([INF])
    assert farkas(a, lo, up, np.zeros(2), np.full(2, 0.5), np.array([1.0]))
    assert farkas(a, lo, up, np.zeros(2), np.full(2, 0.5), np.array([-1.0]))  # either sign
    assert not farkas(a, lo, up, np.zeros(2), np.ones(2), np.array([1.0]))
    assert not farkas(a, lo, up, np.zeros(2), np.full(2, 0.5), None)
    lp = LinearProgram(np.zeros(2), sp.csc_matrix(a), lo, up, np.zeros(2), np.full(2, 0.5))
    sol = HighsSession(lp).solve(duals=True)
    assert sol.status == "infeasible"
    assert farkas(a, lo, up, np.zeros(2), np.full(2, 0.5), sol.row_dual)


def _family(seed: int, p: int):
    """``p`` LPs sharing a matrix but for its last column: bounds with infinite entries,
    multipliers and answers perturbed so that every measure is non-zero somewhere."""
    rng = np.random.default_rng(seed)
    m, n = 9, 7
    a = rng.normal(size=(m, n))
    a[rng.random((m, n)) < 0.3] = 0.0
    col_lower = np.where(rng.random(n) < 0.3, -np.inf, -rng.random(n))
    c = rng.normal(size=n)
    lower = np.where(rng.random((p, m)) < 0.3, -np.inf, -rng.random((p, m)))
    upper = np.where(rng.random((p, m)) < 0.3, np.inf, rng.random((p, m)))
    cu = np.where(rng.random((p, n)) < 0.3, np.inf, 1.0 + rng.random((p, n)))
    x = rng.normal(size=(p, n))
    y = rng.normal(size=(p, m))
    last = rng.normal(size=(p, m))
    last[:, ::3] = 0.0
    ref = np.where(rng.random(n) < 0.5, 0.0, rng.random(n))
    groups = np.repeat(np.arange(4), [3, 2, 3, 1])
    floor = rng.random(p) * 1e-3
    return a, col_lower, c, lower, upper, cu, x, y, last, ref, groups, floor


@pytest.mark.parametrize(("seed", "entries"), [(s, BATCH_ENTRIES) for s in range(5)] + [(5, 63 * 4), (6, 1)])
def test_check_many_gives_each_answer_the_certificate_check_gives_it(seed, entries, monkeypatch):
    """Also in chunks (4 answers of 9 x 7 per product, or one): the chunks keep BLAS on one thread."""
    monkeypatch.setattr("mjtvm.lp.certifier.BATCH_ENTRIES", entries)
    a, col_lower, c, lower, upper, cu, x, y, last, ref, groups, floor = _family(seed, 6)
    one = Certifier(a.copy(), col_lower, col_ref=ref, row_groups=groups, dual_ref=2 * ref)
    many = one.check_many(c, lower, upper, cu, x, y, last, floor=floor)
    assert len(many) == 6
    for i, got in enumerate(many):
        own = a.copy()
        own[:, -1] = last[i]
        want = Certifier(own, col_lower, col_ref=ref, row_groups=groups, dual_ref=2 * ref).check(
            c, lower[i], upper[i], cu[i], x[i], y[i], floor=floor[i]
        )
        for name in ("primal", "dual", "gap", "bound"):
            assert getattr(got, name) == pytest.approx(getattr(want, name), rel=1e-12, abs=1e-14), name
        assert want.primal > 0.0 and want.dual > 0.0 and want.gap > 0.0  # every measure exercised
