"""``mjtvm.jobs.rank_index``: the order from a few numbers a row equals the plain sort of the rows."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from mjtvm.jobs.rank_index import RankIndex
from mjtvm.jobs.rank_order import ranked_rows


def _rows(seed: int, n: int) -> list[dict[str, Any]]:
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        kind = rng.integers(0, 4)
        failed = kind == 3
        feasible = kind in (0, 1)
        tvmmp = float(rng.choice([0.0, 0.25, 0.5, rng.uniform(0, 1)])) if feasible else None
        out.append(
            {
                "id": f"g{rng.integers(0, 10 * n)}-{i}",
                "object": f"obj{rng.integers(0, 3)}",
                "rank": None,
                "failure": "no contact" if failed else None,
                "feasible": feasible and not failed,
                "tvmmp": None if failed else tvmmp,
                "epsilon_l1": None if failed or kind == 1 else float(rng.choice([0.1, 0.2])),
                "reason": None,
                "certified": True,
                "limiting": None,
                "alpha": None,
                "status": None,
            }
        )
    return out


def _plain(rows: list[dict[str, Any]], key: str) -> list[int]:
    """The definition of the order (docs/datasets.md), as a sort of the rows themselves."""

    def group(r: dict[str, Any]) -> int:
        if r["failure"] is not None:
            return 2
        return 0 if r["feasible"] and r.get(key) is not None else 1

    return sorted(
        range(len(rows)),
        key=lambda i: (
            group(rows[i]),
            -float(rows[i][key]) if group(rows[i]) == 0 else 0.0,
            rows[i]["id"] if group(rows[i]) == 0 else "",
            i,
        ),
    )


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("key", ["tvmmp", "epsilon_l1"])
def test_order_is_the_plain_sort(seed: int, key: str) -> None:
    rows = _rows(seed, 200)  # many ties: TVMMP 0, 0.25 and 0.5 repeat
    index = RankIndex.from_rows(rows, key)
    assert list(index.order(lambda i: rows[i]["id"])) == _plain(rows, key)
    ranked = ranked_rows(rows, key)
    assert [r["id"] for r in ranked] == [rows[i]["id"] for i in _plain(rows, key)]
    n = sum(r["rank"] is not None for r in ranked)
    assert [r["rank"] for r in ranked[:n]] == list(range(1, n + 1)) and n == index.ranked


def test_counts_and_objects() -> None:
    rows = _rows(7, 50)
    index = RankIndex.from_rows(rows)
    assert index.objects == tuple(sorted({r["object"] for r in rows}))
    assert int((~index.evaluated).sum()) == sum(r["failure"] is not None for r in rows)
    assert index.failures["no contact"] == sum(r["failure"] is not None for r in rows)
    got = np.where(np.isnan(index.tvmmp), -1.0, index.tvmmp)
    want = [-1.0 if r["tvmmp"] is None else r["tvmmp"] for r in rows]
    assert list(got) == want
