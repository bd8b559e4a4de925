"""The rank row's one statement of its fields (mjtvm.jobs.rank_row) and the jobs' CSV writer."""

from __future__ import annotations

import csv
import io
from dataclasses import FrozenInstanceError, fields

import pytest

from mjtvm.jobs.files import csv_text
from mjtvm.jobs.rank_row import CLASSIC_COLUMNS, SIM_FIELDS, RankRow, csv_columns, flat_row, table_columns


def test_the_row_keys_and_the_csv_columns_come_from_the_fields() -> None:
    row = RankRow("a:0", "a.npz", 0, "ball", 1.0).to_dict()
    assert list(row) == [f.name for f in fields(RankRow) if f.name not in SIM_FIELDS]
    verified = RankRow("a:0", "a.npz", 0, "ball", 1.0).to_dict(sim=True)  # --verify: the sim_* last
    assert list(verified) == [f.name for f in fields(RankRow)] == [*row, *SIM_FIELDS]
    assert csv_columns() == (
        "id", "source", "index", "object", "scale", "rank", "contacts", "penetration",
        "nearest_distance", "penetration_exceeded", "feasible", "tvmmp",
        "limiting_k", "limiting_l", "certified", "failure", "reason",
    )  # fmt: skip
    assert CLASSIC_COLUMNS == tuple(list(row)[-len(CLASSIC_COLUMNS) :])
    with pytest.raises(FrozenInstanceError):
        RankRow("a:0", "a.npz", 0, "ball", 1.0).id = "b"  # type: ignore[misc]


def test_a_flat_row_has_a_column_per_pair_after_the_leading_ones() -> None:
    row = RankRow(
        "a:0", "a.npz", 0, "ball", 1.0, None, 3, 0.0, 1e-3, False, True, 0.5, [0, 1],
        [[0.7, 0.5], [None, 0.9]], [["optimal"] * 2, ["infeasible", "optimal"]], True,
    ).to_dict()  # fmt: skip
    flat = flat_row({**row, "inputs": "x"})
    assert (flat["limiting_k"], flat["limiting_l"]) == (0, 1)
    assert flat["alpha_k1_l0"] is None and flat["status_k1_l0"] == "infeasible"
    columns = table_columns([flat])
    pairs = [f"alpha_k{k}_l{l}" for k in range(2) for l in range(2)]
    pairs += [f"status_k{k}_l{l}" for k in range(2) for l in range(2)]
    assert columns == [*csv_columns(), *pairs, *CLASSIC_COLUMNS, "inputs"]


def test_csv_text_is_the_csv_module_s() -> None:
    rows = [{"a": 1.5, "b": None}, {"b": "x", "c": True}]
    buf = io.StringIO(newline="")
    writer = csv.DictWriter(buf, fieldnames=["a", "b", "c"], restval="")
    writer.writeheader()
    writer.writerows(rows)
    assert csv_text(rows) == buf.getvalue()
    assert (
        csv_text([{"a": 2, "c": None}], ["c", "a"], cell=lambda v: "" if v is None else v) == "c,a\r\n,2\r\n"
    )
    assert csv_text([]) == "\r\n"
