r"""Replay of the scripted lift: TVMMP along it (paper section 5, Fig. 8) and the Fig. 9 sweeps.

For every state of a [`Lift`][mjtvm.lift.trajectory.Lift], Problem 2 (eq. 31-35,
[`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp]) is solved with fingers 2 and 4 as L-points and as S-points (slide
directions of the chosen reading, [`mjtvm.lift.trajectory`][mjtvm.lift.trajectory]), at the given mu and mg; the sweeps
take L-points at mu in [`SWEEP_MUS`][mjtvm.jobs.replay.SWEEP_MUS] (mg = [`SWEEP_MU_MG`][mjtvm.jobs.replay.SWEEP_MU_MG]) and mg in
[`SWEEP_MGS`][mjtvm.jobs.replay.SWEEP_MGS] (mu = [`SWEEP_MG_MU`][mjtvm.jobs.replay.SWEEP_MG_MU]). Results go to ``lift.csv`` (one row per
(variant, reading, state) of the main run), ``lift-sweeps.csv``, ``lift.json`` (the same
with metadata, the lift's bookkeeping and the sweeps) and, unless disabled, ``fig8.png``,
``fig9a.png`` and ``fig9b.png`` (TVMMP vs the object height z, m).

Where HiGHS cannot settle an LP (status ``Unknown`` after its cold restarts), [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp]
itself solves that pair with Clarabel and says so in ``settled_by``; the ``solver`` column names
the backends that produced a row's alphas (``highs``, ``clarabel`` or ``highs+clarabel``).
The records and their CSV and JSON are [`mjtvm.jobs.replay_records`][mjtvm.jobs.replay_records].
"""

from __future__ import annotations

import json
import math
import statistics
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from mjtvm.errors import ParamError
from mjtvm.jobs.figures import ALPHA_UNIT, lift_axes, lift_png, lift_x
from mjtvm.jobs.replay_records import Record, lift_dict, record_state, records_csv
from mjtvm.jobs.style import no_value
from mjtvm.lift.states import READINGS, VARIANTS, lift_state
from mjtvm.lift.trajectory import Lift, scripted_lift
from mjtvm.model.limits import with_limit_horizon
from mjtvm.model.state import GraspState

__all__ = [
    "SCHEMA",
    "SWEEP_MGS",
    "SWEEP_MG_MU",
    "SWEEP_MUS",
    "SWEEP_MU_MG",
    "ReplayOutput",
    "hand_name",
    "paper_hand",
    "replay_lift",
    "run_replay",
    "sweep_lift",
    "time_replay",
]

SCHEMA = "mjtvm.lift/1"
SWEEP_MUS = (0.1, 0.2, 0.3, 0.4, 0.5)  # Fig. 9a
SWEEP_MU_MG = 2.0  # N
SWEEP_MGS = (0.0, 1.0, 2.0, 3.0)  # Fig. 9b (N)
SWEEP_MG_MU = 0.3


def grasp_defaults(grasp: Any, mu: float | None, mg: float | None) -> tuple[float, float]:
    """``mu`` and ``mg`` (N), the grasp's own where ``None``: its friction coefficient and the
    magnitude of its weight (REFS).

    The lift's checks (``replay``, ``verify``) load the object with its weight alone, along
    the model's gravity through its centre of mass: each refusal names the option (``--mu``,
    ``--mg``) or the grasp-file key (``mu``, ``[refs]``) to change, or the model's gravity.

    Raises
    ------
    ParamError
        No single friction coefficient and no ``mu``; REFS other than the weight alone and no
        ``mg``; an ``mg`` the grasp's REFS cannot take (no weight in them, no gravity in the
        model).
    """
    if mu is None:
        mu = getattr(grasp, "default_mu", None)
        if mu is None:
            raise ParamError(
                "mu",
                f"the grasp {grasp.name!r} has no single friction coefficient: give one with --mu, "
                "or one top-level mu in the grasp file",
            )
    document = getattr(grasp, "document", None)
    refs = document.get("refs") if isinstance(document, Mapping) else None
    model = getattr(grasp, "model", None)
    no_gravity = model is not None and not np.any(np.asarray(model.opt.gravity))
    if no_gravity and (mg is not None or getattr(grasp, "weight_mg", None) is not None):
        raise ParamError(
            "mg",
            f"the model of the grasp {grasp.name!r} has no gravity (MuJoCo's option gravity is 0 0 0): "
            "the object has no weight to load or scale; give the model a gravity "
            '(<option gravity="0 0 -9.81"/> in its MJCF file)',
        )
    if mg is not None and isinstance(refs, Mapping) and not refs.get("weight", True):
        raise ParamError(
            "mg",
            f"the grasp {grasp.name!r}'s REFS have no weight ([refs] weight = false): --mg cannot "
            "replace it; set [refs] weight = true in the grasp file",
        )
    if mg is None:
        mg = getattr(grasp, "weight_mg", None)
        if mg is None:
            raise ParamError(
                "mg",
                f"the grasp {grasp.name!r}'s REFS are not its weight alone: give the weight with --mg "
                "(N), or make the grasp file's [refs] the weight alone (weight = true, no wrenches)",
            )
    return float(mu), float(mg)


def paper_hand(name: str) -> str | None:
    """The paper's hand variant (``"default"``, ``"humanlike"``) of a shipped paper grasp's name
    (``case2``, ``case2-humanlike``, ...), ``None`` for any other grasp."""
    from mjtvm.paper_hand.scenario import SCENARIOS

    for variant in ("humanlike", "default"):
        base = name if variant == "default" else name.removesuffix("-" + variant)
        if base in SCENARIOS and (variant == "default" or base != name):
            return variant
    return None


def hand_name(grasp: Any, hand: str = "default") -> str:
    """The hand of a lift's grasp: the paper's hand variant for the paper's grasps, else the
    grasp's MJCF model (its file's stem, ``allegro_right_hand``)."""
    variant = paper_hand(str(grasp.name))
    if variant is not None:
        return variant
    model_path = getattr(grasp, "model_path", None)
    return hand if model_path is None else Path(model_path).stem


def _check(variants: Sequence[str], readings: Sequence[str], mu: float, mg: float) -> None:
    if not variants or len(set(variants)) != len(variants) or any(v not in VARIANTS for v in variants):
        raise ParamError(
            "variants", f"expected distinct values among {', '.join(VARIANTS)}, got {list(variants)}"
        )
    if not readings or len(set(readings)) != len(readings) or any(r not in READINGS for r in readings):
        raise ParamError(
            "readings", f"expected distinct values among {', '.join(READINGS)}, got {list(readings)}"
        )
    if not (math.isfinite(mu) and mu >= 0):
        raise ParamError("mu", f"expected a friction coefficient >= 0, got {mu!r}", mu)
    if not (math.isfinite(mg) and mg >= 0):
        raise ParamError("mg", f"expected a weight >= 0 (N), got {mg!r}", mg)


def replay_lift(
    lift: Lift,
    *,
    variants: Sequence[str] = VARIANTS,
    readings: Sequence[str] = ("physical",),
    mu: float = 0.3,
    mg: float = 1.0,
    progress: bool = False,
    bases: Sequence[GraspState] | None = None,
) -> tuple[Record, ...]:
    r"""TVMMP and every $\alpha_{kl}$ along the lift (Fig. 8).

    One record per (variant, reading, state): L-points once (reading ``None``), S-points once
    per reading. ``bases`` are [`lift_state()`][mjtvm.lift.states.lift_state] of each state, reused.
    """
    _check(variants, readings, mu, mg)
    runs = [(v, r) for v in variants for r in ((None,) if v == "L" else readings)]
    out = []
    bar = tqdm(total=len(runs) * lift.num_states, desc="replay", unit="state", disable=not progress)
    for i in range(lift.num_states):
        base = lift_state(lift, i) if bases is None else bases[i]
        for v, r in runs:
            out.append(record_state(lift, i, base, v, r, float(mu), float(mg)))
            bar.update()
    bar.close()
    order = {run: k for k, run in enumerate(runs)}
    return tuple(sorted(out, key=lambda rec: (order[(rec.variant, rec.reading)], rec.index)))


def sweep_lift(
    lift: Lift,
    *,
    mus: Sequence[float] = SWEEP_MUS,
    mu_mg: float = SWEEP_MU_MG,
    mgs: Sequence[float] = SWEEP_MGS,
    mg_mu: float = SWEEP_MG_MU,
    progress: bool = False,
    bases: Sequence[GraspState] | None = None,
) -> dict[str, tuple[Record, ...]]:
    r"""The Fig. 9 sweeps with L-points: ``"mu"`` (every mu at mg = ``mu_mg``) and ``"mg"``."""
    for m in mus:
        _check(("L",), ("physical",), float(m), mu_mg)
    for g in mgs:
        _check(("L",), ("physical",), mg_mu, float(g))
    pairs = list(
        dict.fromkeys([(float(m), float(mu_mg)) for m in mus] + [(float(mg_mu), float(g)) for g in mgs])
    )
    done: dict[tuple[float, float], list[Record]] = {p: [] for p in pairs}
    bar = tqdm(total=len(pairs) * lift.num_states, desc="sweeps", unit="state", disable=not progress)
    for i in range(lift.num_states):
        base = lift_state(lift, i) if bases is None else bases[i]
        for m, g in pairs:
            done[(m, g)].append(record_state(lift, i, base, "L", None, m, g))
            bar.update()
    bar.close()
    return {
        "mu": tuple(r for m in mus for r in done[(float(m), float(mu_mg))]),
        "mg": tuple(r for g in mgs for r in done[(float(mg_mu), float(g))]),
    }


ALPHA_LABEL = rf"TVMMP $\alpha$ {ALPHA_UNIT}"
READING_LABELS = {
    "literal": "literal reading (the paper's Fig. 8)",
    "physical": "physical reading (what the physics supports)",
}
"""Fig. 8's S-curves: which one is the paper's (the literal slide direction) and which one the physics check
supports (the slip the minimum-norm motion produces: friction resists the lift); ``docs/paper-results.md``."""


def _plot(curves: Sequence[tuple[str, str, Sequence[Record]]], title: str, x: str = "z") -> bytes:
    fig, ax = lift_axes(6.0, 4.0)
    for label, style, recs in curves:
        z = np.array([getattr(r, x) for r in recs])
        a = np.array([np.nan if r.result.tvmmp is None else r.result.tvmmp for r in recs])
        (line,) = ax.plot(z, a, style, label=label)
        no_value(ax, z[np.isnan(a)], color=line.get_color(), label=f"{label}: no solution")
    return lift_png(fig, ax, ylabel=ALPHA_LABEL, title=title, x=x)


def _figures(
    lift: Lift,
    hand: str,
    records: Sequence[Record],
    swept: dict[str, tuple[Record, ...]] | None,
    mu: float,
    mg: float,
) -> dict[str, bytes]:
    """Fig. 8 (solid L, dashed S) and, with the sweeps, Fig. 9a/9b: TVMMP vs z, as PNG bytes."""
    name = str(lift.scenario.name)
    paper = paper_hand(name) is not None  # the paper's figures keep the paper's names
    tag = f"{name.removesuffix('-' + hand)}, {hand} hand" if paper else name
    fig8, fig9a, fig9b = (
        ("Fig. 8", "Fig. 9a", "Fig. 9b") if paper else ("TVMMP along the lift", "mu sweep", "mg sweep")
    )
    runs = list(dict.fromkeys((r.variant, r.reading) for r in records))

    def label(v: str, rd: str | None) -> str:
        if "N" not in lift.roles:
            return "TVMMP (every finger an F-point)"
        if paper and rd in READING_LABELS:
            return f"{v}-points, {READING_LABELS[rd]}"
        return f"{v}-points" + (f" ({rd} reading)" if rd else "")

    curves = [
        (label(v, rd), "-" if v == "L" else "--", [r for r in records if (r.variant, r.reading) == (v, rd)])
        for v, rd in runs
    ]
    x = lift_x(lift)
    swept_points = "L-points" if "N" in lift.roles else "every finger an F-point"
    points = "" if "N" in lift.roles else f", {swept_points}"  # the curves' labels name L and S
    files = {"fig8.png": _plot(curves, f"{fig8}: {tag}{points}, $\\mu$ = {mu:g}, $mg$ = {mg:g} N", x)}
    if swept is not None:
        a = [(f"$\\mu$ = {m:g}", "-", [r for r in swept["mu"] if r.mu == m]) for m in SWEEP_MUS]
        files["fig9a.png"] = _plot(a, f"{fig9a}: {tag}, {swept_points}, $mg$ = {SWEEP_MU_MG:g} N", x)
        b = [(f"$mg$ = {g:g} N", "-", [r for r in swept["mg"] if r.mg == g]) for g in SWEEP_MGS]
        files["fig9b.png"] = _plot(b, f"{fig9b}: {tag}, {swept_points}, $\\mu$ = {SWEEP_MG_MU:g}", x)
    return files


@dataclass(frozen=True, eq=False)
class ReplayOutput:
    """What [`run_replay()`][mjtvm.jobs.replay.run_replay] computed and wrote (``files``: name -> path)."""

    lift: Lift
    records: tuple[Record, ...]
    sweeps: dict[str, tuple[Record, ...]] | None
    files: dict[str, Path]
    timings: dict[str, float]


def run_replay(
    *,
    scenario: str = "case2",
    hand: str = "default",
    mu: float | None = None,
    mg: float | None = None,
    num_states: int = 30,
    stop_margin: float | None = None,
    variants: Sequence[str] = VARIANTS,
    readings: Sequence[str] = ("physical", "literal"),
    out: str | Path = "results",
    plots: bool = True,
    sweeps: bool | None = None,
    progress: bool = False,
    on_replay: Callable[[ReplayOutput], None] | None = None,
    limit_horizon: float | None = None,
) -> ReplayOutput:
    r"""The main job: lift, replay, sweeps, ``lift.csv``/``lift.json`` and the plots in ``out``.

    ``stop_margin``: [`scripted_lift()`][mjtvm.lift.trajectory.scripted_lift]'s (the grasp's by default).
    ``sweeps``: the paper's Fig. 9 sweeps (mu 0.1-0.5 at mg 2 N, mg 0-3 N at mu 0.3); ``None``:
    for the paper's grasps only ([`paper_hand()`][mjtvm.jobs.replay.paper_hand]), not for a grasp file of one's own.
    ``mu`` and ``mg`` default to the grasp's ([`grasp_defaults()`][mjtvm.jobs.replay.grasp_defaults]): 0.3 and 1 N for the paper's
    Case 2. ``on_replay``, if given, is called with the lift and the replay's records (``sweeps``,
    ``files`` and ``timings`` still empty) as soon as they exist, before the sweeps and the
    plots: the CLI starts the rerun recording there ([`start_recording()`][mjtvm.viewer.recording.start_recording]).
    ``limit_horizon`` (m): Problem 2's travel horizon of the joint limits at every state, the
    replay's and the sweeps' (``None``: the grasp file's ``joint_limits.horizon``).

    The files are written as one set, atomically ([`mjtvm.formats.files.write_files()`][mjtvm.formats.files.write_files]), after
    everything is computed; the output folder is checked before any work.

    Raises
    ------
    ParamError
        A bad argument (``variants``, ``readings``, ``mu``, ``mg``).
    OutputError
        An output folder that cannot be created or written.
    ModelError
        Unknown scenario or hand, or a lift that cannot be made.
    """
    from mjtvm.formats.files import check_output_dir, write_files

    _check(variants, readings, 0.0 if mu is None else mu, 0.0 if mg is None else mg)
    outdir = check_output_dir(out, option="out")  # before any work
    times, t0 = {}, time.perf_counter()
    lift = scripted_lift(scenario, variant=hand, num_states=num_states, stop_margin=stop_margin)
    mu, mg = grasp_defaults(lift.scenario, mu, mg)
    if "N" not in lift.roles:  # every finger an F-point: the L/S variants are one and the same
        variants = ("L",)
    # the retyped states of the replay and the sweeps keep their base's joint limits
    bases = [with_limit_horizon(lift_state(lift, i), limit_horizon) for i in range(lift.num_states)]
    times["lift_s"], t0 = time.perf_counter() - t0, time.perf_counter()
    records = replay_lift(
        lift, variants=variants, readings=readings, mu=mu, mg=mg, progress=progress, bases=bases
    )
    times["replay_s"], t0 = time.perf_counter() - t0, time.perf_counter()
    if on_replay is not None:
        on_replay(ReplayOutput(lift, records, None, {}, {}))
    if sweeps is None:
        sweeps = paper_hand(str(lift.scenario.name)) is not None
    swept = sweep_lift(lift, progress=progress, bases=bases) if sweeps else None
    times["sweeps_s"], t0 = time.perf_counter() - t0, time.perf_counter()
    hand = hand_name(lift.scenario, hand)
    meta = {"scenario": lift.scenario.name, "hand": hand}
    # every file is rendered in memory first, then the set is written at once (mjtvm.formats.files)
    contents: dict[str, bytes | str] = {"lift.csv": records_csv(records, meta)}
    if swept is not None:
        tags = ["mu"] * len(swept["mu"]) + ["mg"] * len(swept["mg"])
        contents["lift-sweeps.csv"] = records_csv([*swept["mu"], *swept["mg"]], meta, tags)
    if plots:
        contents.update(_figures(lift, hand, records, swept, mu, mg))
    times["output_s"] = time.perf_counter() - t0  # CSV and PNG (the JSON holds the timings)
    doc = {
        "schema": SCHEMA,
        **meta,
        "mu": mu,
        "mg": mg,
        "variants": list(variants),
        "readings": list(readings),
        "limit_horizon": limit_horizon,
        "refs": records[0].state.refs.tolist() if records else None,
        "rvds": None if lift.scenario.rvds is None else lift.scenario.rvds.tolist(),
        "lift": lift_dict(lift),
        "records": [r.to_dict() for r in records],
        "sweeps": None
        if swept is None
        else {
            "mu": {
                "mg": SWEEP_MU_MG,
                "values": list(SWEEP_MUS),
                "records": [r.to_dict() for r in swept["mu"]],
            },
            "mg": {
                "mu": SWEEP_MG_MU,
                "values": list(SWEEP_MGS),
                "records": [r.to_dict() for r in swept["mg"]],
            },
        },
        "timings": times,
    }
    contents["lift.json"] = json.dumps(doc, indent=1) + "\n"
    order = ["lift.csv", "lift.json", "lift-sweeps.csv", "fig8.png", "fig9a.png", "fig9b.png"]
    files = {name: outdir / name for name in order if name in contents}
    write_files({files[name]: contents[name] for name in files}, option="out")
    return ReplayOutput(lift, records, swept, files, times)


def time_replay(*, repeats: int = 3, num_states: int = 30, hand: str = "default") -> dict[str, Any]:
    r"""Wall time of the full replay without plots and sweeps (both variants, files written).

    Returns ``{"runs_s": [...], "median_s": ..., "num_states": ..., "last": {phase: s}}``.
    """
    runs, last = [], {}
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            result = run_replay(hand=hand, num_states=num_states, out=tmp, plots=False, sweeps=False)
            runs.append(time.perf_counter() - t0)
            last = result.timings
    return {"runs_s": runs, "median_s": statistics.median(runs), "num_states": num_states, "last": last}
