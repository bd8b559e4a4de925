r"""The report of [`benchmarks.suite`][benchmarks.suite]: targets and the table, with the notes on misses
of [`benchmarks.notes`][benchmarks.notes] (the command line that runs the suite and writes them:
[`benchmarks.__main__`][benchmarks.__main__]).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from benchmarks.notes import auto_notes
from benchmarks.suite import P2_TARGET_KEYS, TARGET_SWEEP_SPEEDUP, TARGETS_S

__all__ = ["auto_notes", "format_suite_table", "peer_rows", "rank_rows"]


# ------------------------------------------------------------------ the table
def _ms(s: float | None) -> str:
    return "-" if s is None else f"{1e3 * s:.2f} ms" if s < 1 else f"{s:.2f} s"


def _met(flag: bool | None) -> str:
    return "-" if flag is None else "met" if flag else "NOT met"


_HEAD = f"{'measurement':<44} {'ours':>10} {'baseline':>24} {'ratio':>7} {'paper':>8} {'target':>9} {'':>7}"


def _row(
    name: str, ours: float | None, base: str, ratio: str, pap: float | None, target: str, met: str
) -> str:
    """One line of the main table."""
    return f"{name:<44} {_ms(ours):>10} {base:>24} {ratio:>7} {_ms(pap):>8} {target:>9} {met:>7}"


def _cdd_baseline(r: dict[str, Any]) -> tuple[str, str]:
    """Problem 1's baseline column and ratio: cdd's wall time, its cap, or skipped."""
    cdd = r["cdd"]
    if cdd is None:
        return "cdd skipped", "-"
    if cdd["finished"]:
        return f"cdd {_ms(cdd['wall_s'])}", f"{cdd['wall_s'] / r['lp']['median_s']:.1f}"
    return f"cdd > {cdd['time_limit_s']:.0f} s (cap)", f">{cdd['time_limit_s'] / r['lp']['median_s']:.1f}"


def _case_rows(report: dict[str, Any]) -> list[str]:
    """The paper's cases: Problem 1 against cdd, Problem 2 against cvxpy."""
    c, t, paper = report["cases"], report["targets"], report["paper_s"]
    lines = []
    for key, label in (
        ("case1_p1", "Case 1, Problem 1 (no RVDS)"),
        ("case2_p1", "Case 2 initial, Problem 1 (no RVDS)"),
    ):
        if key in c:
            base, ratio = _cdd_baseline(c[key])
            target = f"<= {_ms(TARGETS_S[key])}"
            lines.append(
                _row(label, c[key]["lp"]["median_s"], base, ratio, paper[key], target, _met(t.get(key)))
            )
    for key, label in (
        ("case1_p2", "Case 1, Problem 2 (8 RVDS vertices)"),
        ("case2_p2", "Case 2 initial, Problem 2 (4 RVDS)"),
    ):
        if key in c:
            r = c[key]
            lines.append(
                _row(
                    label,
                    r["ours"]["median_s"],
                    f"cvxpy {_ms(r['baseline']['median_s'])}",
                    f"{r['ratio_baseline_over_ours']:.1f}",
                    paper[key],
                    f"<= {_ms(TARGETS_S[P2_TARGET_KEYS[key]])}",
                    _met(t.get(key)),
                )
            )
    return lines


def _lift_rows(report: dict[str, Any]) -> list[str]:
    """The full lift (L and S), against its target."""
    if "lift" not in report:
        return []
    lf = report["lift"]
    return [
        _row(
            f"Full lift, L + S ({lf['num_states']} states, no plots/sweeps)",
            lf["median_s"],
            "-",
            "-",
            None,
            f"<= {_ms(TARGETS_S['lift'])}",
            _met(report["targets"].get("lift")),
        )
    ]


def _hand_rows(report: dict[str, Any]) -> list[str]:
    """Each test hand's grasp file: load (with IK), state, Problem 2, lift (benchmarks.hands)."""
    lines = []
    for name, h in report.get("hands", {}).items():
        tag = f"{name} ({h['joints']} joints, {h['contacts']} contacts)"
        for key, what in (
            ("load", "load + configure"),
            ("state", "grasp state"),
            ("p2", f"Problem 2 ({h['rvds']} RVDS)"),
            ("lift", "lift, 30 states"),
        ):
            lines.append(_row(f"{tag}: {what}"[:44], h[key]["median_s"], "-", "-", None, "-", ""))
    return lines


def _sweep_rows(report: dict[str, Any]) -> list[str]:
    """The Fig. 9 sweeps per process count (speed-up against its target), then their runs."""
    if "sweeps" not in report:
        return []
    sw, met = report["sweeps"], _met(report["targets"].get("sweep_speedup_2"))
    lines = []
    for j, r in sw["per_jobs"].items():
        extra = " incl. pool start" if j != "1" else ""
        sp = sw.get("speedup", {}).get(j)
        lines.append(
            _row(
                f"Fig. 9 sweeps, {sw['points']} pts, {j} proc{extra}",
                r["median_s"],
                "-",
                "-" if sp is None else f"x{sp:.3f}",
                None,
                f">= x{TARGET_SWEEP_SPEEDUP}" if j != "1" else "",
                met if j == "2" else "",
            )
        )
    runs = "; ".join(
        f"{j} proc: " + ", ".join(f"{x:.2f}" for x in r["runs_s"]) for j, r in sw["per_jobs"].items()
    )
    lines.append(
        f"sweeps: {sw['combinations']} (mu, mg) combinations ({sw['distinct_combinations']} distinct) x "
        f"{sw['num_states']} states; lift build {sw['lift_build_s']:.2f} s; empty 2-worker pool start-up "
        f"{sw['pool_startup_s'].get('2', float('nan')):.2f} s; runs {runs} s"
    )
    return lines


def _scaling_rows(report: dict[str, Any]) -> list[str]:
    """The synthetic hands: time and memory per finger count, the ratios per doubling."""
    if "scaling" not in report:
        return []
    sc = report["scaling"]
    lines = [
        "",
        f"{'fingers':>7} {'joints':>6} {'LPs':>4} {'P2/state':>10} {'P1 (cone)':>10} {'P1 verts':>8} "
        f"{'traced P2':>10} {'traced P1':>10} {'maxrss':>8}",
    ]
    for f, r in sc["per_fingers"].items():
        m = r["memory_mib"]
        tp1 = "-" if m["tracemalloc_peak_p1"] is None else f"{m['tracemalloc_peak_p1']:.1f} MiB"
        lines.append(
            f"{f:>7} {r['joints']:>6} {r['num_lps']:>4} {_ms(r['p2']['median_s']):>10} {_ms(r['p1']['median_s']):>10} "
            f"{'-' if r['p1_vertices'] is None else r['p1_vertices']:>8} {m['tracemalloc_peak_p2']:>6.2f} MiB "
            f"{tp1:>10} {m['ru_maxrss']:>4.0f} MiB"
        )
    ratios = "; ".join(
        f"{k} fingers: P2 x{r['p2_time']:.2f}, P1 x{r['p1_time']:.2f}" for k, r in sc["ratios"].items()
    )
    exponent = sc["p2_loglog_exponent"]
    lines.append(
        f"ratios (time): {ratios} -> P2 at most linear in every doubling: {'yes' if sc['p2_at_most_linear'] else 'NO'}"
        + ("" if exponent is None else f" (log-log exponent over the sizes: {exponent:.2f})")
    )
    lines.append(f"scaling hands: {sc['hand']}")
    return lines


def _dataset_rows(report: dict[str, Any]) -> list[str]:
    """Dataset scale: grasps/s of the batches, the 2-process speed-up, ``mjtvm solve`` as a process."""
    ds = report.get("dataset")
    if not ds:
        return []
    met, tg, lines = ds["met"], ds["targets"], []
    for key in ("batch_weight", "batch_six_wrenches"):
        b = ds[key]
        one = b["per_jobs"]["1"]
        lines.append(
            _row(
                f"Batch P2, {b['joints']}j/{b['contacts']}c, {b['lps_per_grasp']} LPs: {one['grasps_per_s']:.1f} grasps/s",
                one["median_s"] / b["states"],
                "-",
                "-",
                ds["cli"]["paper_s"],
                f">= {tg[key]:.0f}/s",
                _met(met[key]),
            )
        )
    six, j = ds["batch_six_wrenches"], str(ds["jobs"])
    lines.append(
        _row(
            f"  on {j} proc, pool start incl.: {six['per_jobs'][j]['grasps_per_s']:.1f} grasps/s",
            six["per_jobs"][j]["median_s"] / six["states"],
            "-",
            f"x{six['speedup'][j]:.2f}",
            None,
            f">= x{tg['batch_speedup_2']}",
            _met(met["batch_speedup_2"]),
        )
    )
    c = ds["cli"]
    lines.append(
        _row(
            "mjtvm solve STATE.json, as a process",
            c["solve"]["median_s"],
            "-",
            "-",
            c["paper_s"],
            f"<= {_ms(tg['solve_process'])}",
            _met(met["solve_process"]),
        )
    )
    for key, label in (
        ("import_mjtvm", 'python -c "import mjtvm"'),
        ("import_dependencies", "import numpy, highspy, jsonschema"),
        ("python_startup", 'python -c "pass"'),
    ):
        lines.append(_row(label[:44], c[key]["median_s"], "-", "-", None, "-", ""))
    lines.append(
        f"dataset scale: {ds['hand']}; batches of {ds['batch_weight']['states']} states, times per grasp "
        "(median batch / states), the ratio on 2 processes is the speed-up; "
        f"solve: {c['state']}, processes timed {c['solve']['repeats']} times after one untimed run"
    )
    return lines


def _verdict(r: dict[str, Any]) -> str:
    """ "met", "NOT met", or "loaded" for a row whose core share is below the minimum."""
    return "loaded" if r.get("loaded") else _met(r.get("met"))


def rank_rows(report: dict[str, Any]) -> list[str]:
    """``mjtvm rank`` ([`benchmarks.rank`][benchmarks.rank]): CPU time per grasp, Problem 2 over HiGHS on
    the batch, 16 against 32 fingers, 2 processes, ``--verify``, peak memory; each with its core share."""
    rk = report.get("rank")
    if not rk:
        return []
    lines, th = [], rk["throughput"]
    for key, label in (("classic", "classic measures"), ("none", "TVMMP alone")):
        r = th[key]
        lines.append(
            _row(
                f"rank, {label}: {r['grasps_per_cpu_s']:.1f} grasps/CPU-s",
                r["cpu_s"] / th["grasps"],
                f"wall {_ms(r['wall_s'] / th['grasps'])}",
                f"{r['core_share']:.2f}",
                None,
                f">= {r['target']:.0f}/s",
                _verdict(r),
            )
        )
    t22 = rk.get("throughput_22")
    for key, label in (("classic", "classic"), ("none", "TVMMP alone")) if t22 else ():
        r = t22[key]
        lines.append(
            _row(
                f"rank 22 joints, {label}: {r['grasps_per_cpu_s']:.1f} grasps/CPU-s",
                r["cpu_s"] / t22["grasps"],
                f"wall {_ms(r['wall_s'] / t22['grasps'])}",
                f"{r['core_share']:.2f}",
                None,
                f">= {r['target']:.0f}/s",
                _verdict(r),
            )
        )
    for key, hand in (("p2_floor", ""), ("p2_floor_22", "22-joint, ")):
        f = rk.get(key)
        if f is None:  # p2_floor_22: absent from reports before it
            continue
        lines.append(
            _row(
                f"rank batch P2 (compiled) / HiGHS-alone run ({hand}{f['states']} states, {f['lps']} LPs)",
                f["wall_s"],
                f"HiGHS run {_ms(f['highs_run_s'])}",
                f"{f['ratio']:.2f}",
                None,
                f"<= x{f['target']}",
                _verdict(f),
            )
        )
    g = rk["fingers"]
    per = g["per_fingers"]
    lines.append(
        _row(
            "P2 per LP, 32 fingers / 16 (CPU)",
            per["32"]["cpu_s_per_lp"],
            f"16: {_ms(per['16']['cpu_s_per_lp'])}",
            f"{g['ratio']:.2f}",
            None,
            f"<= x{g['target']}",
            _verdict(g),
        )
    )
    j = rk["jobs"]
    lines.append(
        _row(
            f"rank on {j['jobs']} proc, {j['grasps']} grasps (wall)",
            j[str(j["jobs"])]["wall_s"] / j["grasps"],
            f"1 proc {_ms(j['1']['wall_s'] / j['grasps'])}",
            f"x{j['speedup']:.2f}",
            None,
            f">= x{j['target']}",
            _verdict(j),
        )
    )
    v = rk.get("verify")  # absent from reports before issue 35's row
    if v is not None and "error" in v:
        lines.append(f"{'rank --verify':<44} {'error: ' + v['error']:>24}")
    elif v is not None:
        lines.append(
            _row(
                f"rank --verify: {v['grasps_per_cpu_s']:.2f} grasps/CPU-s",
                v["cpu_s"] / v["grasps"],
                f"wall {_ms(v['wall_s'] / v['grasps'])}",
                f"{v['core_share']:.2f}",
                None,
                f">= {v['target']:.0f}/s",
                _verdict(v),
            )
        )
    mem = rk["memory"]
    for n, r in mem["sizes"].items():
        text = "error: " + r["error"] if "error" in r else f"peak RSS {r['peak_rss_mib']:.0f} MiB"
        cpu = f"cpu {r['cpu_s']:.0f} s, share {r['core_share']:.2f}" if "cpu_s" in r else "-"
        lines.append(f"{'rank memory, ' + n + ' grasps':<44} {text:>24} {cpu:>34}")
    if "mib_per_1000_grasps" in mem:
        lines.append(f"rank memory: {mem['mib_per_1000_grasps']:.2f} MiB more per 1,000 grasps")
    d = mem.get("dask")
    if d is not None:
        text = (
            "error: " + d["error"]
            if "error" in d
            else f"files identical: {'yes' if d['files_identical'] else 'NO'}"
        )
        share = f"wall {d['wall_s']:.0f} s, share {d['core_share']:.2f}" if "wall_s" in d else "-"
        lines.append(f"{'rank on Dask, ' + str(d.get('grasps', '?')) + ' grasps':<44} {text:>24} {share:>34}")
    lines.append(
        f"rank: {rk['grasp']} on {rk['dataset']} ({th['grasps']} grasps) in this process; CPU time per grasp, "
        "ratio column = core share (CPU over wall); a row below a core share of 0.8 is 'loaded', never met"
    )
    return lines


def peer_rows(report: dict[str, Any]) -> list[str]:
    """The table's rows of the velocity and force polytopes against pycapacity (benchmarks.peers).

    Parameters
    ----------
    report : dict
        A [`run_suite()`][benchmarks.suite.run_suite] report.

    Returns
    -------
    list of str
        Three rows per chain, two for pycapacity's four-link robot and a summary line; none
        without a ``peers`` section.
    """
    pe = report.get("peers")
    if not pe:
        return []
    target = f">= x{pe['target_ratio']:.1f}"

    def row(label: str, pair: dict[str, Any]) -> str:
        peer = "pycapacity -" if pair["peer_s"] is None else f"pycapacity {_ms(pair['peer_s'])}"
        ratio = "-" if pair["ratio"] is None else f"x{pair['ratio']:.2f}"
        met = None if pair["ratio"] is None else pair["ratio"] >= pe["target_ratio"]
        return _row(label[:44], pair["ours_s"], peer, ratio, None, target, _met(met))

    lines = []
    for n, r in pe["fingers"].items():
        lines.append(row(f"Velocity polytope {n}j: tvms ({r['method']})", r["tvms"]))
        lines.append(row(f"Velocity polytope {n}j: velocity_polytope", r["function"]))
        lines.append(row(f"Force polytope {n}j: force_polytope", r["force"]))
    ex = pe["four_link_example"]
    lines.append(row("pycapacity's four-link robot: velocity", ex["velocity"]))
    lines.append(row("pycapacity's four-link robot: force", ex["force"]))
    lp = "; ".join(
        f"{n}j {_ms(r['lp']['median_s'])} ({r['lp']['num_lps']} LPs)" for n, r in pe["fingers"].items()
    )
    agree = max(r["vs_lp"]["hausdorff_rel"] for r in pe["fingers"].values())
    lines.append(
        f"peers: the same TVMS by LPs (method='lp'): {lp}; zonotope vs LP vertices within {agree:.1e} relative"
    )
    return lines


def _floor_rows(report: dict[str, Any]) -> list[str]:
    """Problem 2 over its time inside HiGHS ([`benchmarks.floor`][benchmarks.floor]): one row per state."""
    fl = report.get("floor")
    if not fl:
        return []
    lines = []
    for name, r in fl["states"].items():
        lines.append(
            _row(
                f"P2 / HiGHS run, {name} ({r['lps']} LPs)",
                r["total_s"],
                f"HiGHS run {_ms(r['highs_run_s'])}",
                f"{r['ratio']:.2f}",
                None,
                f"<= x{fl['target_ratio']}",
                _met(r["met"]),
            )
        )
    lines.append(
        "P2 / HiGHS run: per call, tvmmp(state, witnesses=False) over the time inside HiGHS run() in the same "
        "call (median of the per-call ratios; ratio column)"
    )
    busy = [f"{n} {r['core_share']:.2f}" for n, r in fl["states"].items() if r.get("core_share", 1.0) > 1.1]
    if busy:
        lines.append("P2 / HiGHS run on more than one core (CPU time over wall time): " + ", ".join(busy))
    return lines


def _footer(report: dict[str, Any], notes: Sequence[str]) -> list[str]:
    """What the figures are, the notes, the machine and the run's wall time."""
    m = report["machine"]
    return [
        "",
        "medians over repeats; P2 = tvmmp(state, witnesses=False) (HiGHS, eliminated box), baseline = cvxpy",
        "rebuilt per pair; P1 = tvms(state) by support LPs, baseline = cdd vertex enumeration (child process,",
        f"capped at {report['settings']['cdd_time_limit_s']:.0f} s); Case 2 Problem 1: median of 3 after a warm-up. The 2-process sweep times include",
        "the pool's start-up (on Linux the workers are forked after the parent built the lift).",
        *notes,
        f"machine: {m['cpu']}, {m['logical_cpus']} logical CPUs ({m['usable_cpus']} usable), {m['platform']}, "
        f"Python {m['python']}, " + ", ".join(f"{k} {v}" for k, v in m["packages"].items()),
        f"total wall time of the run: {report['total_wall_s']:.0f} s",
    ]


def format_suite_table(report: dict[str, Any], notes: Sequence[str] = ()) -> str:
    """A plain-text table of a [`run_suite()`][benchmarks.suite.run_suite] report (medians): the paper's
    cases, the lift, the sweeps, the scaling hands, the test hands, the dataset scale, then the
    notes and the machine."""
    lines = [_HEAD, "-" * len(_HEAD)]
    lines += _case_rows(report) + _lift_rows(report) + _sweep_rows(report) + _scaling_rows(report)
    lines += _hand_rows(report) + _dataset_rows(report) + _floor_rows(report) + rank_rows(report)
    lines += peer_rows(report)
    if "problem1_scale" in report:
        from benchmarks.problem1 import format_scale_table

        lines += ["", format_scale_table(report["problem1_scale"])]
    return "\n".join(lines + _footer(report, notes))
