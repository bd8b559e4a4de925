"""``mjtvm rank``: penetration as data, no-contact rows, sorting and the rank column, --measures."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mjtvm.jobs.rank import batch_models, rank_row
from mjtvm.jobs.rank_files import RankFiles, run_rank_files
from mjtvm.jobs.rank_order import object_rows, ranked_rows
from mjtvm.jobs.rank_row import CLASSIC_COLUMNS

ROOT = Path(__file__).resolve().parents[2]
GRASP = str(ROOT / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml")
DATASET = ROOT / "mjtvm" / "data" / "examples" / "shadow-sphere-dataset.npz"
RADIUS = 0.025  # m: the sphere of the grasp file
AWAY = np.array([0, -0.05, 0])  # m: a shift of the sphere that leaves every finger


def _subset(tmp_path: Path, ids: list[str], scale: dict[str, float] | None = None) -> Path:
    d = np.load(DATASET)
    keep = [list(d["id"]).index(i) for i in ids]
    arrays = {k: d[k][keep] for k in d.files}
    for n, i in enumerate(ids):
        arrays["obj_scale"][n] = (scale or {}).get(i, arrays["obj_scale"][n])
    out = tmp_path / "subset.npz"
    np.savez(out, **arrays)
    return out


def _rows(path: Path, **kw: Any) -> list[dict[str, Any]]:
    from mjtvm.jobs.rank_inputs import read_datasets

    batch = batch_models(GRASP)
    return [rank_row(batch, e, **kw) for e in read_datasets(GRASP, [str(path)])]


@pytest.fixture(scope="module")
def pushed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Grasp 003 with the sphere grown by 2 mm: every fingertip 2 mm inside it."""
    tmp = tmp_path_factory.mktemp("pushed")
    s0 = float(np.load(DATASET)["obj_scale"][3])  # the grasp's own scale: radius s0 * RADIUS
    return _subset(tmp, ["shadow-sphere-003"], {"shadow-sphere-003": s0 + 0.002 / RADIUS})


def test_a_grasp_2_mm_inside_is_evaluated_and_flagged(pushed: Path) -> None:
    (row,) = _rows(pushed)
    assert row["failure"] is None and row["feasible"] and row["tvmmp"] > 0
    assert row["penetration"] == pytest.approx(0.002, abs=1e-4)
    assert row["nearest_distance"] == pytest.approx(-0.002, abs=1e-4)
    assert row["penetration_exceeded"] is True
    (refused,) = _rows(pushed, refuse_penetration=True)
    assert refused["failure"] == "penetration" and refused["tvmmp"] is None
    assert "mm inside the object > max_penetration 1 mm" in refused["reason"]
    assert refused["penetration"] == pytest.approx(0.002, abs=1e-4)


def test_a_grasp_within_max_penetration_is_not_flagged(tmp_path: Path) -> None:
    (row,) = _rows(_subset(tmp_path, ["shadow-sphere-003"]))
    assert row["penetration_exceeded"] is False and 0.0 <= row["penetration"] < 1e-6
    assert row["nearest_distance"] == pytest.approx(-row["penetration"])


def test_an_open_hand_is_no_contact_with_its_nearest_distance(tmp_path: Path) -> None:
    (row,) = _rows(_subset(tmp_path, ["shadow-sphere-032-open"]))
    assert row["failure"] == "no contact" and "does not touch the object: nearest distance" in row["reason"]
    # Only the opened finger is off: the others still touch, and the column is theirs.
    assert row["nearest_distance"] is not None and row["nearest_distance"] <= 1e-4


def test_contact_rules_without_any_touch_is_no_contact_not_grasp(tmp_path: Path) -> None:
    """A rule-typed grasp that touches nothing was ``failure = grasp`` ("no hinge or slide joint
    moves any contact geom"): now ``no contact`` with the nearest distance."""
    import tomllib

    from mjtvm.jobs.rank import rank_rows
    from mjtvm.jobs.rank_inputs import read_datasets
    from tests.support.documents import format_toml

    doc = tomllib.loads(Path(GRASP).read_text())
    del doc["contacts"]
    doc["contact_rules"] = [{"body": "*distal*", "type": "F"}]
    doc["model"] = str(Path(GRASP).parent / doc["model"])
    grasp = tmp_path / "rules.toml"
    grasp.write_text(format_toml(doc))
    z = np.load(DATASET)
    arrays = {k: v[[3]] for k, v in z.items()}
    arrays["obj_pose"][0, :3] += AWAY  # the sphere away from every finger
    np.savez(tmp_path / "d.npz", **arrays)
    (row,) = rank_rows(str(grasp), read_datasets(str(grasp), [str(tmp_path / "d.npz")]), progress=False)
    assert row["failure"] == "no contact", row["reason"]
    assert "no geom touches the object: nearest distance" in row["reason"]
    assert row["nearest_distance"] is not None and 0.01 < row["nearest_distance"] < 0.1
    assert f"{1e3 * row['nearest_distance']:.3g} mm" in row["reason"]


def test_rows_are_sorted_and_ranked(tmp_path: Path) -> None:
    run_rank_files(
        RankFiles(GRASP, (str(DATASET),), out=tmp_path, quiet=True, plots=False),
        emit=lambda _: None,
        notice=lambda _: None,
    )
    rows = json.loads((tmp_path / "rank.json").read_text())
    ranked = [r for r in rows if r["rank"] is not None]
    assert [r["rank"] for r in ranked] == list(range(1, len(ranked) + 1))
    values = [r["tvmmp"] for r in ranked]
    assert values == sorted(values, reverse=True) and len(ranked) >= 25
    # After the ranked rows: the infeasible, then the failed ones, none ranked.
    tail = rows[len(ranked) :]
    groups = [0 if r["failure"] is None else 1 for r in tail]
    assert groups == sorted(groups) and all(r["tvmmp"] is None for r in tail)
    assert rows[0]["tvmmp"] == max(values)
    # The closed grasps (6.5 mm inside) are evaluated and flagged; the open ones fail.
    closed = [r for r in rows if r["id"].endswith("-closed")]
    assert closed and all(r["penetration_exceeded"] and r["failure"] is None for r in closed)
    csv = (tmp_path / "rank.csv").read_text().splitlines()
    header = csv[0].split(",")
    assert header[:6] == ["id", "source", "index", "object", "scale", "rank"]
    assert {"penetration", "nearest_distance", "penetration_exceeded"} <= set(header)
    objects = (tmp_path / "rank-objects.csv").read_text().splitlines()
    assert objects[0] == "object,count,evaluated,feasible,tvmmp_median,tvmmp_max"
    (ball,) = object_rows(rows)
    assert ball["count"] == 36 and ball["evaluated"] == 34 and ball["tvmmp_max"] == max(values)
    assert objects[1].startswith("ball,36,34,")


def test_sort_by_epsilon_l1(tmp_path: Path) -> None:
    rows = _rows(
        _subset(
            tmp_path, ["shadow-sphere-001", "shadow-sphere-002", "shadow-sphere-003", "shadow-sphere-000"]
        )
    )
    by_eps = ranked_rows(rows, "epsilon_l1")
    ranked = [r for r in by_eps if r["rank"] is not None]
    eps = [r["epsilon_l1"] for r in ranked]
    assert eps == sorted(eps, reverse=True) and len(ranked) == 3  # 000 is infeasible: unranked
    assert by_eps[-1]["id"] == "shadow-sphere-000" and by_eps[-1]["rank"] is None
    with pytest.raises(Exception, match="sort"):
        ranked_rows(rows, "contacts")


def test_measures_none_leaves_the_measure_columns_empty(tmp_path: Path) -> None:
    path = _subset(tmp_path, ["shadow-sphere-003"])
    (row,) = _rows(path, measures="none")
    (full,) = _rows(path)
    assert row["tvmmp"] == full["tvmmp"] and full["epsilon_l1"] is not None
    assert all(row[c] is None for c in CLASSIC_COLUMNS)


def test_the_files_written_row_by_row_are_the_whole_texts(tmp_path: Path) -> None:
    from mjtvm.formats.files import write_files
    from mjtvm.jobs.files import csv_text
    from mjtvm.jobs.rank_row import table_columns
    from mjtvm.jobs.rank_tables import rows_csv_chunks, rows_json_chunks, rows_table

    rows = ranked_rows(
        _rows(_subset(tmp_path, ["shadow-sphere-000", "shadow-sphere-003", "shadow-sphere-032-open"]))
    )
    flat = rows_table(rows)
    whole_csv = csv_text(flat, table_columns(flat), cell=lambda v: "" if v is None else v)
    for chunks, whole in (
        (rows_json_chunks(rows), json.dumps(rows, indent=1) + "\n"),
        (rows_json_chunks([]), "[]\n"),
        (rows_csv_chunks(rows, table_columns(flat)), whole_csv),
    ):
        (path,) = write_files({tmp_path / "out.txt": chunks})
        assert path.read_bytes().decode("utf-8") == whole


def test_parquet_written_in_row_groups_is_the_table_pyarrow_infers(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The streamed Parquet (a schema from the rows' Python types, one row group per batch)
    # reads back as pyarrow's own inference of the whole table: the same columns, types, values.
    import io

    import pyarrow as pa
    import pyarrow.parquet as pq

    import mjtvm.jobs.rank_tables as rank_tables
    from mjtvm.jobs.rank_row import table_columns

    rows = ranked_rows(
        _rows(_subset(tmp_path, ["shadow-sphere-000", "shadow-sphere-003", "shadow-sphere-032-open"]))
    )
    flat = rank_tables.rows_table(rows)
    columns = table_columns(flat)
    expected = pa.Table.from_pylist([{c: r.get(c) for c in columns} for r in flat])
    monkeypatch.setattr(rank_tables, "PARQUET_BATCH", 2)
    data = rank_tables.rows_parquet(rows)
    assert data is not None
    got = pq.read_table(io.BytesIO(data))
    assert pq.ParquetFile(io.BytesIO(data)).num_row_groups == 2
    assert got.schema == expected.schema
    assert got.to_pylist() == expected.to_pylist()
