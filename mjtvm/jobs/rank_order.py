r"""The order of ``mjtvm rank``'s rows: sorted by a measure, ranked, summarised per object.

[`ranked_rows()`][mjtvm.jobs.rank_order.ranked_rows] sorts the rows best first by the sort key
(``tvmmp``, or any column of [`SORT_COLUMNS`][mjtvm.jobs.rank_order.SORT_COLUMNS]: every measure is
better higher) and numbers them (``rank``, 1 = best); [`object_rows()`][mjtvm.jobs.rank_order.object_rows]
is ``NAME-objects.csv``: per object, its grasps, how many were evaluated and feasible, the TVMMP's
median and maximum.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from mjtvm.errors import ParamError
from mjtvm.jobs.rank_index import RankIndex
from mjtvm.jobs.rank_row import CLASSIC_COLUMNS

__all__ = [
    "OBJECT_COLUMNS",
    "SORT_COLUMNS",
    "check_sort",
    "index_objects",
    "object_rows",
    "objects_summary",
    "ranked_rows",
    "with_rank",
]

SORT_COLUMNS = ("tvmmp", *(c for c in CLASSIC_COLUMNS if c != "force_closure"))
"""The numeric measures ``--sort`` accepts (higher is better for each; ``epsilon_linf_gap`` is
the bracket of ``epsilon_linf`` and sorts as the others do)."""

OBJECT_COLUMNS = ("object", "count", "evaluated", "feasible", "tvmmp_median", "tvmmp_max")
"""The columns of ``NAME-objects.csv`` (``tvmmp_*`` in the TVMMP's unit, empty without a
feasible grasp)."""


def check_sort(column: str) -> str:
    """``column`` if ``--sort`` accepts it.

    Raises
    ------
    ParamError
        Not one of [`SORT_COLUMNS`][mjtvm.jobs.rank_order.SORT_COLUMNS].
    """
    if column not in SORT_COLUMNS:
        raise ParamError("sort", f"expected one of {', '.join(SORT_COLUMNS)}, got {column!r}")
    return column


def ranked_rows(rows: Sequence[dict[str, Any]], key: str = "tvmmp") -> list[dict[str, Any]]:
    """The rows best first, each with its ``rank``.

    Parameters
    ----------
    rows
        The rows ([`RankRow.to_dict()`][mjtvm.jobs.rank_row.RankRow.to_dict], plus ``inputs``).
    key
        The sort column ([`SORT_COLUMNS`][mjtvm.jobs.rank_order.SORT_COLUMNS]), descending.

    Returns
    -------
    list of dict
        First the evaluated feasible rows with a value of ``key``, descending (ties: id), ranked
        1, 2, ...; then the evaluated rows that are infeasible or lack ``key``; then the failed
        rows (these two in the dataset's order, ``rank`` ``None``).
    """
    check_sort(key)
    index = RankIndex.from_rows(rows, key)
    ranked = index.ranked
    return [with_rank(rows[i], n, ranked) for n, i in enumerate(index.order(lambda i: str(rows[i]["id"])), 1)]


def with_rank(row: Mapping[str, Any], n: int, ranked: int) -> dict[str, Any]:
    """A copy of the ``n``-th row of [`RankIndex.order()`][mjtvm.jobs.rank_index.RankIndex.order]
    with its ``rank``: ``n`` among the first ``ranked`` rows (the ranked ones), else ``None``."""
    out = dict(row)
    out["rank"] = n if n <= ranked else None
    return out


def index_objects(index: RankIndex) -> list[dict[str, Any]]:
    """[`object_rows()`][mjtvm.jobs.rank_order.object_rows] from a [`RankIndex`][mjtvm.jobs.rank_index.RankIndex]."""
    out = []
    for code, name in enumerate(index.objects):
        mine = index.obj == code
        values = index.tvmmp[mine & index.evaluated & ~np.isnan(index.tvmmp)]
        out.append(
            {
                "object": name,
                "count": int(mine.sum()),
                "evaluated": int((mine & index.evaluated).sum()),
                "feasible": int((mine & index.feasible).sum()),
                "tvmmp_median": float(np.median(values)) if len(values) else None,
                "tvmmp_max": float(values.max()) if len(values) else None,
            }
        )
    return out


def object_rows(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per object (sorted by name): ``count`` grasps, ``evaluated`` (not failed), ``feasible``,
    ``tvmmp_median`` and ``tvmmp_max`` over the feasible ones (``None`` without one)."""
    return index_objects(RankIndex.from_rows(rows))


def objects_summary(objects: Sequence[Mapping[str, Any]]) -> str:
    """One line per object of [`object_rows()`][mjtvm.jobs.rank_order.object_rows], for the stderr summary."""
    lines = []
    for o in objects:
        tail = (
            f", TVMMP median {o['tvmmp_median']:.4g}, max {o['tvmmp_max']:.4g}"
            if o["tvmmp_max"] is not None
            else ""
        )
        lines.append(
            f"  {o['object']}: {o['count']} grasps, {o['evaluated']} evaluated, {o['feasible']} feasible{tail}"
        )
    return "\n".join(["per object:", *lines]) if lines else ""
