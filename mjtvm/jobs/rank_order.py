r"""The order of ``mjtvm rank``'s rows: sorted by a measure, ranked, summarised per object.

[`ranked_rows()`][mjtvm.jobs.rank_order.ranked_rows] sorts the rows best first by the sort key
(``tvmmp``, or any column of [`SORT_COLUMNS`][mjtvm.jobs.rank_order.SORT_COLUMNS]: every measure is
better higher) and numbers them (``rank``, 1 = best); [`object_rows()`][mjtvm.jobs.rank_order.object_rows]
is ``NAME-objects.csv``: per object, its grasps, how many were evaluated and feasible, the TVMMP's
median and maximum.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from mjtvm.errors import ParamError
from mjtvm.jobs.rank_row import CLASSIC_COLUMNS

__all__ = ["OBJECT_COLUMNS", "SORT_COLUMNS", "check_sort", "object_rows", "objects_summary", "ranked_rows"]

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


def _group(row: dict[str, Any], key: str) -> int:
    """0: ranked (evaluated, feasible, with the key); 1: evaluated, infeasible or without it; 2: failed."""
    if row["failure"] is not None:
        return 2
    return 0 if row["feasible"] and row.get(key) is not None else 1


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
    order = sorted(
        range(len(rows)),
        key=lambda i: (
            _group(rows[i], key),
            -float(rows[i][key]) if _group(rows[i], key) == 0 else 0.0,
            str(rows[i]["id"]) if _group(rows[i], key) == 0 else "",
            i,
        ),
    )
    out = []
    for n, i in enumerate(order, start=1):
        row = dict(rows[i])
        row["rank"] = n if _group(row, key) == 0 else None
        out.append(row)
    return out


def object_rows(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per object (sorted by name): ``count`` grasps, ``evaluated`` (not failed), ``feasible``,
    ``tvmmp_median`` and ``tvmmp_max`` over the feasible ones (``None`` without one)."""
    out = []
    for name in sorted({str(r["object"]) for r in rows}):
        mine = [r for r in rows if str(r["object"]) == name]
        values = [float(r["tvmmp"]) for r in mine if r["failure"] is None and r["tvmmp"] is not None]
        out.append(
            {
                "object": name,
                "count": len(mine),
                "evaluated": sum(r["failure"] is None for r in mine),
                "feasible": sum(r["failure"] is None and bool(r["feasible"]) for r in mine),
                "tvmmp_median": float(np.median(values)) if values else None,
                "tvmmp_max": max(values) if values else None,
            }
        )
    return out


def objects_summary(rows: Sequence[dict[str, Any]]) -> str:
    """One line per object of [`object_rows()`][mjtvm.jobs.rank_order.object_rows], for the stderr summary."""
    lines = []
    for o in object_rows(rows):
        tail = (
            f", TVMMP median {o['tvmmp_median']:.4g}, max {o['tvmmp_max']:.4g}"
            if o["tvmmp_max"] is not None
            else ""
        )
        lines.append(
            f"  {o['object']}: {o['count']} grasps, {o['evaluated']} evaluated, {o['feasible']} feasible{tail}"
        )
    return "\n".join(["per object:", *lines]) if lines else ""
