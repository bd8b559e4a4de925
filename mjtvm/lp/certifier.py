r"""The batch checker of certificates: one [`Certifier`][mjtvm.lp.certifier.Certifier] per family of LPs.

Problem 2 checks every LP of a state against the same matrix, column bounds, variables'
sizes and row groups; a [`Certifier`][mjtvm.lp.certifier.Certifier] computes what depends on
those alone once and checks one answer ([`check()`][mjtvm.lp.certifier.Certifier.check]) or many
at once ([`check_many()`][mjtvm.lp.certifier.Certifier.check_many]), by the measures of
``mjtvm.lp.certificate``'s module docstring and the tolerances of
[`tolerances`][mjtvm.lp.tolerances].
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from types import ModuleType
from typing import Any, TypeAlias

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.csc import Csc
from mjtvm.lp.nonzero import NonzeroProducts
from mjtvm.lp.roundoff import drop_cancellation
from mjtvm.lp.tolerances import DUAL_TOL, GAP_TOL, Certificate, finite_part

__all__ = ["BATCH_ENTRIES", "Certifier", "Matrix"]

Matrix: TypeAlias = Any  #: a dense ``NDArray[np.float64]`` or a scipy sparse matrix
#: ``(P, .)`` arrays in, the two products of `Certifier._measure()` out
_Products: TypeAlias = Callable[[NDArray[np.float64], NDArray[np.float64]], tuple[NDArray[np.float64], ...]]


#: Most multiply-adds in one matrix product of [`Certifier.check_many()`][mjtvm.lp.certifier.Certifier.check_many] (answers x rows x
#: columns); more answers are certified in chunks. numpy's OpenBLAS (0.3.31) ran the 22-joint
#: dataset state's products on one thread up to 18 answers (390,600) and on two for its 36
#: (781,200), whose second thread then spins between calls: two cores for 2 % less time, and
#: two such processes side by side halved their throughput. A margin below that: 11 answers.
BATCH_ENTRIES = 2**18


def _relative(value: float, ref: float) -> float:
    """``value / ref``; 0 for ``0 / 0``, ``inf`` for a positive value over 0."""
    if ref > 0.0:
        return value / ref
    return 0.0 if value == 0.0 else np.inf


class Certifier:
    """The checks of [`certify()`][mjtvm.lp.certificate.certify] and [`farkas()`][mjtvm.lp.certificate.farkas], in batches, for a family of LPs that share their
    matrix object, column lower bounds, variables' sizes and row groups: Problem 2 checks
    every LP of a state with one (its matrix's last column, the alpha column, overwritten
    in place between LPs), so what depends on those alone is computed once.

    Parameters
    ----------
    a
        ``(m, n)`` the matrix (dense or sparse); read at every check, never copied.
    col_lower
        ``(n,)`` the column lower bounds.
    col_ref, abs_a, row_groups
        As in [`certify()`][mjtvm.lp.certificate.certify]; ``abs_a`` must follow ``a`` if ``a`` changes.
    dual_ref
        ``(n,)`` the sizes a reduced cost of the wrong sign is weighed with (default
        ``col_ref``): a force that is 0 in this solution may be large at another, while the
        rows' violations are measured at ``col_ref`` (a physical force size would drown an
        unbalanced weight in a state whose Jacobians are 1e-100).
    row_cap
        ``(m,)`` the largest a term ``|A_ij| col_ref_j`` may add to row i's scale (``inf``:
        no cap), a physical size of the row (module docstring); the term counts as
        ``max(|A_ij x_j|, row_cap_i)`` where ``|A_ij| col_ref_j`` exceeds it. Read from
        ``abs_a`` once, here: the entries it caps must not change later (Problem 2's last
        column, alpha, has ``col_ref`` 0 and is never capped).
    pattern
        A sparse matrix whose stored entries (each once) cover the nonzeros of ``a``'s
        columns but the last (Problem 2: the assembly's): `check_many()` on a large dense
        ``a`` then takes its pattern from them instead of scanning every entry (the same
        sums: an entry stored but 0 adds 0), read only there.
    jit
        [`products_jit`][mjtvm.lp.products_jit] (the batch paths): with ``pattern`` and a
        dense ``a``, `check_many()`'s products of the shared columns are sums over
        ``pattern``'s entries in numba, at any size (a few percent of the dense products'
        multiply-adds; equal to round-off).
    """

    def __init__(
        self,
        a: Matrix,
        col_lower: NDArray[np.float64],
        *,
        col_ref: NDArray[np.float64] | None = None,
        abs_a: Matrix | None = None,
        row_groups: NDArray[np.int64] | None = None,
        dual_ref: NDArray[np.float64] | None = None,
        row_cap: NDArray[np.float64] | None = None,
        pattern: Csc | None = None,
        jit: ModuleType | None = None,
    ) -> None:
        self.a = a
        self._jit = jit
        self._pattern_cols: NDArray[np.int64] | None = None  # pattern's entries' columns
        self._nonzero: NonzeroProducts | None = None  # built by the first large check_many
        self._pattern = pattern
        self.dual_ref = col_ref if dual_ref is None else dual_ref
        self.abs_a = abs(a) if abs_a is None else abs_a
        self.col_lower = np.asarray(col_lower, dtype=float)
        self.lower_ok, self.lower0 = finite_part(self.col_lower)
        self.col_ref = col_ref
        self.starts: NDArray[np.int64] | None = None
        if row_groups is not None and row_groups.size:
            # Groups are runs of consecutive rows (Assembly.row_groups): one reduceat, not ufunc.at.
            self.starts = np.flatnonzero(np.concatenate([[True], row_groups[1:] != row_groups[:-1]]))
            self.counts = np.diff(np.append(self.starts, row_groups.size))
        # The capped terms (row, column, |A_ij|, cap): none in a state whose rows' terms are
        # all within their caps, which then costs nothing at each check.
        self.capped: (
            tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]] | None
        )
        self.capped = None
        # The rows' terms are |A| s with the capped entries left out (abs_terms), so that a
        # term of 1e20 is not added and then taken off again (the others lost in its round-off).
        self.abs_terms = self.abs_a
        if row_cap is not None and col_ref is not None:
            rows = np.flatnonzero(np.isfinite(row_cap))
            if rows.size and rows[-1] - rows[0] + 1 == rows.size:  # consecutive: a view
                sub = self.abs_a[rows[0] : rows[-1] + 1, :-1]
            else:
                sub = self.abs_a[rows, :-1]  # the last column may change in place: never capped
            sub = sub if isinstance(sub, np.ndarray) else sub.toarray()
            r = cols = np.zeros(0, dtype=np.int64)
            if rows.size and np.any(
                sub.max(axis=1, initial=0.0) * col_ref[:-1].max(initial=0.0) > row_cap[rows]
            ):
                r, cols = np.nonzero(sub * col_ref[:-1] > row_cap[rows, None])
            if r.size:
                self.capped = (rows[r], cols, sub[r, cols], np.asarray(row_cap, dtype=float)[rows[r]])
                if isinstance(self.abs_a, np.ndarray):
                    self.abs_terms = self.abs_a.copy()
                    self.abs_terms[rows[r], cols] = 0.0
                else:
                    lil = self.abs_a.tolil(copy=True)
                    lil[rows[r], cols] = 0.0
                    self.abs_terms = lil.tocsr()

    def _scale(self, scale: NDArray[np.float64]) -> NDArray[np.float64]:
        """Each row's scale (along the last axis) raised to the largest of its group's."""
        if self.starts is None:
            return scale
        return np.repeat(np.maximum.reduceat(scale, self.starts, axis=-1), self.counts, axis=-1)

    def violation(
        self,
        ax: NDArray[np.float64],
        terms: NDArray[np.float64],
        lower: tuple[NDArray[np.bool_], NDArray[np.float64]],
        upper: tuple[NDArray[np.bool_], NDArray[np.float64]],
    ) -> NDArray[np.float64]:
        """[`primal_violation()`][mjtvm.lp.certificate.primal_violation] from the row activities ``ax`` and the rows' terms, along
        the last axis (``(m,)`` or ``(P, m)`` in, ``()`` or ``(P,)`` out)."""
        (lo_ok, lo), (up_ok, up) = lower, upper
        below = np.where(lo_ok, lo - ax, 0.0)
        above = np.where(up_ok, ax - up, 0.0)
        viol = np.maximum(np.maximum(below, above), 0.0)
        scale = self._scale(terms + np.where(below > above, np.abs(lo), np.abs(up)))
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(viol > 0.0, viol / scale, 0.0)  # viol > 0 = scale: inf
        return np.max(rel, axis=-1, initial=0.0)

    def check(
        self,
        c: NDArray[np.float64],
        row_lower: NDArray[np.float64],
        row_upper: NDArray[np.float64],
        col_upper: NDArray[np.float64],
        x: NDArray[np.float64],
        y: NDArray[np.float64] | None,
        *,
        floor: float = 0.0,
    ) -> Certificate:
        """[`certify()`][mjtvm.lp.certificate.certify] on this family's matrix and column lower bounds."""
        a, abs_a, abs_terms = self.a, self.abs_a, self.abs_terms

        def products(xc: NDArray[np.float64], size: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
            if abs_terms is abs_a:
                return (a @ xc[0])[None], (abs_a @ size[0])[None]
            # A copy without the capped entries; its last column read from abs_a (in place).
            last = abs_a[:, -1] if isinstance(abs_a, np.ndarray) else abs_a[:, -1:].toarray().ravel()
            return (a @ xc[0])[None], (abs_terms[:, :-1] @ size[0, :-1] + last * size[0, -1])[None]

        def transposed(
            yy: NDArray[np.float64], abs_y: NDArray[np.float64]
        ) -> tuple[NDArray[np.float64], ...]:
            return (a.T @ yy[0])[None], (abs_a.T @ abs_y[0])[None]

        zero = np.zeros_like(row_lower) if y is None else y
        one = self._measure(
            c,
            row_lower[None],
            row_upper[None],
            col_upper[None],
            x[None],
            zero[None],
            [floor],
            products,
            transposed,
        )[0]
        return one if y is not None else Certificate(one.primal, np.inf, np.inf, -np.inf)

    def check_many(
        self,
        c: NDArray[np.float64],
        row_lower: NDArray[np.float64],
        row_upper: NDArray[np.float64],
        col_upper: NDArray[np.float64],
        x: NDArray[np.float64],
        y: NDArray[np.float64],
        last: NDArray[np.float64],
        *,
        floor: NDArray[np.float64],
    ) -> list[Certificate]:
        """`check()` of ``P`` answers at once, for LPs that differ from this family's
        matrix only in its last column: the same measures, from matrix products instead of
        ``P`` matrix-vector ones (Problem 2 certifies a state's pairs together).

        Parameters
        ----------
        c
            ``(n,)`` the costs, shared.
        row_lower, row_upper, y
            ``(P, m)`` each answer's row bounds and row multipliers.
        col_upper, x
            ``(P, n)`` each answer's column upper bounds and solution.
        last
            ``(P, m)`` each LP's last column (Problem 2: the alpha column of its RVDS vertex),
            in place of the matrix's; ``self.a`` must be dense.
        floor
            ``(P,)`` each answer's ``floor`` ([`certify()`][mjtvm.lp.certificate.certify]).
        """
        m, n = self.a.shape
        sparse = m * n > BATCH_ENTRIES and isinstance(self.a, np.ndarray)
        step = max(1, BATCH_ENTRIES // max(m * n, 1))
        a0, abs0, terms0 = self.a[:, :-1], self.abs_a[:, :-1], self.abs_terms[:, :-1]
        abs_last = np.abs(last)
        if self._jit is not None and self._pattern is not None and isinstance(self.a, np.ndarray):
            return self._measure(c, row_lower, row_upper, col_upper, x, y, floor, *self._jit_products(last))
        if sparse:
            # Above BATCH_ENTRIES even one answer's product ran on several OpenBLAS threads:
            # the same sums over the nonzeros only (the shared columns' pattern is fixed).
            if self._nonzero is None:  # from the given entries where known: O(nnz), not O(m n)
                self._nonzero = (
                    NonzeroProducts(abs0)
                    if self._pattern is None
                    else NonzeroProducts.from_entries(
                        abs0.shape, self._pattern.indices, self._pattern.columns()
                    )
                )
            nz = self._nonzero

            def nz_products(
                xc: NDArray[np.float64], size: NDArray[np.float64]
            ) -> tuple[NDArray[np.float64], ...]:
                return (
                    nz.right(a0, xc[:, :-1]) + xc[:, -1:] * last,
                    nz.right(terms0, size[:, :-1]) + size[:, -1:] * abs_last,
                )

            def nz_transposed(
                yy: NDArray[np.float64], abs_y: NDArray[np.float64]
            ) -> tuple[NDArray[np.float64], ...]:
                ya, abs_ya = np.empty((len(yy), n)), np.empty((len(yy), n))
                ya[:, :-1], ya[:, -1] = nz.left(a0, yy), np.sum(yy * last, axis=1)
                abs_ya[:, :-1], abs_ya[:, -1] = nz.left(abs0, abs_y), np.sum(abs_y * abs_last, axis=1)
                return ya, abs_ya

            return self._measure(c, row_lower, row_upper, col_upper, x, y, floor, nz_products, nz_transposed)

        # The products in blocks of ``step`` answers, which BLAS runs on one thread
        # (BATCH_ENTRIES); the rest of the measures, row by row, on all P at once.
        blocks = [slice(i, i + step) for i in range(0, len(x), step)]

        def products(xc: NDArray[np.float64], size: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
            ax, terms = np.empty((len(xc), m)), np.empty((len(xc), m))
            for b in blocks:  # the shared columns, then each LP's last one
                ax[b] = xc[b, :-1] @ a0.T + xc[b, -1:] * last[b]
                terms[b] = size[b, :-1] @ terms0.T + size[b, -1:] * abs_last[b]
            return ax, terms

        def transposed(
            yy: NDArray[np.float64], abs_y: NDArray[np.float64]
        ) -> tuple[NDArray[np.float64], ...]:
            ya, abs_ya = np.empty((len(yy), n)), np.empty((len(yy), n))
            for b in blocks:
                ya[b, :-1], ya[b, -1] = yy[b] @ a0, np.sum(yy[b] * last[b], axis=1)
                abs_ya[b, :-1], abs_ya[b, -1] = abs_y[b] @ abs0, np.sum(abs_y[b] * abs_last[b], axis=1)
            return ya, abs_ya

        return self._measure(c, row_lower, row_upper, col_upper, x, y, floor, products, transposed)

    def _jit_products(self, last: NDArray[np.float64]) -> tuple[_Products, _Products]:
        """`check_many()`'s ``products`` and ``transposed`` for the LPs of last columns
        ``last`` (``(P, m)``): the shared columns' sums over ``pattern``'s entries
        ([`products_jit`][mjtvm.lp.products_jit]), then each LP's last column."""
        assert self._jit is not None and self._pattern is not None
        jit, pat = self._jit, self._pattern
        m, n = self.a.shape
        assert pat.shape == (m, n - 1)  # the shared columns
        if self._pattern_cols is None:
            self._pattern_cols = pat.columns()
        at = (pat.indices, self._pattern_cols)
        # The shared columns' values read now, as the dense products read them.
        v_a, v_abs, v_terms = self.a[at], self.abs_a[at], self.abs_terms[at]
        abs_last = np.abs(last)

        def products(xc: NDArray[np.float64], size: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
            ax, terms = np.empty((len(xc), m)), np.empty((len(xc), m))
            jit.right(pat.indptr, pat.indices, v_a, xc, ax)
            jit.right(pat.indptr, pat.indices, v_terms, size, terms)
            ax += xc[:, -1:] * last
            terms += size[:, -1:] * abs_last
            return ax, terms

        def transposed(
            yy: NDArray[np.float64], abs_y: NDArray[np.float64]
        ) -> tuple[NDArray[np.float64], ...]:
            ya, abs_ya = np.empty((len(yy), n)), np.empty((len(yy), n))
            jit.left(pat.indptr, pat.indices, v_a, yy, ya)
            jit.left(pat.indptr, pat.indices, v_abs, abs_y, abs_ya)
            ya[:, -1], abs_ya[:, -1] = np.sum(yy * last, axis=1), np.sum(abs_y * abs_last, axis=1)
            return ya, abs_ya

        return products, transposed

    def _measure(
        self,
        c: NDArray[np.float64],
        row_lower: NDArray[np.float64],
        row_upper: NDArray[np.float64],
        col_upper: NDArray[np.float64],
        x: NDArray[np.float64],
        y: NDArray[np.float64],
        floor: Sequence[float] | NDArray[np.float64],
        products: _Products,
        transposed: _Products,
    ) -> list[Certificate]:
        """The certificates of ``P`` answers (the arrays of `check_many()`), the matrix
        reached through ``products(xc, size) -> (A x, |A| size)`` and
        ``transposed(y, |y|) -> (y A, |y| |A|)``, each ``(P, .)``."""
        xc = np.minimum(np.maximum(x, self.col_lower), col_upper)  # clip (bounds may be inf)
        size = np.abs(xc) if self.col_ref is None else np.maximum(np.abs(xc), self.col_ref)
        lower, upper = finite_part(row_lower), finite_part(row_upper)
        (lo_ok, lo), (up_ok, up) = lower, upper
        ax, terms = products(xc, size)
        if self.capped is not None:  # those terms at max(|A_ij x_j|, cap), not |A_ij| s_j
            rows, cols, mag, cap = self.capped
            np.add.at(terms.T, rows, np.maximum(mag * np.abs(xc[:, cols]), cap).T)  # terms.T: a view
        primal = self.violation(ax, terms, lower, upper)
        y = np.array(y, dtype=float)
        c = np.asarray(c, dtype=float)
        # Rows: y_i > 0 pairs with a finite lower bound, y_i < 0 with a finite upper one. A
        # multiplier of the wrong sign is taken as 0; what that moves the bound by is measured
        # by its size times the row's (|A_i| s + |lower bound|), added up with the columns'.
        wrong_row = ((y > 0.0) & ~lo_ok) | ((y < 0.0) & ~up_ok)
        moved = np.sum(np.where(wrong_row, np.abs(y) * (terms + np.abs(lo)), 0.0), axis=1)
        y[wrong_row] = 0.0
        ya, abs_ya = transposed(y, np.abs(y))
        d = c - ya
        # A reduced cost within round-off of its terms is 0 (roundoff.drop_cancellation): the
        # free joint speeds and torques have d = 1e-17 where their terms are 1.
        drop_cancellation(d, np.abs(c) + abs_ya)
        cu_ok, cu = finite_part(col_upper)
        wrong_col = ((d > 0.0) & ~self.lower_ok) | ((d < 0.0) & ~cu_ok)
        dual_size = size if self.dual_ref is None else np.maximum(np.abs(xc), self.dual_ref)
        moved += np.sum(np.where(wrong_col, np.abs(d) * dual_size, 0.0), axis=1)
        d[wrong_col] = 0.0
        bound = (
            np.sum(np.maximum(y, 0.0) * lo + np.minimum(y, 0.0) * up, axis=1)
            + np.maximum(d, 0.0) @ self.lower0
            + np.sum(np.minimum(d, 0.0) * cu, axis=1)
        )
        objective = xc @ c
        out = []
        for i in range(len(xc)):
            b, obj, fl = float(bound[i]), float(objective[i]), float(floor[i])
            size_obj = max(abs(obj), abs(b))
            out.append(
                Certificate(
                    float(primal[i]),
                    _relative(float(moved[i]), max(size_obj, fl / DUAL_TOL)),
                    _relative(abs(obj - b), max(size_obj, fl / GAP_TOL)),
                    b,
                )
            )
        return out

    def farkas(
        self,
        row_lower: NDArray[np.float64],
        row_upper: NDArray[np.float64],
        col_upper: NDArray[np.float64],
        y: NDArray[np.float64] | None,
    ) -> bool:
        """[`farkas()`][mjtvm.lp.certificate.farkas] on this family's matrix and column lower bounds."""
        if y is None or not np.all(np.isfinite(y)):
            return False
        zero = np.zeros(self.a.shape[1])
        for sign in (1.0, -1.0):
            cert = self.check(zero, row_lower, row_upper, col_upper, zero, sign * np.asarray(y))
            if cert.bound > 0.0 and cert.dual <= DUAL_TOL:
                return True
        return False
