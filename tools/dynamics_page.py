r"""Render the validation tables of ``docs/dynamics.md`` from a ``tools/validate_dynamics.py`` report.

Usage::

    python tools/dynamics_page.py --write   # rewrite the generated part of the page
    python tools/dynamics_page.py --check   # exit 1 if the page is not this output

The report is a ``validate-dynamics.json`` of schema ``validate-dynamics/1`` (default
``benchmarks/results/validate-dynamics.json``, written by
``python tools/validate_dynamics.py --out DIR``, its rows of some hands replaced by
``--merge REPORT``: listed under ``merged``, each with its own command and CPU time). The tables go between the page's two marker
comments (:data:`BEGIN`, :data:`END`); the rest of the page is written by hand.
``tests/docs/test_dynamics_page.py`` checks that the committed page equals this output.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling module below, however run
from page_block import markers, page_main

ROOT = Path(__file__).resolve().parent.parent
REPORT = Path("benchmarks/results/validate-dynamics.json")  #: the default report, from the root
PAGE = Path("docs/dynamics.md")  #: the default page, relative to the root
SCHEMA = "validate-dynamics/1"
BEGIN, END = markers("tools/dynamics_page.py", REPORT)  #: the lines above and below the generated tables


def _f(x: float) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.3f}"


def table(results: list[dict[str, Any]]) -> str:
    """The validation table (markdown), one row per hand and run of the report's ``results``;
    the second drive's column ("-" in a report from before it, or on a hand without it)."""
    head = (
        "| hand | run | pairs (alpha_kl = 0; censored) | alpha_sim / alpha_kl median | alpha_dyn / alpha_kl median "
        "| **alpha_sim / alpha_dyn** median (IQR) | second drive: alpha_sim / alpha_dyn median (IQR); spread "
        "| within +-10 % | failing at 0.9 alpha_dyn | causes | not monotone |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    lines = []
    for s in results:
        if not s["pairs"]:
            lines.append(
                f"| {s['hand']} | {s['run']} | 0 ({s['zero_alpha']}; {s.get('censored', 0)}) | - | - | - | - | - | - | - | - |"
            )
            continue
        med = f"**{_f(s['median'])}** ({_f(s['q1'])}-{_f(s['q3'])})" + (
            "" if s["median_met"] else " (outside [0.9, 1.1])"
        )
        ff = "-"
        if math.isfinite(s.get("median_ff", math.nan)):
            ff = f"{_f(s['median_ff'])} ({_f(s['q1_ff'])}-{_f(s['q3_ff'])}); {_f(s['spread'])}"
        fail = f"{s['failing']} / {s['pairs']} ({100 * s['failing_fraction']:.0f} %)" + (
            "" if s["failing_met"] else " (over 10 %)"
        )
        causes = ", ".join(f"{k}: {v}" for k, v in s["causes"].items()) or "-"
        lines.append(
            f"| {s['hand']} | {s['run']} | {s['pairs']} ({s['zero_alpha']}; {s.get('censored', '-')}) "
            f"| {_f(s['sim_kl'])} | {_f(s['dyn_kl'])} | {med} | {ff} "
            f"| {s['within_10pct']} | {fail} | {causes} | {s.get('non_monotone', '-')} |"
        )
    return head + "\n".join(lines) + "\n"


def _details(results: list[dict[str, Any]]) -> list[str]:
    """Per run: the states of the failing pairs and the term that limits alpha_dyn."""
    rows = [
        "| hand | run | states of the failing pairs | limiting term of alpha_dyn (pairs) |",
        "|---|---|---|---|",
    ]
    for s in results:
        states = ", ".join(str(k) for k in s["failing_states"]) or "-"
        terms = ", ".join(f"{k}: {v}" for k, v in s["terms"].items()) or "-"
        rows.append(f"| {s['hand']} | {s['run']} | {states} | {terms} |")
    return rows


def render(report: dict[str, Any]) -> str:
    """The generated part of the page, markers included, from a ``validate-dynamics/1`` report.

    Raises
    ------
    ValueError
        If the report's schema is not ``validate-dynamics/1``.
    """
    if report.get("schema") != SCHEMA:
        raise ValueError(f"not a {SCHEMA} report: schema {report.get('schema')!r}")
    runs = [_run_line(report)]
    for entry in report.get("merged", []):  # hands rerun alone (validate_dynamics.py --merge)
        runs += ["", f"The rows of {', '.join(entry['hands'])} from " + _run_line(entry)]
    lines = [BEGIN, "", *runs, "", table(report["results"]).rstrip("\n"), "", *_details(report["results"])]
    return "\n".join([*lines, "", END])


def _run_line(run: dict[str, Any]) -> str:
    """One run of the validation: its command, date, states, processes and CPU time."""
    share = run["core_share"]
    if run.get("cpu_s") is None:  # several processes: their CPU time was not measured
        cpu = f"{run['wall_s'] / 60:.1f} min wall (the workers' CPU time not measured)."
    else:
        cpu = (
            f"{run['cpu_s'] / 60:.1f} min of CPU in {run['wall_s'] / 60:.1f} min wall (core share "
            f"{share:.2f}" + ("" if share >= 0.8 else ": other jobs shared the machine") + ")."
        )
    return (
        f"`{run['command']}` ({run['date']}): {run['states']} states per lift, "
        + ("every state" if run["stride"] == 1 else f"every {run['stride']}-th state and the last")
        + f" checked, {run['jobs']} process{'es' if run['jobs'] > 1 else ''}; "
        + cpu
    )


def main(argv: list[str] | None = None) -> int:
    """``--write`` the page, or ``--check`` it; return the process exit code (1: stale)."""
    return page_main(
        argv,
        tool="tools/dynamics_page.py",
        render=render,
        report=ROOT / REPORT,
        page=ROOT / PAGE,
        begin=BEGIN,
        end=END,
    )


if __name__ == "__main__":
    raise SystemExit(main())
