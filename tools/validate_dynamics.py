r"""alpha_dyn as a prediction: the three-hand validation of docs/dynamics.md ("Validation").

For each hand, over its scripted lift, ``mjtvm verify --dynamics``
(:func:`~mjtvm.jobs.verify.verify_lift`): per pair (state, RVDS vertex) alpha_kl, alpha_sim
(rollout bisection), alpha_dyn (eq. 31 with the demand M qdd + c along the rollout's checked
span) and one rollout at 0.9 alpha_dyn. Per hand and run it prints the median (and quartiles)
of alpha_sim / alpha_dyn, the pairs failing at 0.9 alpha_dyn with their causes (the rollout's
first violation, grouped), and whether the targets hold: median in [0.9, 1.1], at most 10 %
failing. Nothing is tuned here: the settings are the rollout's defaults (SimSettings).

Usage: ``python tools/validate_dynamics.py [--states 30] [--stride 1] [--jobs 1]
[--out results/validate-dynamics] [--hands case2,allegro-ik,robotiq_2f85-sphere] [--merge REPORT]``.
Writes ``OUT/dyn-<hand>.csv`` (verify's columns, docs/outputs.md), ``OUT/validate-dynamics.md`` and
``OUT/validate-dynamics.json`` (the report ``tools/dynamics_page.py`` renders into docs/dynamics.md).
With ``--merge REPORT`` (e.g. ``benchmarks/results/validate-dynamics.json``) only ``--hands`` run:
their rows replace or join REPORT's, the run is listed under the report's ``merged`` with its
own command and CPU time, and REPORT itself is rewritten (one report, not a copy beside it).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import statistics
import sys
import time
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mjtvm.errors import MjtvmError
from mjtvm.jobs.verify import verify_lift

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling module below, however run
from dynamics_page import SCHEMA, table

# label -> (shipped grasp, the runs checked, travel horizon in m or None for the grasp file's):
# Case 2's fingers 2 and 4 as L-points and as S-points (literal reading, docs/dynamics.md's
# table); the other hands have F-points only, so one run. The 2F-85 twice: at its grasp file's
# 1 mm horizon a pad joint reaches its limit (alpha_kl = 0, nothing to compare), and at horizon
# 0, where only the joints on a limit are held and its speed side is tested.
HANDS: dict[str, tuple[str, tuple[str, ...], float | None]] = {
    "case2": ("case2", ("L", "S-literal"), None),
    "allegro-ik": ("allegro-ik", ("L",), None),
    "robotiq_2f85-sphere": ("robotiq_2f85-sphere", ("L",), None),
    "robotiq_2f85-sphere-h0": ("robotiq_2f85-sphere", ("L",), 0.0),
    "shadow_hand_coupled-sphere": ("shadow_hand_coupled-sphere", ("L",), None),
}
DEFAULT_HANDS = ("case2", "allegro-ik", "robotiq_2f85-sphere", "robotiq_2f85-sphere-h0")
MEDIAN_BAND, MAX_FAILING = (0.9, 1.1), 0.10
_clock: dict[str, float] = {}  # wall and CPU seconds of the last validate(), for the report


def cause(reason: str) -> str:
    """The class of a rollout's first violation (simulate._violation's wording, time stripped)."""
    for pattern, label in (
        (r"^torque saturated", "torque saturated"),
        (r"^contact lost", "contact lost"),
        (r" slips ", "F-point slip"),
        (r"^twist magnitude", "twist magnitude"),
        (r"^twist direction", "twist direction"),
        (r"^object moves", "object moves at rest"),
        (r" past its range's speed", "speed edge"),
    ):
        if re.search(pattern, reason):
            return label
    return reason or "passed"


def hand_summary(rows: Sequence[dict[str, Any]], run: str) -> dict[str, Any]:
    """Medians, failures and their causes of one run's rows.

    A pair whose alpha_kl is 0 (a joint on its limit, or reaching it within the travel
    horizon: docs/joint-limits.md) has no ratio: it is counted in ``zero_alpha``, kept out of
    every median and fraction; so is a censored pair (s* at the bracket's end: a bound, not a
    ratio; ``censored``). ``non_monotone``: the pairs whose pass/fail is not monotone about s*
    (verify.csv's ``monotone``). ``median_ff`` (``q1_ff``, ``q3_ff``, over ``ff_pairs``): alpha_sim
    / alpha_dyn under the second drive (``ratio_dyn_ff``, mjtvm.physics.feedforward), and
    ``spread`` the distance between the two drives' medians, alpha_dyn's uncertainty."""
    mine = [r for r in rows if r["run"] == run and r["status"] == "optimal" and "alpha_dyn" in r]
    positive = [r for r in mine if r["alpha_lp"] > 0]
    ok = [r for r in positive if not r.get("censored")]
    ratios = sorted(r["ratio_dyn"] for r in ok if math.isfinite(r["ratio_dyn"]))
    fails = [r for r in ok if r.get("pass_check_dyn") is False]
    q = statistics.quantiles(ratios, n=4) if len(ratios) > 1 else [math.nan] * 3
    med = statistics.median(ratios) if ratios else math.nan
    frac = len(fails) / len(ok) if ok else math.nan
    causes = Counter(cause(r.get("check_dyn_reason", "")) for r in fails)
    # the second drive (mjtvm.physics.feedforward): alpha_sim under it over alpha_dyn
    ff = sorted(r["ratio_dyn_ff"] for r in ok if math.isfinite(r.get("ratio_dyn_ff", math.nan)))
    ff_med = statistics.median(ff) if ff else math.nan
    ffq = statistics.quantiles(ff, n=4) if len(ff) > 1 else [math.nan] * 3
    states = sorted({int(r["state"]) for r in fails})
    return {
        "pairs": len(ok),
        "zero_alpha": len(mine) - len(positive),
        "censored": len(positive) - len(ok),
        "non_monotone": sum(r.get("monotone") is False for r in ok),
        "no_alpha_dyn": len(ok) - len(ratios),
        "median": med,
        "q1": q[0],
        "q3": q[2],
        "sim_kl": statistics.median(r["ratio"] for r in ok) if ok else math.nan,
        "dyn_kl": statistics.median(r["alpha_dyn"] / r["alpha_lp"] for r in ok) if ok else math.nan,
        "median_ff": ff_med,
        "q1_ff": ffq[0],
        "q3_ff": ffq[2],
        "ff_pairs": len(ff),
        "spread": abs(ff_med - med) if ff and ratios else math.nan,
        "within_10pct": sum(1 for x in ratios if 0.9 <= x <= 1.1),
        "above_1.1": sum(1 for x in ratios if x > 1.1),
        "failing": len(fails),
        "failing_fraction": frac,
        "causes": dict(causes.most_common()),
        "failing_states": states,
        "terms": dict(Counter(r["dyn_term"] for r in ok).most_common()),
        "median_met": bool(MEDIAN_BAND[0] <= med <= MEDIAN_BAND[1]),
        "failing_met": bool(frac <= MAX_FAILING),
    }


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--states", type=int, default=30, help="states along each lift (default: 30)")
    ap.add_argument("--stride", type=int, default=1, help="check every N-th state and the last (default: 1)")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes (default: 1)")
    ap.add_argument("--out", type=Path, default=Path("results/validate-dynamics"), help="output folder")
    ap.add_argument(
        "--hands", default=",".join(DEFAULT_HANDS), help=f"comma-separated, among {sorted(HANDS)}"
    )
    ap.add_argument(
        "--merge",
        type=Path,
        default=None,
        metavar="REPORT",
        help="replace (or add) the rows of --hands in this validate-dynamics.json and rewrite it; "
        "its other hands are not rerun",
    )
    args = ap.parse_args(argv)
    hands = [h for h in args.hands.split(",") if h]
    unknown = [h for h in hands if h not in HANDS]
    if unknown:
        print(f"hands: expected names among {sorted(HANDS)}, got {unknown}", file=sys.stderr)
        return 2
    base = None
    if args.merge is not None:  # read before any work: a bad report is refused at once
        try:
            base = json.loads(args.merge.read_text(encoding="utf-8"))
        except (OSError, ValueError) as e:
            print(f"--merge: cannot read a report from {args.merge}: {e}", file=sys.stderr)
            return 2
        if not isinstance(base, dict) or base.get("schema") != SCHEMA:
            print(f"--merge: {args.merge} is not a {SCHEMA} report", file=sys.stderr)
            return 2
    try:
        results = validate(hands, args.states, args.stride, args.jobs, args.out)
    except MjtvmError as e:  # bad input (states, stride, jobs, out): one line, exit 2
        print(f"error: {' '.join(str(e).split())}", file=sys.stderr)
        return 2
    rows = [{"hand": h, "run": r, **s} for (h, r), s in results.items()]
    run = {
        "command": "python tools/validate_dynamics.py "
        + " ".join(argv if argv is not None else sys.argv[1:]),
        "states": args.states,
        "stride": args.stride,
        "jobs": args.jobs,
        "date": time.strftime("%Y-%m-%d"),
        **_clock,
    }
    if base is None:
        report, target = {"schema": SCHEMA, **run, "results": rows}, args.out / "validate-dynamics.json"
    else:
        report, target = merged(base, rows, {"hands": hands, **run}), args.merge
    text = table(report["results"])
    print(text)
    (args.out / "validate-dynamics.md").write_text(text, encoding="utf-8")
    tmp = target.with_name(target.name + ".tmp")
    tmp.write_text(json.dumps(report, indent=1, allow_nan=True) + "\n", encoding="utf-8")
    os.replace(tmp, target)
    return 0


def merged(base: dict[str, Any], rows: Sequence[dict[str, Any]], run: dict[str, Any]) -> dict[str, Any]:
    """``base`` with the rows of ``run["hands"]`` replaced by ``rows`` (in `HANDS`' order, then
    the run's), and ``run`` listed under ``merged`` in place of an earlier run of the same hands."""
    hands = set(run["hands"])
    kept = [r for r in base["results"] if r["hand"] not in hands]
    order = list(HANDS)
    results = sorted(
        [*kept, *rows],
        key=lambda r: (order.index(r["hand"]) if r["hand"] in order else len(order), r["hand"]),
    )  # a stable sort: each hand's runs stay in their order
    earlier = [m for m in base.get("merged", []) if not set(m["hands"]) <= hands]
    return {**base, "results": results, "merged": [*earlier, run]}


def validate(
    hands: Sequence[str], states: int, stride: int, jobs: int, out: Path
) -> dict[tuple[str, str], dict[str, Any]]:
    """Run verify --dynamics on each hand and summarize each run (module docstring)."""
    results: dict[tuple[str, str], dict[str, Any]] = {}
    wall0, cpu0 = time.perf_counter(), time.process_time()
    for hand in hands:
        t0 = time.perf_counter()
        grasp, runs, horizon = HANDS[hand]
        rows = verify_lift(
            grasp,
            num_states=states,
            stride=stride,
            runs=runs,
            limit_horizon=horizon,
            dynamics=True,
            jobs=jobs,
            out=out,
            name=f"dyn-{hand}",
            progress=False,
            plot=False,
        )
        for run in runs:
            results[hand, run] = s = hand_summary(rows, run)
            print(
                f"{hand} {run}: {s['pairs']} pairs, alpha_sim/alpha_dyn median {s['median']:.3f} "
                f"(IQR {s['q1']:.3f}-{s['q3']:.3f}), failing at 0.9 alpha_dyn {s['failing']} "
                f"({100 * s['failing_fraction']:.1f} %), causes {s['causes']}, states {s['failing_states']}, "
                f"limiting terms {s['terms']}, {time.perf_counter() - t0:.0f} s",
                flush=True,
            )
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    if jobs > 1:  # the workers' CPU time is not this process's: not measured, rather than low
        _clock.update(wall_s=wall, cpu_s=None, core_share=None)
    else:
        _clock.update(wall_s=wall, cpu_s=cpu, core_share=cpu / wall if wall > 0 else math.nan)
    return results


if __name__ == "__main__":  # the guard matters: verify's worker processes re-import this file
    raise SystemExit(main())
