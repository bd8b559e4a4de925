"""docs/dynamics.md's validation tables are ``tools/dynamics_page.py``'s output from the committed
validation report (``benchmarks/results/validate-dynamics.json``)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _dynamics_page() -> ModuleType:
    spec = importlib.util.spec_from_file_location("dynamics_page", ROOT / "tools" / "dynamics_page.py")
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def _report() -> dict:
    return json.loads(
        (ROOT / "benchmarks" / "results" / "validate-dynamics.json").read_text(encoding="utf-8")
    )


def test_dynamics_page_is_the_generator_output() -> None:
    assert _dynamics_page().main(["--check"]) == 0, "run python tools/dynamics_page.py --write"


def test_check_fails_on_a_stale_page(tmp_path: Path) -> None:
    dp = _dynamics_page()
    page = tmp_path / "dynamics.md"
    page.write_text(f"# D\n\n{dp.BEGIN}\nold\n{dp.END}\n\nprose\n", encoding="utf-8")
    assert dp.main(["--check", "--page", str(page)]) == 1
    assert dp.main(["--write", "--page", str(page)]) == 0
    assert dp.main(["--check", "--page", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    assert text.startswith("# D\n\n") and text.endswith("\n\nprose\n") and "| case2 | L |" in text


def test_a_missed_target_is_written_as_such() -> None:
    report = _report()
    row = {**report["results"][0], "median": 1.164, "q1": 1.1, "q3": 1.2, "median_met": False}
    row.update(failing=3, pairs=10, failing_fraction=0.3, failing_met=False)
    text = _dynamics_page().render({**report, "results": [row], "core_share": 0.5})
    assert "**1.164** (1.100-1.200) (outside [0.9, 1.1])" in text
    assert "3 / 10 (30 %) (over 10 %)" in text
    assert "core share 0.50: other jobs shared the machine" in text


def test_render_refuses_another_schema() -> None:
    with pytest.raises(ValueError, match="validate-dynamics/1"):
        _dynamics_page().render({**_report(), "schema": "validate-dynamics/0"})


def test_several_processes_state_that_their_cpu_was_not_measured() -> None:
    report = {**_report(), "jobs": 2, "cpu_s": None, "core_share": None, "wall_s": 600.0}
    text = _dynamics_page().render(report)
    assert "2 processes; 10.0 min wall (the workers' CPU time not measured)." in text


def test_the_second_drive_column_and_a_report_from_before_it() -> None:
    report = _report()
    case2 = report["results"][0]
    text = _dynamics_page().render(report)
    assert (
        f"| {case2['median_ff']:.3f} ({case2['q1_ff']:.3f}-{case2['q3_ff']:.3f}); {case2['spread']:.3f} |"
        in text
    )
    before = {
        k: v for k, v in case2.items() if k not in ("median_ff", "q1_ff", "q3_ff", "spread", "ff_pairs")
    }
    old = _dynamics_page().render({**report, "results": [before]})
    assert "| **1.006** (0.973-1.065) | - |" in old
