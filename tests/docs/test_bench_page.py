"""docs/performance.md's measured tables are ``tools/bench_page.py``'s output from the committed
benchmark report (``benchmarks/results/bench.json``)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _bench_page() -> ModuleType:
    spec = importlib.util.spec_from_file_location("bench_page", ROOT / "tools" / "bench_page.py")
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def test_performance_page_is_the_generator_output() -> None:
    assert _bench_page().main(["--check"]) == 0, "run python tools/bench_page.py --write"


def test_check_fails_on_a_stale_page(tmp_path: Path) -> None:
    bp = _bench_page()
    page = tmp_path / "performance.md"
    page.write_text(f"# P\n\n{bp.BEGIN}\nold\n{bp.END}\n\nprose\n", encoding="utf-8")
    assert bp.main(["--check", "--page", str(page)]) == 1
    assert bp.main(["--write", "--page", str(page)]) == 0
    assert bp.main(["--check", "--page", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    assert text.startswith("# P\n\n") and text.endswith("\n\nprose\n") and "### Scaling" in text


def test_render_refuses_another_schema() -> None:
    report = json.loads((ROOT / "benchmarks" / "results" / "bench.json").read_text(encoding="utf-8"))
    with pytest.raises(ValueError, match="benchmarks/2"):
        _bench_page().render({**report, "schema": "benchmarks/1"})
