"""`NonzeroProducts` against dense products, and the certifier's large-matrix path against its dense one."""

from __future__ import annotations

import numpy as np

from mjtvm.lp import certifier as certifier_module
from mjtvm.lp.certifier import Certifier
from mjtvm.lp.nonzero import NonzeroProducts


def _sparse_dense(rng: np.random.Generator, m: int, k: int, density: float) -> np.ndarray:
    a = rng.standard_normal((m, k))
    a[rng.random((m, k)) > density] = 0.0
    a[3] = 0.0  # an empty row
    a[:, 5] = 0.0  # an empty column
    return a


def test_products_equal_the_dense_ones_to_round_off() -> None:
    rng = np.random.default_rng(7)
    a = _sparse_dense(rng, 40, 30, 0.1)
    nz = NonzeroProducts(np.abs(a))
    xs, ys = rng.standard_normal((6, 30)), rng.standard_normal((6, 40))
    np.testing.assert_allclose(nz.right(a, xs), xs @ a.T, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(nz.left(a, ys), ys @ a, rtol=1e-13, atol=1e-13)
    assert np.all(nz.right(a, xs)[:, 3] == 0.0) and np.all(nz.left(a, ys)[:, 5] == 0.0)
    zeroed = np.abs(a)
    zeroed[0, np.flatnonzero(zeroed[0])[:1]] = 0.0  # a value off within the pattern: still exact
    np.testing.assert_allclose(nz.right(zeroed, xs), xs @ zeroed.T, rtol=1e-13, atol=1e-13)
    empty = NonzeroProducts(np.zeros((4, 3)))
    assert np.all(empty.right(np.zeros((4, 3)), np.ones((2, 3))) == 0.0)
    assert empty.left(np.zeros((4, 3)), np.ones((2, 4))).shape == (2, 3)


def test_check_many_above_batch_entries_matches_the_dense_path(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(3)
    m, n, p = 50, 41, 5
    a = _sparse_dense(rng, m, n, 0.15)
    col_lower = np.zeros(n)
    cert = Certifier(a, col_lower, col_ref=np.ones(n))
    x = np.abs(rng.standard_normal((p, n)))
    y = rng.standard_normal((p, m))
    ax = x @ a.T
    row_lower, row_upper = ax - 1e-3, ax + 1e-3
    c = rng.standard_normal(n)
    col_upper = np.full((p, n), np.inf)
    last = rng.standard_normal((p, m))
    floor = np.zeros(p)
    dense = cert.check_many(c, row_lower, row_upper, col_upper, x, y, last, floor=floor)
    monkeypatch.setattr(certifier_module, "BATCH_ENTRIES", 100)  # m * n above it: the nonzero path
    sparse = Certifier(a, col_lower, col_ref=np.ones(n)).check_many(
        c, row_lower, row_upper, col_upper, x, y, last, floor=floor
    )
    for d, s in zip(dense, sparse, strict=True):
        for field in ("primal", "dual", "gap"):
            got, want = getattr(s, field), getattr(d, field)
            assert got == want or abs(got - want) <= 1e-12 * max(1.0, abs(want)), (field, got, want)


def test_pattern_from_entries_is_the_dense_scan() -> None:
    """`from_entries()` (a sparse matrix's stored entries, in column order, some of them 0)
    gives the arrays `NonzeroProducts(dense)` gives where the entries are exactly the
    nonzeros, and the same sums bit for bit where some given entries are 0."""
    rng = np.random.default_rng(11)
    a = _sparse_dense(rng, 60, 45, 0.08)
    cols, rows = np.nonzero(a.T)  # column-major, as a CSC's stored entries
    scan, given = NonzeroProducts(np.abs(a)), NonzeroProducts.from_entries(a.shape, rows, cols)
    for name in ("rows", "cols", "row_starts", "row_ids", "t_rows", "t_cols", "col_starts", "col_ids"):
        np.testing.assert_array_equal(getattr(given, name), getattr(scan, name), err_msg=name)
    xs, ys = rng.standard_normal((4, 45)), rng.standard_normal((4, 60))
    assert np.array_equal(given.right(a, xs), scan.right(a, xs))
    assert np.array_equal(given.left(a, ys), scan.left(a, ys))
    b = a.copy()
    b[rows[::7], cols[::7]] = 0.0  # given entries that are 0: each adds 0 to its sum
    stored = NonzeroProducts.from_entries(b.shape, rows, cols)
    np.testing.assert_allclose(stored.right(b, xs), xs @ b.T, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(stored.left(b, ys), ys @ b, rtol=1e-13, atol=1e-13)
