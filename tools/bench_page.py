r"""Render the measured tables of ``docs/performance.md`` from a ``python -m benchmarks`` report.

Usage::

    python tools/bench_page.py --write   # rewrite the generated part of the page
    python tools/bench_page.py --check   # exit 1 if the page is not this output

The report is a ``NAME.json`` of schema ``benchmarks/2`` (default
``benchmarks/results/bench.json``, written by
``python -m benchmarks --quick --out benchmarks/results --name bench``). The tables go between
the page's two marker comments (:data:`BEGIN`, :data:`END`); the rest of the page is written by
hand. ``tests/docs/test_bench_page.py`` checks that the committed page equals this output.
When ``rank-memory.json`` (``python -m benchmarks.rank --memory 400,4000,40000 --out
benchmarks/results``) is beside the report, the peak-RSS and Dask rows come from it.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling module below, however run
from page_block import markers, page_main

ROOT = Path(__file__).resolve().parent.parent
REPORT = Path("benchmarks/results/bench.json")  #: the default report, relative to the root
PAGE = Path("docs/performance.md")  #: the default page, relative to the root
SCHEMA = "benchmarks/2"
MEMORY_FILE = "rank-memory.json"  #: beside the report: the memory rows of a run of their own
BEGIN, END = markers("tools/bench_page.py", REPORT)  #: the lines above and below the generated tables
QUIET_SHARE = 0.9  #: below this share of a core the page says the machine was shared


def _t(s: float | None) -> str:
    """A time in ms below 1 s, else in s (three significant figures)."""
    if s is None:
        return "-"
    return f"{1e3 * s:.3g} ms" if s < 1 else f"{s:.3g} s"


def _x(r: float | None) -> str:
    return "-" if r is None else f"x{r:.3g}"


def _runs(runs: list[float]) -> str:
    lo, hi = min(runs), max(runs)
    return _t(lo) if len(runs) == 1 else f"runs {_t(lo)}-{_t(hi)}"


def _table(head: list[str], rows: list[list[str]]) -> list[str]:
    return [
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
        *("| " + " | ".join(row) + " |" for row in rows),
    ]


def _cases(r: dict[str, Any]) -> list[str]:
    c, paper, rows = r["cases"], r["paper_s"], []
    for key, label in (
        ("case1_p1", "Case 1, Problem 1 (no RVDS)"),
        ("case2_p1", "Case 2 initial, Problem 1 (no RVDS)"),
    ):
        if key not in c:
            continue
        lp, cdd = c[key]["lp"], c[key]["cdd"]
        if cdd is None:
            base = "cdd not run (`--quick`)"
        elif cdd["finished"]:
            base = f"cdd {_t(cdd['wall_s'])}"
        else:
            base = f"cdd > {cdd['time_limit_s']:.0f} s (its cap)"
        what = f"{label}: {lp['vertices']} vertices, {lp['num_lps']:,} LPs"
        rows.append([what, _t(lp["median_s"]), base, _t(paper[key])])
    for key, label in (("case1_p2", "Case 1, Problem 2"), ("case2_p2", "Case 2 initial, Problem 2")):
        if key not in c:
            continue
        p = c[key]
        what = f"{label} ({p['size']['rvds']} RVDS vertices; HiGHS `run` {_t(p['split']['highs_run_s'])})"
        base = f"cvxpy {_t(p['baseline']['median_s'])} ({_x(p['ratio_baseline_over_ours'])})"
        rows.append([what, _t(p["ours"]["median_s"]), base, _t(paper[key])])
    if "lift" in r:
        lf = r["lift"]
        rows.append(
            [
                f"full lift, L + S, {lf['num_states']} states, no plots",
                f"{_t(lf['median_s'])} ({_runs(lf['runs_s'])})",
                "-",
                "-",
            ]
        )
    if "sweeps" in r:
        sw = r["sweeps"]
        for j, pj in sw["per_jobs"].items():
            what = f"Fig. 9 sweeps, {sw['points']} points, 1 process (cold caches)"
            ours = f"{_t(pj['median_s'])} ({_runs(pj['runs_s'])})"
            if j != "1":
                what = f"the same on {j} processes (forked after the lift; pool start-up included)"
                ours += f", {_x(sw['speedup'].get(j))}"
            rows.append([what, ours, "-", "-"])
    return _table(["measurement", "mjtvm", "baseline, same run", "paper"], rows)


def _hands(r: dict[str, Any]) -> list[str]:
    rows = [
        [
            f"`{name}`",
            f"{h['joints']}, {h['contacts']}",
            _t(h["load"]["median_s"]),
            _t(h["state"]["median_s"]),
            f"{_t(h['p2']['median_s'])} ({h['rvds']} RVDS)",
            _t(h["lift"]["median_s"]),
        ]
        for name, h in r["hands"].items()
    ]
    head = ["grasp", "joints, contacts", "load + configure", "grasp state", "Problem 2", "lift, 30 states"]
    return _table(head, rows)


def _scaling(r: dict[str, Any]) -> list[str]:
    sc = r["scaling"]
    rows = [
        [
            str(f),
            str(s["joints"]),
            _t(s["p2"]["median_s"]),
            _t(s["p1"]["median_s"]),
            "-" if s["p1_vertices"] is None else f"{s['p1_vertices']:,}",
            f"{s['memory_mib']['tracemalloc_peak_p2']:.2f} MiB",
        ]
        for f, s in sc["per_fingers"].items()
    ]
    head = [
        "fingers",
        "joints",
        "Problem 2 per state",
        "Problem 1 (RVDS cone)",
        "its vertices",
        "traced memory, Problem 2",
    ]
    doublings = "; ".join(
        f"{k}: Problem 2 {_x(v['p2_time'])}, Problem 1 {_x(v['p1_time'])}"
        for k, v in sc["ratios"].items()
        if v["fingers"] == 2.0
    )
    slope = sc["p2_loglog_exponent"]
    tail = f"Per doubling of the fingers: {doublings}"
    if slope is not None:
        tail += f". Problem 2's log-log slope over the range: {slope:.2f}"
    return [*_table(head, rows), "", tail + "."]


def _dataset(r: dict[str, Any]) -> list[str]:
    ds, rows = r["dataset"], []
    for key, label in (("batch_weight", "weight as REFS"), ("batch_six_wrenches", "six test wrenches")):
        b = ds[key]
        one = b["per_jobs"]["1"]
        what = f"batch Problem 2, {label} ({b['lps_per_grasp']} LPs per grasp), 1 process"
        ours = f"{_t(one['median_s'] / b['states'])} per grasp, **{one['grasps_per_s']:.3g} grasps/s**"
        rows.append([what, ours, _t(ds["cli"]["paper_s"]) + " per state"])
        for j, pj in b["per_jobs"].items():
            if j != "1":
                what = f"the same batch on {j} processes (pool start-up included)"
                rows.append([what, f"{pj['grasps_per_s']:.3g} grasps/s, {_x(b['speedup'].get(j))}", "-"])
    c = ds["cli"]
    rows.append(
        [
            "`mjtvm solve STATE.json` as a process (a 6-LP state of the batch)",
            f"**{_t(c['solve']['median_s'])}** ({_runs(c['solve']['runs_s'])})",
            _t(c["paper_s"]) + " per state",
        ]
    )
    for key, label in (
        ("import_mjtvm", '`python -c "import mjtvm"`'),
        (
            "import_dependencies",
            '`python -c "import numpy, highspy, jsonschema"` (what `solve` imports besides mjtvm)',
        ),
        ("python_startup", '`python -c "pass"`'),
    ):
        rows.append([label, _t(c[key]["median_s"]), "-"])
    first = ds["batch_weight"]
    note = f"{first['states']} states per batch, {first['joints']} joints, {first['contacts']} contacts: {ds['hand']}."
    return [*_table(["measurement", "mjtvm", "paper"], rows), "", note]


def _peers(r: dict[str, Any]) -> list[str]:
    pe, rows = r["peers"], []
    for n, f in pe["fingers"].items():
        rows.append(
            [
                str(n),
                _t(f["tvms"]["ours_s"]),
                _t(f["function"]["ours_s"]),
                _t(f["function"]["peer_s"]),
                f"{_x(f['tvms']['ratio'])}, {_x(f['function']['ratio'])}",
                _t(f["force"]["ours_s"]),
                _t(f["force"]["peer_s"]),
                _x(f["force"]["ratio"]),
                f"{_t(f['lp']['median_s'])} ({f['lp']['num_lps']} LPs)",
            ]
        )
    ex = pe["four_link_example"]
    v, fo = ex["velocity"], ex["force"]
    rows.append(
        [
            "pycapacity's four-link robot (2 x 4)",
            "-",
            _t(v["ours_s"]),
            _t(v["peer_s"]),
            _x(v["ratio"]),
            _t(fo["ours_s"]),
            _t(fo["peer_s"]),
            _x(fo["ratio"]),
            "-",
        ]
    )
    head = [
        "joints",
        "`tvms(state)` (zonotope)",
        "`velocity_polytope`",
        f"{pe['peer']} `velocity_polytope`",
        "ratio: tvms, function",
        "`force_polytope`",
        f"{pe['peer']} `force_polytope`",
        "ratio",
        'the LPs (`method="lp"`)',
    ]
    agree = max(f["vs_lp"]["hausdorff_rel"] for f in pe["fingers"].values())
    note = (
        f"{pe['peer']} {pe['peer_version']}; ratio = {pe['peer']} / mjtvm. The zonotope's vertices and the "
        f"LP path's agree to {agree:.1e} relative."
    )
    return [*_table(head, rows), "", note]


def _floor(r: dict[str, Any]) -> list[str]:
    rows = [
        [
            f"`{name}`",
            str(s["lps"]),
            _t(s["total_s"]),
            _t(s["highs_run_s"]),
            f"{s['ratio']:.3g} ({s['ratio_p10']:.3g}-{s['ratio_p90']:.3g})",
            f"{s['core_share']:.2f}",
        ]
        for name, s in r["floor"]["states"].items()
    ]
    head = ["state", "LPs", "Problem 2", "inside HiGHS `run`", "ratio, median (p10-p90)", "core share"]
    return _table(head, rows)


def _verdict(row: dict[str, Any]) -> str:
    """Met, not met, or "loaded" (a core share below 0.8: never reported as met)."""
    if row.get("loaded"):
        return "loaded"
    return "-" if row.get("met") is None else "met" if row["met"] else "**not met**"


def _rank(r: dict[str, Any]) -> list[str]:
    rk = r["rank"]
    th, f, g, j = rk["throughput"], rk["p2_floor"], rk["fingers"], rk["jobs"]
    n = th["grasps"]
    rows = [
        [
            f"`mjtvm rank`, {label} ({n} grasps)",
            f"{th[key]['grasps_per_cpu_s']:.3g} grasps/CPU-s ({_t(th[key]['cpu_s'] / n)} CPU per grasp)",
            _t(th[key]["wall_s"] / n),
            f"{th[key]['core_share']:.2f}",
            f">= {th[key]['target']:g}",
            _verdict(th[key]),
        ]
        for key, label in (("classic", "classic measures"), ("none", "TVMMP alone"))
    ]
    t22 = rk.get("throughput_22")  # absent from reports before the five-finger hand
    if t22 is not None:
        n22 = t22["grasps"]
        rows += [
            [
                f"`mjtvm rank`, {label}, {t22['joints']}-joint Shadow hand, {t22['lps']} LPs ({n22} grasps)",
                f"{t22[key]['grasps_per_cpu_s']:.3g} grasps/CPU-s ({_t(t22[key]['cpu_s'] / n22)} CPU per grasp)",
                _t(t22[key]["wall_s"] / n22),
                f"{t22[key]['core_share']:.2f}",
                f">= {t22[key]['target']:g}",
                _verdict(t22[key]),
            ]
            for key, label in (("classic", "classic measures"), ("none", "TVMMP alone"))
        ]
        ceiling = t22["none"].get("highs_ceiling_grasps_per_s")  # absent before 2026-12-03
        if ceiling is not None:
            rows.append([
                f"HiGHS `run` alone in the {t22['joints']}-joint TVMMP-alone pass: the ceiling of any code around it",
                f"{ceiling:.3g} grasps/s ({_t(t22['none']['highs_run_ms_per_grasp'] / 1e3)} per grasp)",
                "-", "-", "-", "-",
            ])  # fmt: skip
    for key, hand in (("p2_floor", ""), ("p2_floor_22", "22-joint Shadow hand, ")):
        f = rk.get(key)
        if f is None:  # p2_floor_22: absent from reports before it
            continue
        hp = f.get("highs_path")  # absent before the batch row ran rank's compiled path
        what = "`rank`'s path (compiled re-solves)" if hp is not None else "HiGHS path"
        rows.append([
            f"Problem 2 on {what} over HiGHS-alone `run`, summed over the batch ({hand}{f['states']} states, {f['lps']} LPs)",
            f"x{f['ratio']:.3g} ({_t(f['wall_s'])} / {_t(f['highs_run_s'])})",
            _t(f["wall_s"]), f"{f['core_share']:.2f}", f"<= x{f['target']:g}", _verdict(f),
        ])  # fmt: skip
        if hp is not None:
            rows.append([
                "the same on HiGHS alone (`mjtvm solve`'s path), for comparison",
                f"x{hp['ratio']:.3g} ({_t(hp['wall_s'])} / {_t(f['highs_run_s'])})",
                _t(hp["wall_s"]), "-", "-", "-",
            ])  # fmt: skip
    per = g["per_fingers"]
    rows.append([
        "Problem 2 per LP, 32 fingers over 16",
        f"x{g['ratio']:.3g} ({_t(per['32']['cpu_s_per_lp'])} / {_t(per['16']['cpu_s_per_lp'])} CPU)",
        f"{_t(per['32']['wall_s'] / per['32']['lps'])} / {_t(per['16']['wall_s'] / per['16']['lps'])}",
        f"{g['core_share']:.2f}", f"<= x{g['target']:g}", _verdict(g),
    ])  # fmt: skip
    k = str(j["jobs"])
    rows.append([
        f"`rank_rows` on {k} processes ({j['grasps']} grasps; rows identical: {'yes' if j['rows_identical'] else 'no'})",
        f"x{j['speedup']:.3g}",
        f"{_t(j[k]['wall_s'])} ({_t(j['1']['wall_s'])} on 1)",
        f"{j['core_share']:.2f}", f">= x{j['target']:g}", _verdict(j),
    ])  # fmt: skip
    v = rk.get("verify")  # absent from reports before issue 35's row
    if v is not None and "error" in v:
        rows.append(["`mjtvm rank --verify`", f"failed: {v['error']}", "-", "-", "-", "-"])
    elif v is not None:
        rows.append([
            f"`mjtvm rank --verify` as a process ({v['grasps']} grasps, {v['simulated']} simulated)",
            f"{v['grasps_per_cpu_s']:.3g} grasps/CPU-s ({_t(v['cpu_s'] / v['grasps'])} CPU per grasp)",
            _t(v["wall_s"] / v["grasps"]), f"{v['core_share']:.2f}", f">= {v['target']:g}", _verdict(v),
        ])  # fmt: skip
    memory = rk["memory"]
    separate = r.get("rank_memory")
    if separate is not None:  # the memory rows of a run of their own (benchmarks.rank.main)
        memory = separate["memory"]
    for size, m in memory["sizes"].items():
        if "error" in m:
            rows.append(
                [f"peak RSS, {int(size):,} generated grasps", f"failed: {m['error']}", "-", "-", "-", "-"]
            )
            continue
        rows.append([
            f"peak RSS of `mjtvm rank`, {int(size):,} generated grasps",
            f"{m['peak_rss_mib']:.0f} MiB ({m['cpu_s']:.3g} s CPU)",
            _t(m["wall_s"]), f"{m['core_share']:.2f}", "flat", "loaded" if m["loaded"] else "-",
        ])  # fmt: skip
    d = memory.get("dask")
    if d is not None:
        if "error" in d:
            rows.append(
                ["`mjtvm rank --cluster`, local Dask cluster", f"failed: {d['error']}", "-", "-", "-", "-"]
            )
        else:
            same = "yes" if d["files_identical"] else "**no**"
            rows.append([
                f"`mjtvm rank --cluster`, local Dask cluster of {d['workers']} worker processes, "
                f"{d['grasps']:,} generated grasps: files identical to one process",
                same, _t(d["wall_s"]), f"{d['core_share']:.2f}", "identical",
                "met" if d["files_identical"] else "**not met**",
            ])  # fmt: skip
    head = ["measurement", "mjtvm", "wall", "core share", "target", ""]
    out = _table(head, rows)
    if "mib_per_1000_grasps" in memory:
        out += ["", f"Peak RSS grows by {memory['mib_per_1000_grasps']:.3g} MiB per 1,000 grasps."]
    if separate is not None:
        out += [
            "",
            f"The peak-RSS and Dask rows are a run of their own (`{separate['command']}`, started "
            f"{separate['started']}, `benchmarks/results/rank-memory.json`): the 40,000-grasp size "
            "takes about 40 minutes with its Dask run, too long for the suite.",
        ]
    return out


def _shares(r: dict[str, Any]) -> list[float]:
    """Every ``core_share`` the report records (CPU time over wall time of a solving process)."""
    out = [s["core_share"] for s in r.get("floor", {}).get("states", {}).values() if "core_share" in s]
    for key in ("batch_weight", "batch_six_wrenches"):
        for pj in r.get("dataset", {}).get(key, {}).get("per_jobs", {}).values():
            out += pj.get("core_share", [])
    return out


def _run(r: dict[str, Any]) -> list[str]:
    m = r["machine"]
    packages = ", ".join(f"{k} {v}" for k, v in m["packages"].items())
    text = (
        f"The run: {m['cpu']}, {m['logical_cpus']} logical CPUs ({m['usable_cpus']} usable), "
        f"{m['platform']}, Python {m['python']}, {packages}; "
        + ("`--quick` (no cdd, no Case 2 Problem 1)" if r["settings"]["quick"] else "the full suite")
        + f", {r['total_wall_s']:.0f} s in all. Times are medians over repeats."
    )
    shares = _shares(r)
    if shares and min(shares) < QUIET_SHARE:
        text += (
            f" The machine was shared with other jobs during this run: a solving process got "
            f"{min(shares):.2f}-{max(shares):.2f} of a core (`core_share`), so these times are longer, and "
            "the speed-ups on 2 processes lower, than on a quiet machine."
        )
    return [text]


def render(report: dict[str, Any]) -> str:
    """The generated part of the page, markers included, from a ``benchmarks/2`` report.

    Parameters
    ----------
    report : dict
        A ``NAME.json`` of ``python -m benchmarks``.

    Returns
    -------
    str
        The lines from :data:`BEGIN` to :data:`END`, each section present in the report.

    Raises
    ------
    ValueError
        If the report's schema is not ``benchmarks/2``.
    """
    if report.get("schema") != SCHEMA:
        raise ValueError(f"not a {SCHEMA} report: schema {report.get('schema')!r}")
    lines = [BEGIN, "", *_run(report)]
    sections = (
        ("cases", "The paper's cases, the lift and the sweeps", _cases),
        ("hands", "Hands mjtvm does not generate", _hands),
        ("scaling", "Scaling", _scaling),
        ("dataset", "Dataset scale", _dataset),
        ("peers", "Velocity and force polytopes against pycapacity", _peers),
        ("floor", "Problem 2 against its solver's floor", _floor),
        ("rank", "Ranking a dataset (`mjtvm rank`)", _rank),
    )
    for key, title, fn in sections:
        if report.get(key):
            lines += ["", f"### {title}", "", *fn(report)]
    return "\n".join([*lines, "", END])


def render_with_memory(report: dict[str, Any]) -> str:
    """`render()`, with the memory rows of ``rank-memory.json`` beside the report when it is there."""
    extra = ROOT / REPORT.parent / MEMORY_FILE
    if extra.is_file():
        report = {**report, "rank_memory": json.loads(extra.read_text(encoding="utf-8"))}
    return render(report)


def main(argv: list[str] | None = None) -> int:
    """``--write`` the page, or ``--check`` it; return the process exit code (1: stale)."""
    return page_main(
        argv,
        tool="tools/bench_page.py",
        render=render_with_memory,
        report=ROOT / REPORT,
        page=ROOT / PAGE,
        begin=BEGIN,
        end=END,
    )


if __name__ == "__main__":
    raise SystemExit(main())
