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


def _validate_dynamics() -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        "validate_dynamics", ROOT / "tools" / "validate_dynamics.py"
    )
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def test_a_merged_run_replaces_its_hands_rows_and_is_listed() -> None:
    """``validate_dynamics.py --merge``: the rerun hand's rows replace the report's (in the tool's
    order of hands), the other hands' rows stay as they were, and the page names both runs."""
    vd, report = _validate_dynamics(), _report()
    first = {k: v for k, v in report.items() if k not in ("merged", "results")}
    base = {**first, "results": [r for r in report["results"] if r["hand"] != "shadow_hand_coupled-sphere"]}
    row = {**base["results"][0], "hand": "shadow_hand_coupled-sphere", "median": 0.5}
    run = {"hands": ["shadow_hand_coupled-sphere"], **{k: first[k] for k in ("states", "stride", "jobs")}}
    run.update(command="python tools/validate_dynamics.py --merge X", date="2026-12-04", wall_s=60.0)
    run.update(cpu_s=30.0, core_share=0.5)
    once = vd.merged(base, [row], run)
    assert [r["hand"] for r in once["results"]][-1] == "shadow_hand_coupled-sphere"
    assert once["results"][:-1] == base["results"] and once["merged"] == [run]
    again = vd.merged(once, [{**row, "median": 0.9}], {**run, "date": "2026-12-05"})
    assert [r["median"] for r in again["results"] if r["hand"] == row["hand"]] == [0.9]
    assert len(again["merged"]) == 1 and again["merged"][0]["date"] == "2026-12-05"
    text = _dynamics_page().render(again)
    assert "The rows of shadow_hand_coupled-sphere from `python tools/validate_dynamics.py --merge X`" in text
    assert "0.5 min of CPU in 1.0 min wall (core share 0.50: other jobs shared the machine)" in text
    assert vd.cause("rh_A_THJ5 1.0 % past its range's speed at t = 2.50 ms") == "speed edge"
