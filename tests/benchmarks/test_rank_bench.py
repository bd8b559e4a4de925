"""`benchmarks.rank`: the rows of ``mjtvm rank``'s speed and memory, and their rendering."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from benchmarks import rank as bench_rank
from benchmarks.report import rank_rows

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def rank_report() -> dict[str, Any]:
    # 22 joints: ~0.3 s a grasp; --verify: ~0.5 s a simulated grasp
    return bench_rank.bench_rank(repeats=1, sizes=(8, 16), grasps_22=4, verify_grasps=4)


def test_rank_rows_carry_cpu_wall_and_core_share(rank_report: dict[str, Any]) -> None:
    th = rank_report["throughput"]
    assert th["grasps"] == 36
    for key in ("classic", "none"):
        r = th[key]
        assert r["cpu_s"] > 0 and r["wall_s"] > 0
        assert r["grasps_per_cpu_s"] == pytest.approx(36 / r["cpu_s"])
        assert r["core_share"] == pytest.approx(r["cpu_s"] / r["wall_s"])
        assert r["loaded"] == (r["core_share"] < bench_rank.CORE_SHARE_MIN)
        assert (r["met"] is None) if r["loaded"] else isinstance(r["met"], bool)
    assert th["classic"]["cpu_s"] > th["none"]["cpu_s"]  # the classic measures cost something
    t22 = rank_report["throughput_22"]  # issue 34's hand: 22 joints, 36 LPs a grasp
    assert (t22["joints"], t22["contacts"], t22["lps"], t22["grasps"]) == (22, 5, 36, 4)
    for key in ("classic", "none"):
        r = t22[key]
        assert r["grasps_per_cpu_s"] == pytest.approx(t22["grasps"] / r["cpu_s"])
        assert r["target"] == th[key]["target"] and r["loaded"] == (
            r["core_share"] < bench_rank.CORE_SHARE_MIN
        )
    f = rank_report["p2_floor"]
    assert f["states"] == 32 and f["lps"] >= f["states"]
    # HiGHS alone runs every LP; the compiled pass fewer, and its whole call includes its runs
    assert f["highs_runs"] >= f["lps"] and 1 <= f["highs_runs_compiled"] < f["highs_runs"]
    assert 0 < f["highs_run_compiled_s"] < f["wall_s"] and f["highs_run_s"] < f["highs_path"]["wall_s"]
    assert f["ratio"] == pytest.approx(f["wall_s"] / f["highs_run_s"], rel=0.5)
    f22 = rank_report["p2_floor_22"]  # the 22-joint hand's batch: 36 LPs a grasp, 6 REFS vertices
    assert f22["states"] == t22["grasps"] and f22["lps"] == 36 * f22["states"]
    assert f22["highs_runs"] >= f22["lps"] and 1 <= f22["highs_runs_compiled"] < f22["lps"] // 6
    assert (
        rank_report["fingers"]["per_fingers"]["32"]["lps"]
        == rank_report["fingers"]["per_fingers"]["16"]["lps"]
    )
    assert (
        rank_report["jobs"]["rows_identical"] and rank_report["jobs"]["grasps"] == 36 * bench_rank.JOBS_COPIES
    )
    v = rank_report["verify"]  # rank --verify as a process: the example's first 4 grasps
    assert "error" not in v, v
    assert v["grasps"] == 4 and 0 < v["simulated"] <= 4 and v["main_cpu_s"] <= v["cpu_s"]
    assert v["grasps_per_cpu_s"] == pytest.approx(4 / v["cpu_s"])
    assert v["core_share"] == pytest.approx(v["cpu_s"] / v["wall_s"])
    assert v["target"] == bench_rank.TARGETS["rank_verify"] == 5.0
    assert v["loaded"] == (v["core_share"] < bench_rank.CORE_SHARE_MIN)
    assert (v["met"] is None) if v["loaded"] else v["met"] == (v["grasps_per_cpu_s"] >= 5.0)
    sizes = rank_report["memory"]["sizes"]
    assert set(sizes) == {"8", "16"} and all(
        s["exit"] == 0 and s["peak_rss_mib"] > 50 for s in sizes.values()
    )
    assert "mib_per_1000_grasps" in rank_report["memory"]
    dask = rank_report["memory"]["dask"]  # the largest size again on 2 Dask worker processes
    assert dask["grasps"] == 16 and dask["workers"] == 2 and dask["files_identical"] is True


def test_a_loaded_row_is_never_met() -> None:
    assert bench_rank._verdict(200.0, 40.0, 0.5, at_least=True) == {
        "target": 40.0, "core_share": 0.5, "loaded": True, "met": None,
    }  # fmt: skip
    assert bench_rank._verdict(200.0, 40.0, 0.95, at_least=True)["met"] is True
    assert bench_rank._verdict(2.0, 1.5, 1.0, at_least=False)["met"] is False


def test_rows_and_page_render_every_measurement(rank_report: dict[str, Any]) -> None:
    lines = rank_rows({"rank": rank_report})
    assert sum("grasps/CPU-s" in line for line in lines) == 5  # 13 and 22 joints x 2, --verify
    assert sum("rank memory, " in line for line in lines) == 2
    spec = importlib.util.spec_from_file_location("bench_page", ROOT / "tools" / "bench_page.py")
    assert spec is not None and spec.loader is not None
    bench_page = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench_page)
    table = bench_page._rank({"rank": rank_report})
    # head, the rows (13 joints, 22 joints with HiGHS's ceiling, the two batches' P2 over HiGHS
    # each with HiGHS alone beside it, 32 over 16 fingers, 2 jobs, --verify), memory, Dask
    assert len([row for row in table if row.startswith("| ")]) == 1 + 2 + 3 + 2 * 2 + 2 + 1 + 2 + 1
    floors = [row for row in table if "over HiGHS-alone `run`" in row]
    assert len(floors) == 2 and "22-joint Shadow hand, 4 states, 144 LPs" in floors[1]
    assert sum("the same on HiGHS alone" in row for row in table) == 2
    (verify,) = [row for row in table if "`mjtvm rank --verify` as a process" in row]
    assert f"{rank_report['verify']['grasps_per_cpu_s']:.3g} grasps/CPU-s" in verify
    assert sum("22-joint Shadow hand, 36 LPs" in row for row in table) == 2
    (ceiling,) = [row for row in table if "the ceiling of any code around it" in row]
    none = rank_report["throughput_22"]["none"]
    assert f"{none['highs_ceiling_grasps_per_s']:.3g} grasps/s" in ceiling
    assert none["highs_ceiling_grasps_per_s"] == pytest.approx(1e3 / none["highs_run_ms_per_grasp"])
    old = {
        k: v for k, v in rank_report.items() if k not in ("throughput_22", "verify", "p2_floor_22")
    }  # from before
    old["p2_floor"] = {k: v for k, v in old["p2_floor"].items() if k != "highs_path"}
    assert len([row for row in bench_page._rank({"rank": old}) if row.startswith("| ")]) == 1 + 2 + 3 + 2 + 1
    loaded = {**rank_report, "throughput": {**rank_report["throughput"]}}
    loaded["throughput"]["classic"] = {**loaded["throughput"]["classic"], "loaded": True, "met": None}
    assert "| loaded |" in "\n".join(bench_page._rank({"rank": loaded}))


def test_generated_dataset_repeats_the_example_with_distinct_scales(tmp_path: Path) -> None:
    path = bench_rank.write_dataset(tmp_path / "g.npz", 40)
    with np.load(path) as z, np.load(bench_rank._dataset()) as ex:
        assert len(set(z["id"].tolist())) == 40 and len(set(z["obj_scale"].tolist())) == 40
        np.testing.assert_array_equal(z["grasp_qpos"][36:], ex["grasp_qpos"][:4])
        np.testing.assert_allclose(z["obj_scale"][:36], ex["obj_scale"], rtol=1e-4)
