"""The compiled warm dual simplex (mjtvm.lp.warm, mjtvm.lp.dual_jit) against HiGHS on random
bounded LPs whose row bounds change: the same optimal objective (1e-9 relative), a feasible
x, HiGHS' row duals' sign convention; infeasible LPs given up (HiGHS then proves them)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from mjtvm.lp import dual_jit as jit  # numba is a dependency: this imports
from mjtvm.lp.highs import HighsSession
from mjtvm.lp.lp import LinearProgram
from mjtvm.lp.warm import WarmRows


def _random_lp(
    rng: np.random.Generator, m: int, n: int, *, degenerate: bool = False
) -> tuple[LinearProgram, np.ndarray]:
    """A random LP with columns boxed, free, lower- and upper-bounded and fixed, rows equal,
    ranged and one-sided, bounded by construction: its costs are ``A^T y + d`` with ``y`` and
    ``d`` of the signs the bounds allow (a dual feasible point), so the optimum is finite
    whenever the LP is feasible. ``degenerate``: half the reduced costs ``d`` are 0 (ties in
    the dual ratio test) and the first five rows are repeated (ties in the primal one).
    Returns the LP and a feasible point ``x0``."""
    a = sp.random(m, n, density=0.25, random_state=rng, data_rvs=lambda k: rng.normal(size=k)).tocsc()
    kind = rng.integers(0, 5, n)  # 0 boxed, 1 free, 2 lower, 3 upper, 4 fixed
    x0 = rng.normal(size=n)
    lo = np.where(np.isin(kind, (0, 2)), x0 - rng.uniform(0, 1, n), -np.inf)
    up = np.where(np.isin(kind, (0, 3)), x0 + rng.uniform(0, 1, n), np.inf)
    lo[kind == 4] = up[kind == 4] = x0[kind == 4]
    d = rng.uniform(0, 1, n) * np.select(
        [kind == 2, kind == 3, kind == 0], [1.0, -1.0, rng.choice([-1.0, 1.0], n)], 0.0
    )
    ax = a @ x0
    rkind = rng.integers(0, 4, m)  # 0 equal, 1 ranged, 2 lower, 3 upper
    rl = np.where(np.isin(rkind, (0, 1, 2)), ax - np.where(rkind == 0, 0.0, rng.uniform(0, 1, m)), -np.inf)
    ru = np.where(np.isin(rkind, (0, 1, 3)), ax + np.where(rkind == 0, 0.0, rng.uniform(0, 1, m)), np.inf)
    y = rng.normal(size=m) * np.select([rkind == 2, rkind == 3], [0.0, 0.0], 1.0)
    y = np.where(rkind == 2, np.abs(rng.normal(size=m)), np.where(rkind == 3, -np.abs(rng.normal(size=m)), y))
    if degenerate:
        d[::2] = 0.0
        a = sp.vstack([a, a[:5]]).tocsc()  # the repeats' duals 0: c stays dual feasible
        rl, ru, y = np.append(rl, rl[:5]), np.append(ru, ru[:5]), np.append(y, np.zeros(5))
    c = a.T @ y + d
    return LinearProgram(c, a, rl, ru, lo, up), x0


def _moved_bounds(rng, lp, x0, scale):  # type: ignore[no-untyped-def]
    """Row bounds around ``A x1`` for a point ``x1`` near ``x0`` within the column bounds:
    the LP stays feasible (x1 is feasible)."""
    x1 = np.clip(x0 + scale * rng.normal(size=len(x0)), lp.col_lower, lp.col_upper)
    shift = lp.A @ x1 - lp.A @ x0
    return lp.row_lower + shift, lp.row_upper + shift


def _check(lp, lo, up, got, ref) -> None:  # type: ignore[no-untyped-def]
    """``got`` optimal: feasible, HiGHS' objective, and optimal by its own duals (dual
    feasibility and complementary slackness with HiGHS' signs: reduced costs ``c - A^T y``,
    ``y > 0`` at a row's lower bound, ``y < 0`` at its upper one)."""
    assert ref.status == "optimal"
    assert abs(got.objective - ref.objective) <= 1e-9 * max(1.0, abs(ref.objective))
    x, y = got.x, got.row_dual
    ax = lp.A @ x
    size = max(1.0, np.abs(x).max())
    assert np.all(x >= lp.col_lower - 1e-8 * size) and np.all(x <= lp.col_upper + 1e-8 * size)
    assert np.all(ax >= lo - 1e-8 * size) and np.all(ax <= up + 1e-8 * size)
    assert got.objective == pytest.approx(float(lp.c @ x), rel=1e-9, abs=1e-9)
    d = lp.c - lp.A.T @ y
    tol = 1e-7 * max(1.0, np.abs(lp.c).max(), np.abs(y).max())
    at = 1e-7 * size
    assert np.all((d <= tol) | (x <= lp.col_lower + at)), "positive reduced cost off the lower bound"
    assert np.all((d >= -tol) | (x >= lp.col_upper - at)), "negative reduced cost off the upper bound"
    assert np.all((y <= tol) | (ax <= lo + at)), "positive row dual off the row's lower bound"
    assert np.all((y >= -tol) | (ax >= up - at)), "negative row dual off the row's upper bound"


@pytest.mark.parametrize("seed", range(12))
def test_warm_resolves_agree_with_highs(seed):
    rng = np.random.default_rng(seed)
    m, n = int(rng.integers(8, 40)), int(rng.integers(8, 40))
    lp, x0 = _random_lp(rng, m, n)
    ses = HighsSession(lp)
    assert ses.solve(duals=True).status == "optimal"
    warm = WarmRows(ses, jit, lp.row_lower, lp.row_upper)
    solved = 0
    rows = np.arange(m)
    for step in range(8):
        lo, up = _moved_bounds(rng, lp, x0, 0.3 * (step + 1) / 8)
        got = warm.solve(lo, up)
        ses.set_row_bounds(rows, lo, up)
        ref = ses.solve(duals=True)
        if got is None:  # given up: as StateLPs does, the next re-solve starts from HiGHS' basis
            warm = WarmRows(ses, jit, lo, up)
            continue
        solved += 1
        _check(lp, lo, up, got, ref)
    assert solved >= 6  # the kernel gives up only rarely (iteration cap, tiny pivots)


@pytest.mark.parametrize("seed", range(6))
def test_degenerate_lps(seed):
    """Repeated rows and zero reduced costs on half the columns: ties in both ratio tests."""
    rng = np.random.default_rng(100 + seed)
    lp, x0 = _random_lp(rng, 20, 24, degenerate=True)
    ses = HighsSession(lp)
    assert ses.solve(duals=True).status == "optimal"
    warm = WarmRows(ses, jit, lp.row_lower, lp.row_upper)
    rows = np.arange(lp.A.shape[0])
    solved = 0
    for _ in range(6):
        lo, up = _moved_bounds(rng, lp, x0, 0.2)
        got = warm.solve(lo, up)
        ses.set_row_bounds(rows, lo, up)
        ref = ses.solve(duals=True)
        if got is None:
            warm = WarmRows(ses, jit, lo, up)
            continue
        solved += 1
        _check(lp, lo, up, got, ref)
    assert solved >= 5


def test_infeasible_bounds_are_given_up():
    """Row bounds no x meets: the kernel returns None (HiGHS proves it infeasible)."""
    rng = np.random.default_rng(7)
    lp, _ = _random_lp(rng, 15, 15)
    ses = HighsSession(lp)
    assert ses.solve(duals=True).status == "optimal"
    warm = WarmRows(ses, jit, lp.row_lower, lp.row_upper)
    # the same row twice with disjoint bounds
    a = lp.A.toarray()
    i = int(np.argmax(np.count_nonzero(a, axis=1)))
    lo, up = lp.row_lower.copy(), lp.row_upper.copy()
    row_max = float(
        np.sum(
            np.abs(a[i])
            * np.fmax(
                np.abs(np.where(np.isfinite(lp.col_lower), lp.col_lower, 1e3)),
                np.abs(np.where(np.isfinite(lp.col_upper), lp.col_upper, 1e3)),
            )
        )
    )
    lo[i], up[i] = 10 * row_max + 1e4, np.inf
    assert warm.solve(lo, up) is None
    ses.set_row_bounds(np.arange(15), lo, up)
    assert ses.solve(duals=True).status == "infeasible"


def _with_column(lp: LinearProgram, j: int, values: np.ndarray) -> LinearProgram:
    """``lp`` with column ``j`` replaced by the dense ``values``."""
    a = lp.A.tolil()
    a[:, j] = values.reshape(-1, 1)
    return LinearProgram(lp.c, a.tocsc(), lp.row_lower, lp.row_upper, lp.col_lower, lp.col_upper)


def test_column_as_held_is_what_set_column_sends():
    """The column, factor, bounds and costs `column_as_held()` predicts are those HiGHS holds
    after ``set_column(rescale=True)`` (``held()``), bit for bit, for a column 1e6 times
    larger (a new column factor) and one with a round-off entry (dropped)."""
    rng = np.random.default_rng(3)
    lp, _ = _random_lp(rng, 12, 10)
    ses = HighsSession(lp)
    assert ses.solve(duals=True).status == "optimal"
    rows = np.arange(12)
    for scale in (1e6, 1.0):
        values = scale * rng.normal(size=12)
        values[3] = 1e-20 * scale  # round-off beside the rest
        predicted = ses.column_as_held(4, rows, values)
        ses.set_column(4, rows, values, rescale=True)
        assert ses.solve(duals=True).status == "optimal"
        held = ses.held()
        dense = np.zeros(12)
        dense[predicted.rows] = predicted.values
        got = sp.csc_matrix((held.a.data, held.a.indices, held.a.indptr), shape=held.a.shape).toarray()[:, 4]
        assert np.array_equal(got, dense) and dense[3] == 0.0
        assert held.col_scale[4] == predicted.factor
        assert held.col_lower[4] == predicted.col_lower and held.col_upper[4] == predicted.col_upper
        assert np.array_equal(held.cost, predicted.cost) and held.cost_scale == predicted.cost_scale


@pytest.mark.parametrize("seed", range(12))
def test_changed_column_agrees_with_highs(seed):
    """A column and the row bounds changed together: `set_column()` then `solve()` against
    HiGHS' ``set_column(rescale=True)`` and warm solve, on the LP with the new column."""
    rng = np.random.default_rng(200 + seed)
    m, n = int(rng.integers(8, 40)), int(rng.integers(8, 40))
    lp, x0 = _random_lp(rng, m, n)
    ses = HighsSession(lp)
    assert ses.solve(duals=True).status == "optimal"
    warm = WarmRows(ses, jit, lp.row_lower, lp.row_upper)
    rows = np.arange(m)
    solved = 0
    for _ in range(8):
        j = int(rng.integers(0, n))
        old = lp.A[:, [j]].toarray().ravel()
        new = old * (1.0 + 0.05 * rng.normal(size=m))  # its non-zeros moved by ~5 %
        lp = _with_column(lp, j, new)
        lo, up = _moved_bounds(rng, lp, x0, 0.05)
        ok = warm.set_column(ses.column_as_held(j, rows, new), [warm.basis()])
        got = warm.solve(lo, up) if ok else None
        ses.set_column(j, rows, new, rescale=True)
        ses.set_row_bounds(rows, lo, up)
        ref = ses.solve(duals=True)
        # Feasible by construction (bounds around A x1); bounded on these seeds, though the
        # costs are no longer A^T y + d for the new column.
        assert ref.status == "optimal"
        if got is None:
            warm = WarmRows(ses, jit, lo, up)
            continue
        solved += 1
        _check(lp, lo, up, got, ref)
    assert solved >= 5


def test_with_column_is_a_dense_write():
    """`with_column()` (the kernel's) and `merge_columns()` (the session's) both give ``A``
    with ``A[rows, j] = values`` written densely, zeros not stored, rows sorted: a column
    that grows, one that shrinks to nothing, the first and the last column."""
    from mjtvm.lp.basis_jit import with_column
    from mjtvm.lp.csc import as_csc
    from mjtvm.lp.held import merge_columns

    rng = np.random.default_rng(5)
    a = sp.random(9, 6, density=0.4, random_state=rng).tocsc()
    held = as_csc(a)
    cases = [
        (0, np.array([8, 1, 4]), np.array([1.5, -2.0, 0.0])),
        (5, np.arange(9), rng.normal(size=9)),
        (2, np.arange(9), np.zeros(9)),
        (3, np.array([2]), np.array([7.0])),
    ]
    for j, rows, values in cases:
        dense = a.toarray()
        dense[rows, j] = values
        ptr, idx, data = with_column(held.indptr, held.indices, held.data, 9, j, rows, values)
        merged = merge_columns(held, {j: (rows, values)})
        for p, i, d in ((ptr, idx, data), (merged.indptr, merged.indices, merged.data)):
            got = sp.csc_matrix((d, i, p), shape=(9, 6))
            assert np.array_equal(got.toarray(), dense)
            assert np.all(d != 0.0) and got.has_sorted_indices
        assert idx.dtype == held.indices.dtype and ptr.dtype == held.indptr.dtype


@pytest.mark.parametrize("seed", range(8))
def test_negated_column_from_a_cap(seed):
    """``max x_0`` (the only cost, x_0 >= 0) over boxed columns and equality rows; x_0's
    column negated: its pivot in the old basis is -1, so neither the old basis nor (without
    ``cap``) any start is dual feasible, and `set_column()` refuses. With ``cap`` an upper
    bound of x_0 (twice the rows' bound), x_0 starts nonbasic at the cap and the re-solve
    meets HiGHS' optimum of the new LP."""
    rng = np.random.default_rng(300 + seed)
    m, n = 6, 12
    a = rng.normal(size=(m, n))
    x0 = np.append(rng.uniform(0.1, 1.0), rng.uniform(-1, 1, n - 1))
    x0[0] = 0.0  # feasible for either sign of x_0's column
    b = a @ x0
    lo, up = np.append(0.0, -np.ones(n - 1)), np.append(np.inf, np.ones(n - 1))
    c = np.zeros(n)
    c[0] = -1.0
    lp = LinearProgram(c, sp.csc_matrix(a), b, b, lo, up)
    ses = HighsSession(lp)
    assert ses.solve(duals=True).status == "optimal"
    rows = np.arange(m)
    flipped = _with_column(lp, 0, -a[:, 0])
    bound = np.min((np.abs(b) + np.abs(a[:, 1:]).sum(axis=1)) / np.abs(a[:, 0]))  # x_0 <= bound
    for cap, works in ((np.inf, False), (2.0 * bound, True)):
        warm = WarmRows(ses, jit, b, b)
        assert 0 in warm.basis().basic  # x_0 > 0 at the first optimum: basic
        ok = warm.set_column(ses.column_as_held(0, rows, -a[:, 0]), cap=cap)
        assert ok == works
        if ok:
            got = warm.solve(b, b)
            ref_ses = HighsSession(flipped)
            ref = ref_ses.solve(duals=True)
            assert got is not None and got.x[0] < 2.0 * bound
            _check(flipped, b, b, got, ref)
