#!/usr/bin/env python3
r"""Differential run at scale: ``tvmmp`` (HiGHS eliminated / literal, Clarabel) against the cvxpy
reference (:func:`~oracles.reference.reference_tvmmp`, solver HiGHS; Clarabel where the
HiGHS reference and ``tvmmp`` disagree, to tell a reference that cannot decide).

States: ``--states N`` seeded random states (:func:`~tests.support.perturb.random_case`), each
also near-singular (one Jacobian column x 1e-6), in a unit system (lengths x 1e-3, forces
x 1e3, times x 1e2), in joint units of 1e-6 rad and with Jacobian round-off noise; plus the
shipped states with the same perturbations and the Allegro's fingertips as S-points (4 x 8).

Writes ``DIR/differential.csv`` (one row per pair and configuration) and
``DIR/differential.json`` (summary per family), and prints the summary.

CSV columns: ``state`` (the state's id), ``family`` (random, shipped, near-singular, units,
joint-unit, roundoff, allegro-S), ``k``, ``l`` (the pair), ``solver``, ``box`` (tvmmp's
configuration), ``alpha`` and ``ref_alpha`` (empty where not optimal), ``rel_err``
(``|alpha - ref| / |ref|``, absolute below the zero floor), ``status``, ``ref_status``,
``certified`` (tvmmp's verdict for the pair), ``noted`` (the pair has a note),
``ref_inconclusive`` (cvxpy's HiGHS and Clarabel disagree beyond 1e-6: not counted).
JSON: ``states``, ``seed``, ``random_states``, ``seconds`` and per family ``pairs``,
``max_rel_err``, ``over_1e-6_noted``, ``over_1e-6_without_note`` (the acceptance: 0),
``ref_inconclusive``, ``negative_alphas``, ``uncertified``, ``noted``.

Usage: ``python tools/differential.py --states 200 --seed 0 --out results/differential``
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from mjtvm.formats.state_file import load_state
from mjtvm.model.state import GraspState
from mjtvm.problem2.tvmmp import tvmmp
from oracles.reference import reference_tvmmp

# The test oracles live in tests/support, outside the installed package: import them from
# this checkout.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from tests.support.perturb import (
    add_jacobian_roundoff,
    random_case,
    rescale,
    rescale_joints,
    scale_joint_column,
    slide_contact,
)

CONFIGS = (("highs", "eliminated"), ("highs", "literal"), ("clarabel", "eliminated"))
REL, ZERO_REL = 1e-6, 1e-9  # as tests/problem2/test_differential.py
SHIPPED = ("allegro-ik", "allegro-sphere", "gripper3-box", "case1", "case1-s", "case2")
COLUMNS = [
    "state",
    "family",
    "k",
    "l",
    "solver",
    "box",
    "alpha",
    "ref_alpha",
    "rel_err",
    "status",
    "ref_status",
    "certified",
    "noted",
    "ref_inconclusive",
]


def _moving_column(state: GraspState) -> int:
    moving = np.flatnonzero(np.any([np.any(c.jacobian != 0.0, axis=0) for c in state.contacts], axis=0))
    return int(moving[-1])


def _variants(
    name: str, family: str, state: GraspState, seed: int
) -> Iterator[tuple[str, str, GraspState, str]]:
    """``(id, family, state, reference id)``: the state and its perturbations."""
    yield name, family, state, name
    yield (
        f"{name}/singular",
        "near-singular",
        scale_joint_column(state, _moving_column(state), 1e-6),
        f"{name}/singular",
    )
    yield f"{name}/units", "units", rescale(state, length=1e-3, force=1e3, time=1e2), name
    yield f"{name}/joint-unit", "joint-unit", rescale_joints(state, 1e-6), name
    yield f"{name}/roundoff", "roundoff", add_jacobian_roundoff(state, np.random.default_rng(seed)), name


def _cases(n: int, seed: int) -> Iterator[tuple[str, str, GraspState, str]]:
    from mjtvm.paper_hand.scenario import load_scenario

    shipped = {"pinch": load_state(Path(__file__).resolve().parents[1] / "mjtvm/data/examples/pinch.json")}
    for name in SHIPPED:
        s = load_scenario(name).state()
        shipped[name] = s if s.rvds is not None else s.with_(rvds=np.vstack([np.eye(6), -np.eye(6)]))
    for name, state in shipped.items():
        yield from _variants(name, "shipped", state, seed)
    for grasp in ("allegro-ik", "allegro-sphere"):
        for i in range(4):
            for th in 2.0 * np.pi * np.arange(8) / 8:
                key = f"{grasp}/S{i}/{th:.3f}"
                yield key, "allegro-S", slide_contact(shipped[grasp], i, float(th)), key
    for s in range(seed, seed + n):
        _, state = random_case(s)
        yield from _variants(f"random-{s}", "random", state, s)


def _close(a: float, b: float, floor: float) -> bool:
    return abs(a - b) <= max(REL * abs(b), floor)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--states", type=int, default=100, help="random states (each with 4 perturbations)")
    ap.add_argument("--seed", type=int, default=0, help="first seed")
    ap.add_argument("--out", type=Path, default=Path("results/differential"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    cases = list(_cases(args.states, args.seed))
    refs: dict[str, Any] = {}
    refs_c: dict[str, Any] = {}
    states = {key: st for key, _, st, _ in cases}
    rows: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    for key, family, state, ref_key in tqdm(cases, desc="states", unit="state"):
        if ref_key not in refs:
            refs[ref_key] = reference_tvmmp(states[ref_key], solver="HIGHS")
        ref_a, ref_s = refs[ref_key]
        floor = ZERO_REL * float(np.max(np.abs(ref_a[np.isfinite(ref_a)]), initial=1.0))
        for solver, box in CONFIGS:
            r = tvmmp(state, solver=solver, box=box, witnesses=False)  # type: ignore[arg-type]
            for k, l in np.ndindex(*ref_a.shape):
                if ref_s[k][l] == "skipped":
                    continue
                a, b = float(r.alpha[k, l]), float(ref_a[k, l])
                noted = any(p[0] == k and (p[1] == l or r.status[k][l] == "infeasible") for p, _ in r.notes)
                rel = (
                    abs(a - b) / abs(b)
                    if np.isfinite(a) and np.isfinite(b) and b != 0
                    else (0.0 if a == b else np.inf)
                )
                over = r.status[k][l] != ref_s[k][l] or (np.isfinite(a) and not _close(a, b, floor))
                inconclusive = False
                if over:  # can the reference decide? its Clarabel must agree with its HiGHS
                    if ref_key not in refs_c:
                        try:
                            refs_c[ref_key] = reference_tvmmp(states[ref_key], solver="CLARABEL")
                        except Exception:  # a reference that fails decides nothing
                            refs_c[ref_key] = None
                    rc = refs_c[ref_key]
                    inconclusive = (
                        rc is None
                        or rc[1][k][l] != ref_s[k][l]
                        or (np.isfinite(b) and not _close(float(rc[0][k, l]), b, floor))
                    )
                rows.append(
                    {
                        "state": key,
                        "family": family,
                        "k": k,
                        "l": l,
                        "solver": solver,
                        "box": box,
                        "alpha": a,
                        "ref_alpha": b,
                        "rel_err": rel,
                        "status": r.status[k][l],
                        "ref_status": ref_s[k][l],
                        "certified": r.certified[k][l],
                        "noted": noted,
                        "over": over,
                        "ref_inconclusive": inconclusive,
                    }
                )
    with (args.out / "differential.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    summary: dict[str, Any] = {}
    for fam in sorted({r["family"] for r in rows}):
        fr = [r for r in rows if r["family"] == fam]
        finite = [r["rel_err"] for r in fr if np.isfinite(r["rel_err"])]
        summary[fam] = {
            "pairs": len(fr),
            "max_rel_err": max(finite, default=0.0),
            "over_1e-6_noted": sum(r["over"] and r["noted"] and r["certified"] is False for r in fr),
            "over_1e-6_without_note": sum(
                r["over"] and not (r["noted"] and r["certified"] is False) and not r["ref_inconclusive"]
                for r in fr
            ),
            "ref_inconclusive": sum(r["over"] and r["ref_inconclusive"] for r in fr),
            "negative_alphas": sum(np.isfinite(r["alpha"]) and r["alpha"] < 0 for r in fr),
            "uncertified": sum(r["certified"] is False for r in fr),
            "noted": sum(r["noted"] for r in fr),
        }
    meta = {
        "states": len(cases),
        "seed": args.seed,
        "random_states": args.states,
        "seconds": time.perf_counter() - t0,
        "families": summary,
    }
    (args.out / "differential.json").write_text(json.dumps(meta, indent=1) + "\n")
    head = ["family", *next(iter(summary.values()))]
    print(" | ".join(head))
    for fam, s in summary.items():
        print(" | ".join([fam, *(f"{v:.2e}" if isinstance(v, float) else str(v) for v in s.values())]))
    print(f"{len(cases)} states, {len(rows)} pairs, {meta['seconds']:.0f} s")


if __name__ == "__main__":
    main()
