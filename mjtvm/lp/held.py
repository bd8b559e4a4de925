r"""The equilibrated LP a [`HighsSession`][mjtvm.lp.highs.HighsSession] holds, with its last
basis: [`HeldLP`][mjtvm.lp.held.HeldLP], what
[`HighsSession.held()`][mjtvm.lp.highs.HighsSession.held] gives another solver of the same LP
as its warm start ([`WarmRows`][mjtvm.lp.warm.WarmRows]).

The session passes its matrix to HiGHS once and then only sends single coefficients
(``changeCoeff``); the matrix HiGHS holds is the first one with those writes merged
([`merge_columns()`][mjtvm.lp.held.merge_columns]). HiGHS numbers a basic row activity
``-(1 + i)``; here it is ``n + i`` ([`basic_variables()`][mjtvm.lp.held.basic_variables]).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.csc import Csc

__all__ = ["HeldColumn", "HeldLP", "basic_variables", "merge_columns"]


@dataclass(frozen=True, eq=False)
class HeldLP:
    """The equilibrated LP a [`HighsSession`][mjtvm.lp.highs.HighsSession] holds and its last basis ([`HighsSession.held()`][mjtvm.lp.highs.HighsSession.held]).

    Attributes
    ----------
    a
        ``(m, n)`` the matrix.
    cost
        ``(n,)`` the costs.
    col_lower, col_upper
        ``(n,)`` the column bounds (``+-inf`` where none).
    basic
        ``(m,)`` the basic variables: ``j < n`` column ``j``, ``n + i`` row ``i``'s activity.
    value
        ``(n + m,)`` the columns' values, then the row activities, of the last solve.
    col_scale, row_scale, cost_scale
        The factors: ``x = col_scale * x_s``, row bounds ``row_scale * bounds``, row duals
        ``y = row_scale * y_s / cost_scale`` (as [`HighsSession.solve()`][mjtvm.lp.highs.HighsSession.solve] unscales).
    """

    a: Csc
    cost: NDArray[np.float64]
    col_lower: NDArray[np.float64]
    col_upper: NDArray[np.float64]
    basic: NDArray[np.int64]
    value: NDArray[np.float64]
    col_scale: NDArray[np.float64]
    row_scale: NDArray[np.float64]
    cost_scale: float


@dataclass(frozen=True, eq=False)
class HeldColumn:
    """One column as [`HighsSession.set_column()`][mjtvm.lp.highs.HighsSession.set_column]
    with ``rescale`` would leave it in the LP HiGHS holds
    ([`HighsSession.column_as_held()`][mjtvm.lp.highs.HighsSession.column_as_held]).

    Attributes
    ----------
    col
        The column.
    rows, values
        ``(k,)`` its scaled entries on these rows (every non-zero among them; round-off 0).
    factor
        Its column factor (``x[col] = factor * x_s[col]``).
    col_lower, col_upper
        Its scaled bounds.
    cost
        ``(n,)`` every column's scaled cost under the cost factor below.
    cost_scale
        The cost factor the new column factor implies.
    """

    col: int
    rows: NDArray[np.int64]
    values: NDArray[np.float64]
    factor: float
    col_lower: float
    col_upper: float
    cost: NDArray[np.float64]
    cost_scale: float


def merge_columns(a: Csc, written: Mapping[int, tuple[Sequence[int], NDArray[np.float64]]]) -> Csc:
    """``a`` with the coefficients ``written`` (``{col: (rows, values)}``: ``A[rows, col] =
    values``, the other entries of the column kept) merged in, canonical (rows sorted, zeros
    not stored), int32 indices."""
    indptr, indices, data = a.indptr, a.indices, a.data
    for col, (rows, v) in sorted(written.items()):  # column by column, each shifting the next
        lo, hi = int(indptr[col]), int(indptr[col + 1])
        r_all = np.concatenate([indices[lo:hi], np.asarray(rows, dtype=indices.dtype)])
        v_all = np.concatenate([data[lo:hi], v])
        # the last occurrence of a row wins (the write); zeros are not stored
        order = np.lexsort((np.arange(len(r_all)), r_all))
        r_s, v_s = r_all[order], v_all[order]
        last = np.append(r_s[1:] != r_s[:-1], True)
        keep = last & (v_s != 0.0)
        r_new, v_new = r_s[keep], v_s[keep]
        indices = np.concatenate([indices[:lo], r_new, indices[hi:]])
        data = np.concatenate([data[:lo], v_new, data[hi:]])
        indptr = indptr.copy()
        indptr[col + 1 :] += len(r_new) - (hi - lo)
    return Csc(data, indices.astype(np.int32), indptr.astype(np.int32), a.shape)


def basic_variables(highs_basic: Sequence[int], num_col: int) -> NDArray[np.int64]:
    """``(m,)`` HiGHS' ``getBasicVariables()`` (column ``j``, or ``-(1 + i)`` for row ``i``'s
    activity) in [`HeldLP`][mjtvm.lp.held.HeldLP]'s numbering: row ``i`` is ``num_col + i``."""
    basic = np.asarray(highs_basic, dtype=np.int64)
    return np.where(basic >= 0, basic, num_col - 1 - basic)
