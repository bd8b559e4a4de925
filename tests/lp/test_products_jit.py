"""`products_jit` against dense products, and the certifier's compiled path against its dense one."""

from __future__ import annotations

import numpy as np
import pytest

from mjtvm.lp.certifier import Certifier
from mjtvm.lp.csc import Csc

products_jit = pytest.importorskip("mjtvm.lp.products_jit")  # numba


def _sparse(rng: np.random.Generator, m: int, k: int, density: float) -> tuple[np.ndarray, Csc]:
    a = rng.standard_normal((m, k))
    a[rng.random((m, k)) > density] = 0.0
    a[3] = 0.0  # an empty row
    a[:, 5] = 0.0  # an empty column
    cols, rows = np.nonzero(a.T)  # column-major: a CSC's stored entries
    indptr = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=k))])
    return a, Csc(a[rows, cols], rows, indptr, (m, k))


def test_products_equal_the_dense_ones_to_round_off() -> None:
    rng = np.random.default_rng(7)
    a, csc = _sparse(rng, 40, 30, 0.1)
    xs, ys = rng.standard_normal((6, 31)), rng.standard_normal((6, 40))  # xs: one more column
    right, left = np.full((6, 40), np.nan), np.full((6, 31), 7.0)
    products_jit.right(csc.indptr, csc.indices, csc.data, xs, right)
    products_jit.left(csc.indptr, csc.indices, csc.data, ys, left)
    np.testing.assert_allclose(right, xs[:, :30] @ a.T, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(left[:, :30], ys @ a, rtol=1e-13, atol=1e-13)
    assert np.all(right[:, 3] == 0.0) and np.all(left[:, 5] == 0.0)
    assert np.all(left[:, 30] == 7.0)  # the column past the matrix's is left as it was


def test_check_many_compiled_matches_the_dense_path() -> None:
    """The certificates from the sums over the pattern's entries are the dense products'
    to round-off, a capped row term (its entry zeroed in the terms) included."""
    rng = np.random.default_rng(3)
    m, k, p = 50, 40, 5
    a0, csc = _sparse(rng, m, k, 0.15)
    a = np.hstack([a0, rng.standard_normal((m, 1))])  # the last column: each LP's own
    n = k + 1
    col_lower = np.zeros(n)
    col_ref = np.append(np.ones(k), 0.0)
    row_cap = np.full(m, np.inf)
    row_cap[0] = 0.5 * np.abs(a0[0]).max()  # at least one capped term in row 0
    x = np.abs(rng.standard_normal((p, n)))
    y = rng.standard_normal((p, m))
    last = rng.standard_normal((p, m))
    ax = x[:, :k] @ a0.T + x[:, -1:] * last
    row_lower, row_upper = ax - 1e-3, ax + 1e-3
    c = rng.standard_normal(n)
    col_upper = np.full((p, n), np.inf)
    floor = np.zeros(p)
    kw = {"col_ref": col_ref, "row_cap": row_cap, "pattern": csc}
    dense = Certifier(a, col_lower, **kw).check_many(
        c, row_lower, row_upper, col_upper, x, y, last, floor=floor
    )
    jit = Certifier(a, col_lower, jit=products_jit, **kw)
    assert jit.capped is not None
    compiled = jit.check_many(c, row_lower, row_upper, col_upper, x, y, last, floor=floor)
    for d, s in zip(dense, compiled, strict=True):
        assert d.ok == s.ok
        for field in ("primal", "dual", "gap", "bound"):
            got, want = getattr(s, field), getattr(d, field)
            assert got == want or abs(got - want) <= 1e-12 * max(1.0, abs(want)), (field, got, want)
