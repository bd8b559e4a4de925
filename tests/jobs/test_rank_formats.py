"""``mjtvm rank`` on every dataset layout as the pipelines write it (docs/datasets.md).

The samples under ``tests/data/datasets`` are written by ``tools/make_dataset_samples.py`` (seeded):
DexGraspBench's tree of per-grasp dicts with object folders, DexGraspNet's per-object list of
dicts, and the same sphere grasps as ``.npz`` and ``.csv``.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mjtvm.cli import main

DATA = Path(__file__).resolve().parents[1] / "data" / "datasets"
GRASP = str(
    Path(__file__).resolve().parents[2] / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml"
)


def _rank(tmp_path: Path, *words: str) -> list[dict]:
    out = tmp_path / "out"
    assert main(["rank", GRASP, *words, "--out", str(out), "--quiet", "--no-plots"]) == 0
    return json.loads((out / "rank.json").read_text())


def test_dexgraspbench_tree_ranks_as_it_is(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # obj_path is relative to the benchmark's root ("assets/object/..."), found from the
    # dataset's folder up, whatever the working directory; stems repeat: ids from the paths.
    monkeypatch.chdir(tmp_path)
    rows = sorted(_rank(tmp_path, str(DATA / "dexgraspbench" / "output")), key=lambda r: r["id"])
    assert [r["id"] for r in rows] == [
        "ellipsoid_00/scale009_pose000/0",
        "ellipsoid_00/scale009_pose000/1",
        "ellipsoid_01/scale009_pose000/0",
        "ellipsoid_01/scale009_pose000/1",
    ]
    assert all(r["failure"] is None and r["tvmmp"] > 0.03 for r in rows)
    assert rows[0]["tvmmp"] == pytest.approx(0.038428513389991766, rel=1e-6)
    assert sorted(r["rank"] for r in rows) == [1, 2, 3, 4]


def test_pose_option_ranks_the_pregrasp(tmp_path: Path) -> None:
    grasp = _rank(tmp_path / "g", str(DATA / "dexgraspbench" / "output"))
    pregrasp = _rank(tmp_path / "p", str(DATA / "dexgraspbench" / "output"), "--pose", "pregrasp")
    # The pregrasp's fingers are opened by 0.1 rad: off the object, so no row evaluates as the grasp's.
    assert [r["tvmmp"] for r in pregrasp] != [r["tvmmp"] for r in grasp]
    assert all(r["failure"] == "no contact" for r in pregrasp)


def test_dexgraspnet_npz_and_csv_give_the_same_rows(tmp_path: Path) -> None:
    def by_id(rows: list[dict]) -> list[dict]:  # the files are sorted by TVMMP
        return sorted(rows, key=lambda r: r["id"])

    npz = by_id(_rank(tmp_path / "a", str(DATA / "shadow-sphere.npz")))
    csv = by_id(_rank(tmp_path / "b", str(DATA / "shadow-sphere.csv")))
    net = by_id(_rank(tmp_path / "c", str(DATA / "dexgraspnet" / "shadow-sphere.npy")))
    assert (
        [r["id"] for r in npz]
        == [r["id"] for r in csv]
        == ["shadow-sphere-000", "shadow-sphere-001", "shadow-sphere-002"]
    )
    assert [r["id"] for r in net] == ["shadow-sphere:0", "shadow-sphere:1", "shadow-sphere:2"]
    expected = [r["tvmmp"] for r in npz]
    assert all(v is not None and v > 0.03 for v in expected)
    # CSV: the same float64 numbers; DexGraspNet: the palm's pose through Euler angles, the
    # object moved to the origin (a translation: no alpha changes).
    assert [r["tvmmp"] for r in csv] == pytest.approx(expected, rel=1e-12)
    assert [r["tvmmp"] for r in net] == pytest.approx(expected, rel=1e-6)
