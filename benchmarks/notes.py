r"""The notes of the report of [`benchmarks.suite`][benchmarks.suite]: for each target missed, where the
time goes and what would close it, from the measured figures of the run (nothing here is a fixed
claim). [`benchmarks.report`][benchmarks.report] appends them to the table.
"""

from __future__ import annotations

from typing import Any

from benchmarks.suite import TARGET_SWEEP_SPEEDUP, TARGETS_S

__all__ = ["auto_notes", "dataset_notes", "peer_notes"]


def auto_notes(report: dict[str, Any]) -> list[str]:
    """Where the time goes for the targets that are missed (measured numbers of this run)."""
    notes: list[str] = []
    t, c = report["targets"], report["cases"]
    if t.get("case2_p1") is False:
        lp = c["case2_p1"]["lp"]
        notes.append(
            f"Case 2 Problem 1 misses {TARGETS_S['case2_p1']:g} s: {lp['median_s']:.2f} s (median) for {lp['num_lps']} LPs: the "
            f"projection {lp['project_s']:.2f} s, of which {lp['highs_run_s']:.2f} s inside HiGHS and the "
            f"rest mostly Qhull on the polar points (~0.4 s in a profile), and the volume "
            f"{lp['volume_s']:.2f} s (Qhull per facet, on two threads). Two HiGHS sessions on two "
            "threads were tried for the rays and gave nothing end to end on this machine."
        )
    sw = report.get("sweeps")
    if sw and t.get("sweep_speedup_2") is False:
        one = sw["per_jobs"]["1"]["median_s"]
        start = sw["pool_startup_s"].get("2")
        ceiling = sw.get("speedup_ceiling", {}).get("2")
        notes.append(
            f"2-process sweep speed-up x{sw['speedup']['2']:.3f} < x{TARGET_SWEEP_SPEEDUP}: the serial run is only "
            f"{one:.2f} s; the workers are forked after the parent built the lift ({sw.get('start_method')}; "
            f"pool start-up {start:.2f} s), so the lift, built once and serially before any state is solved, "
            "bounds the speed-up"
            + (f" (ceiling x{ceiling:.2f})" if ceiling else "")
            + "; the rest is noise on a 2-core machine (x1.56-1.73 in three quiet runs)."
        )
    lf = report.get("lift")
    if lf and t.get("lift") is False:
        last = lf.get("last", {})
        notes.append(
            f"Full lift {lf['median_s']:.2f} s > 1 s (runs "
            + ", ".join(f"{x:.2f}" for x in lf["runs_s"])
            + " s; last "
            "run: "
            + ", ".join(f"{k} {v:.2f} s" for k, v in last.items())
            + "): building the lift (IK per state) "
            "and the LPs; the spread of the runs shows how much the machine's load moves this figure."
        )
    sc = report.get("scaling")
    if sc and not sc["p2_at_most_linear"]:
        per = sc["per_fingers"]
        notes.append(
            "P2 per state is not linear in every doubling: HiGHS run() time per state "
            + ", ".join(f"{f} fingers {1e3 * r['p2_highs_run_s']:.2f} ms" for f, r in per.items())
            + "; Python "
            + ", ".join(f"{1e3 * r['p2_python_s']:.2f}" for r in per.values())
            + " ms: the simplex work (HiGHS) grows faster than the LP size at the largest hand; closing it "
            "would need a warmer start across RVDS vertices or a smaller LP (fewer friction-cone edges)."
        )
    notes += dataset_notes(report)
    notes += peer_notes(report)
    return notes


def peer_notes(report: dict[str, Any]) -> list[str]:
    """The rows slower than pycapacity ([`benchmarks.peers`][benchmarks.peers]), with this run's split."""
    pe = report.get("peers")
    if not pe or pe.get("met") is not False:
        return []
    slow = [
        f"{n} joints {key} x{r[key]['ratio']:.2f}"
        for n, r in pe["fingers"].items()
        for key in ("tvms", "function", "force")
        if r[key]["ratio"] < pe["target_ratio"]
    ]
    ex = pe["four_link_example"]
    slow += [
        f"four-link {k} x{ex[k]['ratio']:.2f}"
        for k in ("velocity", "force")
        if ex[k]["ratio"] < pe["target_ratio"]
    ]
    split = "; ".join(
        f"{n} joints: tvms {1e6 * r['tvms']['ours_s']:.0f} us of which the zonotope itself "
        f"{1e6 * r['function']['ours_s']:.0f} us"
        for n, r in pe["fingers"].items()
    )
    return [
        "Slower than pycapacity: "
        + ", ".join(slow)
        + f". {split}: the rest of tvms is the condition's checks, the kinematic map (SVDs), the "
        "alphas and the result; every step is numpy on arrays of a few dozen numbers, so the time "
        "is per-call overhead (a few us per numpy call), not arithmetic."
    ]


def dataset_notes(report: dict[str, Any]) -> list[str]:
    """The dataset-scale misses ([`benchmarks.dataset`][benchmarks.dataset]), with this run's figures."""
    ds = report.get("dataset")
    if not ds:
        return []
    met, notes = ds["met"], []
    six = ds["batch_six_wrenches"]
    if not met["batch_six_wrenches"] or not met["batch_weight"]:
        notes.append(
            "Batch Problem 2 below its target: "
            + "; ".join(
                f"{b['lps_per_grasp']} LPs per grasp {b['per_jobs']['1']['grasps_per_s']:.0f} grasps/s "
                f"({1e3 * b['per_jobs']['1']['median_s'] / b['states']:.1f} ms per grasp)"
                for b in (ds["batch_weight"], six)
            )
            + f". In the instrumented run of {six['lps_per_grasp']} LPs, {six['highs_run_s']:.2f} s of "
            f"{six['instrumented_s']:.2f} s were inside HiGHS run() "
            f"({1e3 * six['highs_run_s'] / (six['states'] * six['lps_per_grasp']):.2f} ms per LP), the rest "
            "Python (a profile: certificates and column updates first); HiGHS alone allows "
            f"{six['states'] / six['highs_run_s']:.0f} grasps/s with 16 friction-cone edges, so closing "
            "the gap needs less simplex work (fewer edges, a warmer start across REFS vertices) as well "
            "as less overhead."
        )
    if not met["batch_speedup_2"]:
        two = six["per_jobs"][str(ds["jobs"])]
        notes.append(
            f"Batch on {ds['jobs']} processes x{six['speedup'][str(ds['jobs'])]:.2f} < "
            f"x{ds['targets']['batch_speedup_2']} (runs "
            + ", ".join(f"{x:.2f}" for x in two["runs_s"])
            + " s, pool start-up included); each process's share of a core: serial "
            + ", ".join(f"{x:.2f}" for x in six["per_jobs"]["1"]["core_share"])
            + f", {ds['jobs']} processes "
            + ", ".join(f"{x:.2f}" for x in two["core_share"])
            + " (below 1: the machine's other jobs took the rest)."
        )
    if not met["solve_process"]:
        c = ds["cli"]
        notes.append(
            f"mjtvm solve as a process {c['solve']['median_s']:.2f} s > {ds['targets']['solve_process']} s: "
            f"Python starts in {c['python_startup']['median_s']:.2f} s, importing numpy, scipy.sparse, "
            f"highspy and jsonschema alone takes {c['import_dependencies']['median_s']:.2f} s (scipy.sparse "
            "clones numpy's namespace, importing numpy.testing, f2py and ma), import mjtvm "
            f"{c['import_mjtvm']['median_s']:.2f} s; the solve itself is a few tens of ms."
        )
    return notes
