r"""The basis matrix of the warm dual simplex ([`dual_jit`][mjtvm.lp.dual_jit]) in numba: its
inverse, products with the columns of ``[A | -I]``, and the basic values and row duals the
inverse gives.

``A`` (``(m, n)``) is given as CSC arrays ``indptr, indices, data``; the variables are the
``n`` columns then the ``m`` row activities ``r = A x`` (the columns of ``[A | -I]``): variable
``j >= n`` is row ``j - n``'s activity. The basis ``basic`` (``(m,)``) lists the basic
variables; row ``p`` of the inverse belongs to ``basic[p]``. The inverse is dense (a few
hundred rows): it is built once per basis by [`invert()`][mjtvm.lp.basis_jit.invert] and
updated by the dual simplex's pivots, whose steepest-edge weights are its rows' norms.

Imported with [`dual_jit`][mjtvm.lp.dual_jit] (lazily, on the batch paths only; compiled code
cached on disk, ``cache=True``).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = [
    "add_column",
    "column_dot",
    "column_pivot",
    "ftran",
    "invert",
    "pivot_update",
    "replace_column",
    "values_and_duals",
    "with_column",
]

_SINGULAR_TOL = 1e-11  # Gauss-Jordan pivot below this times the column's largest: singular


@numba.njit(cache=True)
def invert(
    indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, basic: np.ndarray, binv: np.ndarray
) -> bool:
    """Write ``B^{-1}`` into ``binv`` (``(m, m)``), ``B`` the columns ``basic`` of
    ``[A | -I]`` (``A`` in CSC arrays ``indptr, indices, data``; ``basic[p] >= n`` is row
    ``basic[p] - n``'s activity). Row ``p`` of the inverse belongs to ``basic[p]``.
    Returns ``False`` where ``B`` is singular (a pivot at most ``_SINGULAR_TOL`` times its
    column's largest entry).

    Only the block ``M = A[R, C]`` needs eliminating (``C`` the basic columns, ``R`` the rows
    whose activity is nonbasic, as many): with ``z_C = M^{-1} v_R``, the basic activity of
    row ``i`` is ``A[i, C] z_C - v_i``. Gauss-Jordan with partial pivoting on ``M`` (most
    of a basis is row activities: 123 of 175 on the 22-joint hand's LPs)."""
    m = binv.shape[0]
    n = indptr.shape[0] - 1
    row_basic = np.zeros(m, dtype=np.bool_)
    k = 0
    for p in range(m):
        if basic[p] >= n:
            row_basic[basic[p] - n] = True
        else:
            k += 1
    rpos = np.full(m, -1, dtype=np.int64)  # row i in R: its index in M
    rows = np.empty(k, dtype=np.int64)
    c = 0
    for i in range(m):
        if not row_basic[i]:
            if c >= k:
                return False
            rpos[i] = c
            rows[c] = i
            c += 1
    if c != k:
        return False
    mm = np.zeros((k, k))
    cols = np.empty(k, dtype=np.int64)  # M's column c: the basic column at position cols[c]
    c = 0
    for p in range(m):
        j = basic[p]
        if j < n:
            cols[c] = p
            for t in range(indptr[j], indptr[j + 1]):
                q = rpos[indices[t]]
                if q >= 0:
                    mm[q, c] = data[t]
            c += 1
    inv = np.zeros((k, k))
    for i in range(k):
        inv[i, i] = 1.0
    pivot_row = np.empty(k, dtype=np.int64)
    used = np.zeros(k, dtype=np.bool_)
    for p in range(k):
        best, arg, big = 0.0, -1, 0.0
        for i in range(k):
            v = abs(mm[i, p])
            if v > big:
                big = v
            if not used[i] and v > best:
                best, arg = v, i
        if arg < 0 or best <= _SINGULAR_TOL * big:
            return False
        used[arg] = True
        pivot_row[p] = arg
        f = 1.0 / mm[arg, p]
        for q in range(p, k):
            mm[arg, q] *= f
        for q in range(k):
            inv[arg, q] *= f
        for i in range(k):
            g = mm[i, p]
            if i != arg and g != 0.0:
                for q in range(p, k):
                    if mm[arg, q] != 0.0:
                        mm[i, q] -= g * mm[arg, q]
                for q in range(k):
                    if inv[arg, q] != 0.0:
                        inv[i, q] -= g * inv[arg, q]
    # M's column c was reduced to e_{pivot_row[c]}: M^{-1}'s row c is inv's row pivot_row[c].
    binv[:, :] = 0.0
    slack_pos = np.full(m, -1, dtype=np.int64)
    for p in range(m):
        if basic[p] >= n:
            slack_pos[basic[p] - n] = p
            binv[p, basic[p] - n] = -1.0
    for c in range(k):
        p = cols[c]
        minv_row = inv[pivot_row[c]]
        for q in range(k):
            binv[p, rows[q]] = minv_row[q]
        j = basic[p]
        for t in range(indptr[j], indptr[j + 1]):
            sp = slack_pos[indices[t]]
            a = data[t]
            if sp >= 0 and a != 0.0:
                for q in range(k):
                    binv[sp, rows[q]] += a * minv_row[q]
    return True


@numba.njit(cache=True)
def column_pivot(
    indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, j: int, p: int, binv: np.ndarray
) -> float:
    """``u_p = (B^{-1} a_j)_p`` (``a_j`` column ``j < n`` as the arrays hold it now, ``p`` its
    position in the basis): the pivot of `replace_column()`, one row of the inverse (``nnz``
    flops). Its sign is that of the new basis' row duals relative to the old ones where the
    replaced column alone is costed (``y = c_j B^{-T} e_p``)."""
    return column_dot(indptr, indices, data, indptr.shape[0] - 1, j, binv[p])


@numba.njit(cache=True)
def with_column(
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    m: int,
    j: int,
    rows: np.ndarray,
    values: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``A`` (CSC arrays, ``m`` rows) with ``A[rows, j] = values``, the column's other entries
    kept: [`merge_columns()`][mjtvm.lp.held.merge_columns] for one column (rows sorted, zeros
    not stored), new arrays of ``indptr``'s and ``indices``' dtypes."""
    dense = np.zeros(m)
    for t in range(indptr[j], indptr[j + 1]):
        dense[indices[t]] = data[t]
    for q in range(rows.shape[0]):
        dense[rows[q]] = values[q]
    k = 0
    for i in range(m):
        if dense[i] != 0.0:
            k += 1
    lo, hi = indptr[j], indptr[j + 1]
    shift = k - (hi - lo)
    nnz = indptr[-1] + shift
    new_ptr = indptr.copy()
    for c in range(j + 1, indptr.shape[0]):
        new_ptr[c] += shift
    new_idx = np.empty(nnz, dtype=indices.dtype)
    new_data = np.empty(nnz)
    new_idx[:lo] = indices[:lo]
    new_data[:lo] = data[:lo]
    t = lo
    for i in range(m):
        if dense[i] != 0.0:
            new_idx[t] = i
            new_data[t] = dense[i]
            t += 1
    new_idx[t:] = indices[hi:]
    new_data[t:] = data[hi:]
    return new_ptr, new_idx, new_data


@numba.njit(cache=True)
def replace_column(
    indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, j: int, p: int, binv: np.ndarray
) -> bool:
    """Update ``binv`` (``(m, m)``, in place) for the basis whose column at position ``p`` is
    now variable ``j`` of ``[A | -I]`` (a column ``j < n`` whose entries changed to those
    ``indptr, indices, data`` hold, or another variable entering for the one at ``p``):
    with ``u = B^{-1} a_j``, ``B' = B E`` (``E`` the identity but column ``p``, ``u``), so
    ``B'^{-1} = E^{-1} B^{-1}``: one Gauss-Jordan step on pivot ``u_p``, ``m^2`` flops
    instead of a fresh `invert()`. Returns ``False``, ``binv`` unchanged, where ``u_p`` is
    at most ``_SINGULAR_TOL`` times ``u``'s largest entry (singular to `invert()`'s
    criterion)."""
    m = binv.shape[0]
    u = np.empty(m)
    ftran(indptr, indices, data, indptr.shape[0] - 1, j, binv, u)
    big = 0.0
    for i in range(m):
        if abs(u[i]) > big:
            big = abs(u[i])
    if not abs(u[p]) > _SINGULAR_TOL * big:  # also a nan or a zero column
        return False
    pivot_update(binv, u, p)
    return True


@numba.njit(cache=True)
def ftran(
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    n: int,
    j: int,
    binv: np.ndarray,
    out: np.ndarray,
) -> None:
    """``out = B^{-1} a_j`` (``(m,)``, written in place), ``a_j`` column ``j`` of ``[A | -I]``
    (``n`` columns in ``A``): a row activity's is ``-B^{-1} e_(j - n)``."""
    m = binv.shape[0]
    out[:] = 0.0
    if j >= n:
        for i in range(m):
            out[i] = -binv[i, j - n]
    else:
        for t in range(indptr[j], indptr[j + 1]):
            v = data[t]
            k = indices[t]
            for i in range(m):
                out[i] += v * binv[i, k]


@numba.njit(cache=True)
def pivot_update(binv: np.ndarray, u: np.ndarray, p: int) -> None:
    """``binv`` (``(m, m)``, in place) for the basis whose column at position ``p`` is
    replaced by the one with ``B^{-1} a = u``: one Gauss-Jordan step on the pivot ``u_p``
    (the caller has checked it is nonzero)."""
    m = binv.shape[0]
    f = 1.0 / u[p]
    for c in range(m):
        binv[p, c] *= f
    for i in range(m):
        g = u[i]
        if i != p and g != 0.0:
            for c in range(m):
                binv[i, c] -= g * binv[p, c]


@numba.njit(cache=True)
def add_column(
    indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, n: int, j: int, v: float, out: np.ndarray
) -> None:
    """``out += v * (column j of [A | -I])`` (``out``: ``(m,)``, written in place)."""
    if j >= n:
        out[j - n] -= v
    else:
        for t in range(indptr[j], indptr[j + 1]):
            out[indices[t]] += v * data[t]


@numba.njit(cache=True)
def column_dot(
    indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, n: int, j: int, y: np.ndarray
) -> float:
    """``(column j of [A | -I]) . y`` (``y``: ``(m,)``)."""
    if j >= n:
        return -y[j - n]
    s = 0.0
    for t in range(indptr[j], indptr[j + 1]):
        s += data[t] * y[indices[t]]
    return s


@numba.njit(cache=True)
def values_and_duals(
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    cost: np.ndarray,
    basic: np.ndarray,
    value: np.ndarray,
    binv: np.ndarray,
    x_b: np.ndarray,
    y: np.ndarray,
) -> None:
    """Write ``x_B = -B^{-1} N x_N`` into ``x_b`` (``(m,)``; ``value``, ``(n + m,)``, holds
    the nonbasic values, its basic entries ignored) and the row duals ``y = B^{-T} c_B`` into
    ``y`` (``(m,)``; ``cost``, ``(n,)``, the row activities cost 0), from the inverse ``binv``
    (``(m, m)``): afresh, rather than updated pivot by pivot."""
    m = binv.shape[0]
    n = indptr.shape[0] - 1
    isbasic = np.zeros(n + m, dtype=np.bool_)
    for p in range(m):
        isbasic[basic[p]] = True
    rhs = np.zeros(m)
    for j in range(n + m):
        if not isbasic[j] and value[j] != 0.0:
            add_column(indptr, indices, data, n, j, -value[j], rhs)
    for p in range(m):
        s = 0.0
        for i in range(m):
            s += binv[p, i] * rhs[i]
        x_b[p] = s
    y[:] = 0.0
    for p in range(m):
        j = basic[p]
        cb = cost[j] if j < n else 0.0
        if cb != 0.0:
            for i in range(m):
                y[i] += cb * binv[p, i]
