r"""Render the dataset benchmark's tables of ``docs/physics-check.md`` from a ``tools/validate_datasets.py`` report.

Usage::

    python tools/datasets_page.py --write   # rewrite the generated part of the page
    python tools/datasets_page.py --check   # exit 1 if the page is not this output

The report is a ``validate-datasets.json`` of schema ``validate-datasets/1`` (default
``benchmarks/results/validate-datasets.json``, written by
``python tools/validate_datasets.py --out DIR``): per run, the commands that made the dataset
and ran ``mjtvm rank --verify`` on it, the counts read from that run's ``NAME.json`` and the
AUC rows of its ``NAME-auc.json``. The tables go between the page's two marker comments
(:data:`BEGIN`, :data:`END`); the rest of the page is written by hand.
``tests/docs/test_datasets_page.py`` checks that the committed page equals this output.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling module below, however run
from page_block import markers, page_main

ROOT = Path(__file__).resolve().parent.parent
REPORT = Path("benchmarks/results/validate-datasets.json")  #: the default report, from the root
PAGE = Path("docs/physics-check.md")  #: the default page, relative to the root
SCHEMA = "validate-datasets/1"
BEGIN, END = markers("tools/datasets_page.py", REPORT)  #: the lines above and below the generated tables
SPEED_TARGET = 5.0
"""Grasps per CPU-second of ``mjtvm rank --verify`` (issue 35: 6 directions x 3 speeds)."""
MEASURES = (
    ("tvmmp", "TVMMP"),
    ("alpha_l", "alpha_l (per RVDS direction: min-max)"),
    ("epsilon_l1", "epsilon L1"),
    ("epsilon_linf", "epsilon L-inf"),
    ("grasp_sigma_min", "sigma_min"),
    ("force_closure", "force closure"),
)
TARGETS = (("sim_speed_success", "speed success"), ("sim_hold", "hold"))


def _pct(k: int, n: int) -> str:
    return f"{k} ({100 * k / n:.0f} %)" if n else f"{k}"


def _auc(row: dict[str, Any] | None) -> str:
    """``0.637 (0.552-0.718)``; ``-`` where a class is empty (no AUC)."""
    if row is None or row["auc"] is None or not math.isfinite(row["auc"]):
        return "-"
    if row["ci_low"] is None:
        return f"{row['auc']:.3f}"
    return f"{row['auc']:.3f} ({row['ci_low']:.3f}-{row['ci_high']:.3f})"


def _cell(rows: list[dict[str, Any]], measure: str, target: str) -> str:
    """The AUC cell of ``measure`` against ``target``; the RVDS directions' alphas as their range."""
    if measure != "alpha_l":
        return _auc(next((r for r in rows if r["measure"] == measure and r["target"] == target), None))
    aucs = [
        r["auc"]
        for r in rows
        if r["measure"].startswith("alpha_l") and r["target"] == target and r["auc"] is not None
    ]
    if not aucs:
        return "-"
    lo, hi = min(aucs), max(aucs)
    return f"{lo:.3f}" if hi - lo < 5e-4 else f"{lo:.3f}-{hi:.3f}"


def _speed(run: dict[str, Any]) -> str:
    """Grasps per CPU-second of the rank run, with the target's verdict and the core share."""
    if run.get("cpu_s") is None:
        return f"{run['wall_s']:.0f} s wall on {run['jobs']} processes (CPU time not measured)"
    rate = run["grasps"] / run["cpu_s"] if run["cpu_s"] > 0 else math.nan
    share = run["core_share"]
    verdict = "met" if rate >= SPEED_TARGET and share >= 0.8 else "missed"
    if share < 0.8:
        verdict = "not measured (core share below 0.8)"
    return (
        f"{rate:.2f} grasps/CPU-s ({run['cpu_s']:.0f} CPU-s, {run['wall_s']:.0f} s wall on "
        f"{run['jobs']} process{'es' if run['jobs'] > 1 else ''}, core share {share:.2f}; "
        f"target {SPEED_TARGET:g}: {verdict})"
    )


def _on(machine: dict[str, Any] | None) -> str:
    """``", on CPU (N cores)"``: the machine of the CPU times (reports before it was kept: "")."""
    if not machine:
        return ""
    return f", on {machine['cpu']} ({machine['usable_cpus']} usable cores)"


def render(report: dict[str, Any]) -> str:
    """The generated part of the page, markers included, from a ``validate-datasets/1`` report.

    Raises
    ------
    ValueError
        If the report's schema is not ``validate-datasets/1``.
    """
    if report.get("schema") != SCHEMA:
        raise ValueError(f"not a {SCHEMA} report: schema {report.get('schema')!r}")
    runs = report["runs"]
    lines = [
        BEGIN,
        "",
        f"`{report['command']}` ({report['date']}{_on(report.get('machine'))}). Each run, its two commands:",
        "",
    ]
    for r in runs:
        lines += [f"* **{r['label']}**: `{r['make']}`; `{r['rank']}`"]
    lines += [
        "",
        "| run | grasps | evaluated | simulated | hold | speed success | rank --verify speed |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        n = r["simulated"]
        lines.append(
            f"| {r['label']} | {r['grasps']} | {r['evaluated']} | {r['simulated']} | {_pct(r['held'], n)} "
            f"| {_pct(r['speed_success'], n)} | {_speed(r)} |"
        )
    for target, name in TARGETS:
        lines += [
            "",
            f"AUC against the simulated **{name}** (`{target}`), 95 % bootstrap interval; "
            "`-`: one class is empty",
            "",
            "| measure | " + " | ".join(r["label"] for r in runs) + " |",
            "|---|" + "---|" * len(runs),
        ]
        for measure, label in MEASURES:
            lines.append(f"| {label} | " + " | ".join(_cell(r["auc"], measure, target) for r in runs) + " |")
    return "\n".join([*lines, "", END])


def main(argv: list[str] | None = None) -> int:
    """``--write`` the page, or ``--check`` it; return the process exit code (1: stale)."""
    return page_main(
        argv,
        tool="tools/datasets_page.py",
        render=render,
        report=ROOT / REPORT,
        page=ROOT / PAGE,
        begin=BEGIN,
        end=END,
    )


if __name__ == "__main__":
    raise SystemExit(main())
