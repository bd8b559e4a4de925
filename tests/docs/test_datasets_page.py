"""docs/physics-check.md's dataset benchmark is ``tools/datasets_page.py``'s output from the committed
report (``benchmarks/results/validate-datasets.json``, written by ``tools/validate_datasets.py``)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _tool(name: str) -> ModuleType:
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        spec = importlib.util.spec_from_file_location(name, ROOT / "tools" / f"{name}.py")
        module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
        spec.loader.exec_module(module)  # type: ignore[union-attr]
    finally:
        sys.path.remove(str(ROOT / "tools"))
    return module


def _auc(
    measure: str, target: str, auc: float | None, lo: float | None = None, hi: float | None = None
) -> dict:
    return {"measure": measure, "target": target, "auc": auc, "ci_low": lo, "ci_high": hi}


def _report(**run: Any) -> dict[str, Any]:
    base = {
        "label": "hand-a",
        "grasp": "models/a.toml",
        "make": "python tools/make_rank_dataset.py -n 10 --out DIR/hand-a.npz",
        "rank": "mjtvm rank models/a.toml DIR/hand-a.npz --verify",
        "grasps": 10,
        "evaluated": 9,
        "simulated": 8,
        "held": 2,
        "speed_success": 6,
        "auc": [
            _auc("tvmmp", "sim_speed_success", 0.6371, 0.5523, 0.7184),
            _auc("alpha_l0", "sim_speed_success", 0.614),
            _auc("alpha_l1", "sim_speed_success", 0.637),
            _auc("tvmmp", "sim_hold", None),
        ],
        "cpu_s": 4.0,
        "wall_s": 4.0,
        "jobs": 1,
        "core_share": 1.0,
    }
    return {
        "schema": "validate-datasets/1",
        "command": "python tools/validate_datasets.py",
        "date": "2026-12-03",
        "runs": [{**base, **run}],
    }


def test_counts_and_aucs_are_written_with_their_intervals() -> None:
    text = _tool("datasets_page").render(_report())
    assert (
        "| hand-a | 10 | 9 | 8 | 2 (25 %) | 6 (75 %) | 2.50 grasps/CPU-s (4 CPU-s, 4 s wall on 1 process, core share 1.00; target 5: missed) |"
        in text
    )
    assert "| TVMMP | 0.637 (0.552-0.718) |" in text
    assert "| alpha_l (per RVDS direction: min-max) | 0.614-0.637 |" in text
    # the hold's classes: one empty, so no AUC; a measure absent from the run: no AUC either
    hold = text.split("simulated **hold**")[1]
    assert "| TVMMP | - |" in hold and "| epsilon L1 | - |" in text


def test_the_speed_target_is_met_only_on_a_quiet_core() -> None:
    render = _tool("datasets_page").render
    assert "target 5: met" in render(_report(cpu_s=2.0, wall_s=2.0))  # 5 grasps per CPU-s
    loaded = render(_report(cpu_s=1.0, wall_s=2.0, core_share=0.5))
    assert "target 5: not measured (core share below 0.8)" in loaded


def test_the_machine_is_named_beside_the_cpu_times() -> None:
    render = _tool("datasets_page").render
    machine = {"cpu": "AMD EPYC", "logical_cpus": 2, "usable_cpus": 2}
    assert "(2026-12-03, on AMD EPYC (2 usable cores)). Each run" in render({**_report(), "machine": machine})
    assert "(2026-12-03). Each run" in render(_report())  # a report from before the machine was kept


def test_check_fails_on_a_stale_page(tmp_path: Path) -> None:
    dp = _tool("datasets_page")
    report = tmp_path / "report.json"
    report.write_text(__import__("json").dumps(_report()), encoding="utf-8")
    page = tmp_path / "page.md"
    page.write_text(f"# P\n\n{dp.BEGIN}\nold\n{dp.END}\n\nprose\n", encoding="utf-8")
    args = ["--page", str(page), "--report", str(report)]
    assert dp.main(["--check", *args]) == 1
    assert dp.main(["--write", *args]) == 0
    assert dp.main(["--check", *args]) == 0
    text = page.read_text(encoding="utf-8")
    assert text.startswith("# P\n\n") and text.endswith("\n\nprose\n") and "| hand-a | 10 |" in text


def test_render_refuses_another_schema() -> None:
    with pytest.raises(ValueError, match="validate-datasets/1"):
        _tool("datasets_page").render({**_report(), "schema": "validate-datasets/0"})


def test_the_counts_come_from_the_rows() -> None:
    rows = [
        {"failure": None, "sim_hold": True, "sim_speed_success": True},
        {"failure": None, "sim_hold": False, "sim_speed_success": None},  # no direction to test
        {"failure": None, "sim_hold": None, "sim_speed_success": None},  # infeasible: not simulated
        {"failure": "grasp", "sim_hold": None, "sim_speed_success": None},
    ]
    counts = _tool("validate_datasets").run_summary(rows)
    assert counts == {"grasps": 4, "evaluated": 3, "simulated": 2, "held": 1, "speed_success": 1}


def test_the_page_is_the_generator_output() -> None:
    assert _tool("datasets_page").main(["--check"]) == 0, "run python tools/datasets_page.py --write"
