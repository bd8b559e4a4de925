r"""The files of ``mjtvm sweep``: the inputs digest, the rows as CSV, the checkpoint, resume and the lock.

[`run_sweep_files()`][mjtvm.jobs.sweep_files.run_sweep_files] runs a [`SweepFiles`][mjtvm.jobs.sweep_files.SweepFiles] (the grid of [`grid()`][mjtvm.jobs.sweep.grid]
and the solving of [`run_sweep()`][mjtvm.jobs.sweep.run_sweep]) into ``NAME.json`` and ``NAME.csv``,
keeping every finished row in ``NAME.partial.json`` while it runs.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mjtvm.errors import ParamError
from mjtvm.jobs.checkpoint import RowCheckpoint
from mjtvm.jobs.files import csv_text, model_files, stderr
from mjtvm.jobs.replay import grasp_defaults
from mjtvm.jobs.sweep import grid, point_lift, point_state, row_key, run_sweep

__all__ = ["SweepFiles", "run_sweep_files"]

CHECKPOINT_SCHEMA = "mjtvm.sweep-checkpoint/1"
CHECKPOINT_EVERY_S = 5.0
"""At most this often (s) the checkpoint is rewritten while a sweep runs (and always on an
interrupt or a failure, with every finished row)."""


def inputs_digest(grasp: str, hand: str, num_states: int) -> str:
    """A digest of what a sweep's rows of one grasp depend on beyond their point's fields.

    That is: the grasp file's bytes (mjtvm.grasp/1, shipped or the user's), its MJCF model's
    and those of the files the model names (includes, meshes), the number of lift states and
    mjtvm's version. ``--resume`` keeps a finished row only if its ``inputs`` equals this.

    Raises
    ------
    ModelError
        The grasp does not load (its own error, as the sweep would raise it).
    """
    from mjtvm import __version__
    from mjtvm.grasp import load_grasp

    loaded = load_grasp(grasp, hand=hand)
    h = hashlib.sha256(f"mjtvm {__version__}\n{grasp}\n{hand}\n{num_states}\n".encode())
    files = ([loaded.path] if loaded.path is not None else []) + model_files(loaded.model_path)
    if loaded.path is None:  # a grasp given as a document: its normalised content
        h.update(json.dumps(dict(loaded.document), sort_keys=True, default=str).encode())
    for path in files:
        h.update(f"{path.name}\n".encode())
        h.update(hashlib.sha256(path.read_bytes()).digest())
    return h.hexdigest()[:32]


def rows_csv(rows: Sequence[dict[str, Any]]) -> str:
    """The rows as CSV: the point's fields, ``z``, ``tvmmp``, ``feasible``, ``certified``,
    ``limiting_k``, ``limiting_l`` and ``alpha_k<k>_l<l>`` / ``status_k<k>_l<l>`` (empty
    where not optimal)."""
    flat = []
    for r in rows:
        out = {k: v for k, v in r.items() if k not in ("alpha", "status", "limiting")}
        for k, (alphas, statuses) in enumerate(zip(r["alpha"], r["status"])):
            for l, (a, st) in enumerate(zip(alphas, statuses)):
                out[f"alpha_k{k}_l{l}"] = "" if a is None else a
                out[f"status_k{k}_l{l}"] = st
        out["limiting_k"], out["limiting_l"] = ("", "") if r["limiting"] is None else r["limiting"]
        out["tvmmp"] = "" if r["tvmmp"] is None else r["tvmmp"]
        flat.append(out)
    return csv_text(flat)


_BUILT_FROM: dict[tuple[str, str, int], str] = {}
"""(grasp, hand, states) -> the inputs digest its cached lift ([`point_lift()`][mjtvm.jobs.sweep.point_lift]) was built from;
a lift of unknown or other inputs is built again."""


@dataclass(frozen=True)
class SweepFiles:
    """What ``mjtvm sweep`` runs: the grid (the arguments of [`grid()`][mjtvm.jobs.sweep.grid]), where its files go
    and how it is solved (the arguments of [`run_sweep()`][mjtvm.jobs.sweep.run_sweep]).

    Parameters
    ----------
    scenarios, hands, variants, readings
        The grid's grasps, hand models, contact types of the L/S fingers and slide readings.
    mus, mgs
        Friction coefficients and object weights (N); ``None``: the grasps' own, which must
        then agree.
    num_states
        Number of states along the lift.
    states
        The lift states to solve (indices below ``num_states``); ``None``: all.
    out, name
        The folder of the files and their stem: ``NAME.json``, ``NAME.csv`` and, while the
        sweep runs, ``NAME.partial.json``.
    jobs, cluster
        Local worker processes, or a Dask scheduler address (which overrides ``jobs``).
    resume
        Keep the finished rows of an earlier run ([`run_sweep_files()`][mjtvm.jobs.sweep_files.run_sweep_files]).
    quiet
        No progress bar and no resume summary.
    limit_horizon
        Problem 2's travel horizon of the joint limits (m) at every point; ``None``: the
        grasp file's ``joint_limits.horizon``.
    """

    scenarios: tuple[str, ...] = ("case2",)
    hands: tuple[str, ...] = ("default",)
    variants: tuple[str, ...] = ("L",)
    readings: tuple[str, ...] = ("physical",)
    mus: tuple[float, ...] | None = None
    mgs: tuple[float, ...] | None = None
    num_states: int = 30
    states: tuple[int, ...] | None = None
    out: str | Path = "results"
    name: str = "sweep"
    jobs: int = 1
    cluster: str | None = None
    resume: bool = False
    quiet: bool = False
    limit_horizon: float | None = None

    def __post_init__(self) -> None:
        bad = [i for i in (self.states or ()) if not 0 <= i < self.num_states]
        if bad:
            raise ParamError(
                "states", f"expected indices in [0, num_states = {self.num_states}), got {bad[0]}", bad[0]
            )


def run_sweep_files(
    run: SweepFiles, *, emit: Callable[[str], None] = print, notice: Callable[[str], None] = stderr
) -> list[Path]:
    r"""``mjtvm sweep``: check ``run.out``, lock it, resume, solve, write ``NAME.json`` and ``NAME.csv``.

    While the sweep runs, ``NAME.partial.json`` (schema ``mjtvm.sweep-checkpoint/1``) holds
    every finished row; it is rewritten atomically at most every [`CHECKPOINT_EVERY_S`][mjtvm.jobs.sweep_files.CHECKPOINT_EVERY_S]
    seconds and on an interrupt or failure, and removed once ``NAME.json`` and ``NAME.csv``
    are written. Every row carries ``inputs``, the [`inputs_digest()`][mjtvm.jobs.sweep_files.inputs_digest] of its grasp. With
    ``run.resume`` the rows of the checkpoint and of an earlier ``NAME.json`` whose point
    belongs to this grid and whose ``inputs`` equal the grasp's digest now are kept, and only
    the other points are solved; rows whose inputs changed (an edited grasp or model file,
    another mjtvm version, a row without ``inputs``) are solved again, and ``notice`` says how
    many. The result equals an uninterrupted run (tested).

    Raises
    ------
    OutputError
        ``run.out`` cannot be written, or another run holds its lock.
    ParamError
        ``mus`` or ``mgs`` left to grasps whose friction or weight differ, or an unreachable
        ``cluster``.
    StateError
        An unreadable checkpoint or earlier ``NAME.json``.
    """
    from mjtvm.formats.files import check_output_dir, output_lock, write_files

    outdir = check_output_dir(run.out)
    out_json, out_csv = outdir / f"{run.name}.json", outdir / f"{run.name}.csv"
    checkpoint = outdir / f"{run.name}.partial.json"
    digests = {(g, h): inputs_digest(g, h, run.num_states) for g in run.scenarios for h in run.hands}
    if any(_BUILT_FROM.get((g, h, run.num_states)) != d for (g, h), d in digests.items()):
        point_lift.cache_clear()  # a grasp file may have changed since this process built its lift
        point_state.cache_clear()
        _BUILT_FROM.clear()
    _BUILT_FROM.update(((g, h, run.num_states), d) for (g, h), d in digests.items())
    mus, mgs = run.mus, run.mgs
    if mus is None or mgs is None:  # the grasps' own: they must agree to make one grid
        defaults = {
            grasp_defaults(point_lift(g, h, run.num_states).scenario, None, None)
            for g in run.scenarios
            for h in run.hands
        }
        if len(defaults) > 1:
            raise ParamError(
                "mus", "the grasps have different friction or weight: give the coefficients and the weights"
            )
        mu0, mg0 = defaults.pop()
        mus, mgs = (mu0,) if mus is None else mus, (mg0,) if mgs is None else mgs

    with output_lock(outdir):
        points = grid(
            scenarios=run.scenarios,
            hands=run.hands,
            variants=run.variants,
            readings=run.readings,
            mus=mus,
            mgs=mgs,
            states=run.states,
            num_states=run.num_states,
            limit_horizon=run.limit_horizon,
        )
        wanted = {row_key(p) for p in points}
        ck = RowCheckpoint(
            checkpoint,
            CHECKPOINT_SCHEMA,
            key=row_key,
            digest=lambda r: digests[r["scenario"], r["hand"]],
            every_s=CHECKPOINT_EVERY_S,
            again="run again without resuming",
        )
        rows = ck.run(
            lambda done, on_rows: run_sweep(
                points,
                jobs=run.jobs,
                cluster=run.cluster,
                progress=not run.quiet,
                done=done,
                on_rows=on_rows,
            ),
            resume=run.resume,
            earlier=out_json,
            wanted=wanted,
            quiet=run.quiet,
            emit=emit,
            notice=notice,
        )
        doubtful = sum(r.get("certified") is False for r in rows)
        if doubtful:
            notice(
                f"mjtvm: warning: {doubtful} of {len(rows)} rows have an alpha that is not certified (column certified)"
            )
        written = write_files({out_json: json.dumps(rows, indent=1) + "\n", out_csv: rows_csv(rows)})
        checkpoint.unlink(missing_ok=True)
    return written
