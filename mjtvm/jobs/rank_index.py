r"""What ``mjtvm rank`` keeps of each row to order, count and draw them: a few numbers a row.

A [`RankIndex`][mjtvm.jobs.rank_index.RankIndex] holds, per row, its position in the datasets,
its group (ranked, evaluated without a rank, failed), its sort value, TVMMP, epsilon L1 and
object as numpy arrays (about 50 bytes a row), and the counts of the summary; the rows
themselves stay where they are (a list in memory, or the log on disk:
[`mjtvm.jobs.rank_log`][mjtvm.jobs.rank_log]). The order, the ``rank`` column, the per-object
table, the summary and the plots are computed from it
([`mjtvm.jobs.rank_order`][mjtvm.jobs.rank_order]), so that ranking 40,000 grasps or 400 needs
the same memory.
"""

from __future__ import annotations

from array import array
from collections import Counter
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.jobs.rank_row import flat_row

__all__ = ["RankIndex", "RankIndexBuilder", "most_common"]

RANKED, UNRANKED, FAILED = 0, 1, 2
"""A row's group: evaluated, feasible and with the sort key; evaluated without it (infeasible,
or the measure missing); failed."""


def most_common(counts: Counter[str]) -> list[tuple[str, int]]:
    """``counts`` by count, descending, ties by name (the same whichever order rows came in)."""
    return sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))


def _value(v: Any) -> float:
    return float("nan") if v is None else float(v)


@dataclass(frozen=True, eq=False)
class RankIndex:
    """The numbers of ``n`` rows that order, count and draw them.

    Attributes
    ----------
    key
        The sort column (``tvmmp``, or ``--sort``'s).
    seq
        ``(n,)`` each row's position in the datasets (from 0).
    group
        ``(n,)`` 0 ranked, 1 evaluated without a rank, 2 failed.
    value
        ``(n,)`` the sort key of a ranked row (NaN otherwise).
    tvmmp
        ``(n,)`` m/s per unit RVDS vertex: the TVMMP of an evaluated row, NaN without one.
    epsilon
        ``(n,)`` the L1 epsilon of an evaluated row, NaN without one.
    obj
        ``(n,)`` the row's object, an index into ``objects``.
    objects
        The objects' names, sorted.
    evaluated, feasible
        ``(n,)`` not failed; evaluated and feasible.
    failures, causes
        Failed rows by ``failure``; evaluated rows with TVMMP 0 or none by the cause of their
        ``reason``.
    uncertified, deep
        Rows whose ``certified`` is ``False``; evaluated rows deeper than ``max_penetration``.
    columns
        The flattened columns (`flat_row()`) in order of first appearance, each with the
        Python types of its values (for Parquet's schema).
    """

    key: str
    seq: NDArray[np.int64]
    group: NDArray[np.int8]
    value: NDArray[np.float64]
    tvmmp: NDArray[np.float64]
    epsilon: NDArray[np.float64]
    obj: NDArray[np.int32]
    objects: tuple[str, ...]
    evaluated: NDArray[np.bool_]
    feasible: NDArray[np.bool_]
    failures: Counter[str]
    causes: Counter[str]
    uncertified: int
    deep: int
    columns: dict[str, set[type]] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.seq)

    @property
    def ranked(self) -> int:
        """How many rows are ranked (group 0)."""
        return int((self.group == RANKED).sum())

    @classmethod
    def from_rows(cls, rows: Iterable[Mapping[str, Any]], key: str = "tvmmp") -> RankIndex:
        """The index of rows held in memory, their positions ``0, 1, ...``."""
        builder = RankIndexBuilder(key)
        for i, row in enumerate(rows):
            builder.add(row, i)
        return builder.build()

    def order(self, row_id: Callable[[int], str]) -> NDArray[np.int64]:
        """The rows' positions in this index, best first: the ranked rows by the sort key
        descending (ties by id, then position), then the evaluated unranked rows, then the
        failed ones, these two by position. ``row_id(i)``: the id of row ``i`` (read only for
        ties)."""
        ranked = self.group == RANKED
        neg = np.where(ranked, -np.nan_to_num(self.value, nan=0.0), 0.0)
        order = np.lexsort((self.seq, neg, self.group))
        m = int(ranked.sum())
        top = order[:m]
        v = neg[top]
        starts = np.flatnonzero(np.r_[True, v[1:] != v[:-1]])
        ends = np.r_[starts[1:], m]
        for a, b in zip(starts, ends, strict=True):
            if b - a > 1:  # equal values: by id, then by position
                run = sorted(top[a:b], key=lambda i: (row_id(int(i)), int(self.seq[i])))
                top[a:b] = run
        order[:m] = top
        return order


class RankIndexBuilder:
    """A [`RankIndex`][mjtvm.jobs.rank_index.RankIndex] made one row at a time, holding only its numbers.

    Parameters
    ----------
    key
        The sort column.
    """

    def __init__(self, key: str = "tvmmp") -> None:
        self.key = key
        self._seq = array("q")
        self._group = array("b")
        self._value, self._tvmmp, self._epsilon = array("d"), array("d"), array("d")
        self._obj = array("l")
        self._names: dict[str, int] = {}
        self._evaluated, self._feasible = array("b"), array("b")
        self.failures: Counter[str] = Counter()
        self.causes: Counter[str] = Counter()
        self.uncertified = self.deep = 0
        self.columns: dict[str, set[type]] = {}

    def add(self, row: Mapping[str, Any], seq: int) -> None:
        """Add a row ([`RankRow.to_dict()`][mjtvm.jobs.rank_row.RankRow.to_dict]) at position ``seq``."""
        failed = row["failure"] is not None
        tvmmp = None if failed else row["tvmmp"]
        if failed:
            group = FAILED
            self.failures[str(row["failure"])] += 1
        else:
            group = RANKED if row["feasible"] and row.get(self.key) is not None else UNRANKED
            reason = row.get("reason")
            if reason and (tvmmp is None or tvmmp <= 0.0):
                self.causes[reason.split(": ")[1]] += 1
            self.deep += row.get("penetration_exceeded") is True
        self.uncertified += row.get("certified") is False
        self._seq.append(seq)
        self._group.append(group)
        self._value.append(_value(row.get(self.key)) if group == RANKED else float("nan"))
        self._tvmmp.append(_value(tvmmp))
        self._epsilon.append(float("nan") if failed else _value(row.get("epsilon_l1")))
        self._obj.append(self._names.setdefault(str(row["object"]), len(self._names)))
        self._evaluated.append(not failed)
        self._feasible.append(not failed and bool(row["feasible"]))
        for k, v in flat_row(row).items():
            kinds = self.columns.setdefault(k, set())
            if v is not None:
                kinds.add(type(v))

    def build(self) -> RankIndex:
        """The index of the rows added."""
        names = sorted(self._names)
        where = np.empty(len(self._names), dtype=np.int32)
        for new, name in enumerate(names):
            where[self._names[name]] = new
        obj = (
            np.frombuffer(self._obj, dtype=np.int_).astype(np.int32)
            if len(self._obj)
            else np.zeros(0, np.int32)
        )
        return RankIndex(
            key=self.key,
            seq=np.frombuffer(self._seq, dtype=np.int64).copy(),
            group=np.frombuffer(self._group, dtype=np.int8).copy(),
            value=np.frombuffer(self._value, dtype=np.float64).copy(),
            tvmmp=np.frombuffer(self._tvmmp, dtype=np.float64).copy(),
            epsilon=np.frombuffer(self._epsilon, dtype=np.float64).copy(),
            obj=where[obj] if len(obj) else obj,
            objects=tuple(names),
            evaluated=np.frombuffer(self._evaluated, dtype=np.int8).astype(bool),
            feasible=np.frombuffer(self._feasible, dtype=np.int8).astype(bool),
            failures=self.failures,
            causes=self.causes,
            uncertified=self.uncertified,
            deep=self.deep,
            columns=self.columns,
        )
