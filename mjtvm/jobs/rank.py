r"""Rank a grasp dataset by TVMMP: one row per grasp, in this process, a local pool or on Dask.

[`rank_row()`][mjtvm.jobs.rank.rank_row] evaluates one [`DatasetGrasp`][mjtvm.grasp.document.dataset.DatasetGrasp] on the grasp
file's model ([`BatchModels`][mjtvm.grasp.resolve.batch.BatchModels]): the contacts MuJoCo finds, the
deepest penetration, the grasp state, Problem 2 ([`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp] with
``diagnose=True``, which says why an alpha is 0 or a pair infeasible). A grasp that cannot be
evaluated (no contact where the file expects one, a finger too deep, a solver failure, a bad
base) is a row with ``failure`` and ``reason``: it never stops the batch. [`rank_rows()`][mjtvm.jobs.rank.rank_rows]
runs the rows serially, on ``jobs`` local processes (forked on Linux after the model is
compiled, as [`mjtvm.jobs.sweep`][mjtvm.jobs.sweep] does) or on a Dask cluster; rows come back in the
dataset's order whichever way ran them. The files of ``mjtvm rank`` are
[`mjtvm.jobs.rank_files`][mjtvm.jobs.rank_files].
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import replace
from itertools import islice
from pathlib import Path
from typing import Any

from tqdm import tqdm

from mjtvm.errors import ModelError, ParamError, SolverError, StateError
from mjtvm.grasp import NoContactError
from mjtvm.grasp.contacts.report import kept_contacts
from mjtvm.grasp.document.dataset import DatasetGrasp
from mjtvm.grasp.resolve.batch import BatchModels
from mjtvm.jobs.pool import forks, run_calls
from mjtvm.jobs.rank_row import CLASSIC_COLUMNS, RankRow
from mjtvm.jobs.sweep import dask_client
from mjtvm.model.limits import with_limit_horizon
from mjtvm.model.state import GraspState
from mjtvm.problem2.tvmmp import tvmmp

__all__ = [
    "CLASSIC_COLUMNS",
    "FAILURES",
    "MEASURES",
    "RankRow",
    "batch_models",
    "rank_row",
    "rank_rows",
    "stream_rows",
]

FAILURES = ("no contact", "penetration", "grasp", "state", "solver")
"""The values of a failed row's ``failure``: no contact within ``contact_tolerance`` (the
nearest distance in the reason and ``nearest_distance``), a finger deeper than
``max_penetration`` (only with ``refuse_penetration``: else evaluated and flagged), another grasp-file or configuration error (an untyped
touching geom, an equality the configuration breaks, an unusable root), a state the core refuses, a
solver that fails."""

_BATCHES: dict[str, BatchModels] = {}
"""Grasp file -> its compiled models, per process (a worker compiles each model once)."""


def batch_models(grasp: str) -> BatchModels:
    """The [`BatchModels`][mjtvm.grasp.resolve.batch.BatchModels] of a grasp file, cached in this process.

    Raises
    ------
    GraspError
        The grasp file does not read.
    """
    if grasp not in _BATCHES:
        _BATCHES[grasp] = BatchModels.from_file(grasp)
    return _BATCHES[grasp]


def _classify(error: Exception) -> str:
    text = str(error)
    if isinstance(error, SolverError):
        return "solver"
    if "does not touch the object" in text:
        return "no contact"
    if "max_penetration" in text:
        return "penetration"
    return "grasp" if isinstance(error, ModelError) else "state"


#: Grasps per task of a process pool, at most: what an interruption can lose per worker.
TASK_GRASPS = 20
#: Tasks in flight per Dask worker thread: enough to keep it busy, few enough to hold.
DASK_WINDOW = 4


def _classic_columns(state: GraspState) -> dict[str, Any]:
    """The classic measures of the state the TVMMP was computed on
    ([`classic_measures()`][mjtvm.measures.classic_measures], without the velocity polytope)."""
    from mjtvm.measures import classic_measures

    doc = classic_measures(state, polytope=False).to_dict()
    return {key: doc[key] for key in CLASSIC_COLUMNS}


def _object_name(entry: DatasetGrasp, batch: BatchModels) -> str:
    if entry.obj_path is not None:
        return Path(entry.obj_path).stem
    return str(batch.doc["object"]["body"])


MEASURES = ("classic", "none")
"""``--measures``: ``classic`` (the classic measures beside the TVMMP) or ``none`` (TVMMP alone:
the measure columns empty)."""


def rank_row(
    batch: BatchModels,
    entry: DatasetGrasp,
    *,
    limit_horizon: float | None = None,
    refuse_penetration: bool = False,
    measures: str = "classic",
    verify: bool = False,
    hold_time: float | None = None,
) -> dict[str, Any]:
    r"""The row of one grasp: evaluated, or failed with its reason (Problem 2 with the travel
    horizon ``limit_horizon`` of the joint limits, m; ``None``: the grasp file's).

    A contact deeper than the grasp file's ``max_penetration`` is evaluated and flagged
    (``penetration_exceeded``), or with ``refuse_penetration`` a failure ``penetration``.
    ``measures``: one of [`MEASURES`][mjtvm.jobs.rank.MEASURES]. ``verify``: also the
    simulated ``sim_*`` columns ([`sim_columns()`][mjtvm.jobs.rank_sim.sim_columns]; a failed
    grasp's empty, ``sim_failure`` naming its failure), each push of the hold test lasting
    ``hold_time`` s (``None``: the protocol's 2 s).

    Returns
    -------
    dict
        The [`RankRow`][mjtvm.jobs.rank_row.RankRow] as a dict
        ([`RankRow.to_dict()`][mjtvm.jobs.rank_row.RankRow.to_dict]: its fields, in order, with
        their types and units there); ``docs/outputs.md`` documents each.
    """
    row = RankRow(entry.id, Path(entry.source).name, entry.index, _object_name(entry, batch), entry.obj_scale)
    limit = float(batch.doc["max_penetration"])
    try:
        grasp = batch.grasp(entry, max_penetration=math.inf)
        ignored = set(grasp.ignored_geoms)
        found = [c for c in kept_contacts(grasp) if c.geom not in ignored]
        depth = max([0.0, *(-float(c.distance) for c in found)])
        row = replace(
            row,
            contacts=len(found),
            penetration=depth,
            nearest_distance=min((float(c.distance) for c in found), default=None),
            penetration_exceeded=depth > limit,
        )
        if refuse_penetration and depth > limit:
            raise ModelError(
                "penetration",
                f"a contact is {1e3 * depth:.3g} mm inside the object > max_penetration "
                f"{1e3 * limit:.3g} mm (--refuse-penetration)",
            )
        state = with_limit_horizon(grasp.state(), limit_horizon)
        row = replace(row, contacts=len(state.contacts))
        result = tvmmp(state, witnesses=verify, diagnose=True, compiled=True)  # a batch: numba's re-solves
    except NoContactError as e:
        return _failed(
            replace(
                row,
                failure="no contact",
                reason=" ".join(str(e).split()),
                nearest_distance=e.nearest if row.nearest_distance is None else row.nearest_distance,
            ),
            verify,
        )
    except (ModelError, StateError, SolverError) as e:
        return _failed(replace(row, failure=_classify(e), reason=" ".join(str(e).split())), verify)
    doc = result.to_dict(witnesses=False)
    row = replace(
        row,
        **{key: doc[key] for key in ("tvmmp", "feasible", "alpha", "status", "limiting")},
        certified=all(c is not False for line in doc["certified"] for c in line),
    )
    reason = None
    if result.diagnosis and (result.tvmmp is None or result.tvmmp <= 0.0):
        limiting = result.limiting
        first = next(
            (d for d in result.diagnosis if limiting is not None and tuple(d.pair) == tuple(limiting)), None
        )
        chosen = first or result.diagnosis[0]
        reason = f"pair {list(chosen.pair)}: {chosen.cause}: {' '.join(chosen.message.split())}"
    if measures == "classic":
        try:
            row = replace(row, **_classic_columns(state))
        except Exception as e:  # Qhull, a solver: the TVMMP stands, the measures are flagged as missing
            why = f"classic measures not computed: {type(e).__name__}: {' '.join(str(e).split())[:200]}"
            reason = why if reason is None else f"{reason}; {why}"
    if verify:
        from mjtvm.jobs.rank_sim import sim_columns

        row = replace(row, **sim_columns(grasp, state, result, hold_time=hold_time, batch=batch, entry=entry))
    return replace(row, reason=reason).to_dict(sim=verify)


def _failed(row: RankRow, verify: bool) -> dict[str, Any]:
    """A failed grasp's row; with ``verify``, its empty ``sim_*`` columns and why."""
    if not verify:
        return row.to_dict()
    from mjtvm.jobs.rank_sim import not_simulated

    return replace(row, **not_simulated(f"not evaluated: {row.failure}")).to_dict(sim=True)


def _solve_chunk(
    grasp: str,
    entries: Sequence[DatasetGrasp],
    limit_horizon: float | None = None,
    refuse_penetration: bool = False,
    measures: str = "classic",
    verify: bool = False,
    hold_time: float | None = None,
) -> list[dict[str, Any]]:
    """The rows of some grasps of one grasp file (runs in a worker)."""
    batch = batch_models(grasp)
    return [
        rank_row(
            batch,
            e,
            limit_horizon=limit_horizon,
            refuse_penetration=refuse_penetration,
            measures=measures,
            verify=verify,
            hold_time=hold_time,
        )
        for e in entries
    ]


def _batches(
    entries: Iterable[DatasetGrasp], size: int, *, total: int | None = None, jobs: int = 1
) -> Iterator[list[DatasetGrasp]]:
    """Consecutive tasks of ``size`` grasps, read from ``entries`` as they are needed.

    With ``total`` (the number of ``entries``) the tasks shrink towards the end, each at most
    ``ceil(remaining / (4 jobs))`` grasps (guided self-scheduling, Polychronopoulos and Kuck
    1987): the last tasks are single grasps, so the workers finish within about one grasp of
    each other instead of half a task."""
    it = iter(entries)
    left = total
    while True:
        n = size if left is None else max(1, min(size, math.ceil(left / (4 * jobs))))
        task = list(islice(it, n))
        if not task:
            return
        if left is not None:
            left -= len(task)
        yield task


def stream_rows(
    grasp: str,
    entries: Iterable[DatasetGrasp],
    on_rows: Callable[[list[dict[str, Any]]], None],
    *,
    total: int | None = None,
    jobs: int = 1,
    cluster: Any = None,
    progress: bool = True,
    limit_horizon: float | None = None,
    refuse_penetration: bool = False,
    measures: str = "classic",
    verify: bool = False,
    hold_time: float | None = None,
) -> None:
    r"""Evaluate every grasp of ``entries`` ([`rank_row()`][mjtvm.jobs.rank.rank_row]) and hand
    the rows to ``on_rows`` as tasks finish (in no set order), keeping none of them: with a
    lazy ``entries`` the memory does not grow with the dataset (at most a few tasks per
    worker are in flight).

    Parameters
    ----------
    grasp
        The grasp file.
    entries
        The grasps to evaluate (ids unique), read as they are needed.
    on_rows
        Called in this process with the rows of every finished task.
    total
        How many ``entries`` holds, for the progress bar (``None``: unknown).
    jobs, cluster, progress, limit_horizon, refuse_penetration, measures, verify, hold_time
        As [`rank_rows()`][mjtvm.jobs.rank.rank_rows].

    Raises
    ------
    ParamError
        ``jobs`` below 1, an unknown ``measures`` or an unreachable ``cluster``.
    GraspError
        The grasp file does not read, or its model does not compile.
    """
    if jobs < 1:
        raise ParamError("jobs", f"expected a positive number of processes, got {jobs}")
    if measures not in MEASURES:
        raise ParamError("measures", f"expected one of {', '.join(MEASURES)}, got {measures!r}")
    opts = (limit_horizon, refuse_penetration, measures, verify, hold_time)
    batch_models(grasp).model()  # compiled before any fork, and its errors are the command's
    if total == 0:
        return  # nothing to evaluate (all resumed): no pool, no cluster, no bar
    bar = tqdm(total=total, desc="rank", unit="grasp", disable=not progress)

    def finished(rows: list[dict[str, Any]]) -> None:
        on_rows(rows)
        bar.update(len(rows))

    try:
        if cluster is not None:
            _run_dask(grasp, _batches(entries, TASK_GRASPS), cluster, finished, opts)
        elif jobs == 1:
            for e in entries:
                finished(_solve_chunk(grasp, [e], *opts))
        else:
            # Small tasks: a finished grasp reaches the checkpoint within a few grasps' time.
            size = TASK_GRASPS if total is None else max(1, min(TASK_GRASPS, math.ceil(total / (8 * jobs))))
            _run_pool(grasp, _batches(entries, size, total=total, jobs=jobs), jobs, finished, opts)
    finally:
        bar.close()


def rank_rows(
    grasp: str,
    entries: Iterable[DatasetGrasp],
    *,
    jobs: int = 1,
    cluster: Any = None,
    progress: bool = True,
    done: Mapping[str, dict[str, Any]] | None = None,
    on_rows: Callable[[list[dict[str, Any]]], None] | None = None,
    limit_horizon: float | None = None,
    refuse_penetration: bool = False,
    measures: str = "classic",
    verify: bool = False,
    hold_time: float | None = None,
) -> list[dict[str, Any]]:
    r"""The row of every grasp ([`rank_row()`][mjtvm.jobs.rank.rank_row]), in the order of
    ``entries``, held in memory ([`stream_rows()`][mjtvm.jobs.rank.stream_rows] keeps none:
    ``mjtvm rank`` streams them to disk).

    Parameters
    ----------
    grasp
        The grasp file.
    entries
        The dataset's grasps (ids unique).
    jobs
        Local worker processes (1 = in this process).
    cluster
        A Dask scheduler address or a ``distributed.Client``; overrides ``jobs``.
    progress
        Show a tqdm progress bar over the grasps to evaluate.
    done
        Rows already computed, by id: not evaluated again, returned as given.
    on_rows
        Called in this process with the rows of every finished task (checkpointing).
    limit_horizon
        Problem 2's travel horizon of the joint limits (m); ``None``: the grasp file's.
    refuse_penetration, measures, verify, hold_time
        As [`rank_row()`][mjtvm.jobs.rank.rank_row].

    Raises
    ------
    ParamError
        ``jobs`` below 1 or an unreachable ``cluster``.
    GraspError
        The grasp file does not read, or its model does not compile.
    """
    items = list(entries)
    table: dict[str, dict[str, Any]] = dict(done or {})
    todo = [e for e in items if e.id not in table]

    def finished(rows: list[dict[str, Any]]) -> None:
        table.update((r["id"], r) for r in rows)
        if on_rows is not None:
            on_rows(rows)

    stream_rows(
        grasp,
        todo,
        finished,
        total=len(todo),
        jobs=jobs,
        cluster=cluster,
        progress=progress,
        limit_horizon=limit_horizon,
        refuse_penetration=refuse_penetration,
        measures=measures,
        verify=verify,
        hold_time=hold_time,
    )
    return [table[e.id] for e in items]


def _run_pool(
    grasp: str,
    tasks: Iterable[list[DatasetGrasp]],
    jobs: int,
    finished: Callable[[list[dict[str, Any]]], None],
    opts: tuple[Any, ...] = (),
) -> None:
    """The tasks on ``jobs`` local processes, read as they finish: forked on Linux (the
    compiled model inherited), else started from a forkserver (each worker compiles it)."""
    run_calls(
        ((_solve_chunk, (grasp, task, *opts)) for task in tasks), jobs, finished, fork=forks(), in_order=False
    )


def _run_dask(
    grasp: str,
    tasks: Iterable[list[DatasetGrasp]],
    cluster: Any,
    finished: Callable[[list[dict[str, Any]]], None],
    opts: tuple[Any, ...] = (),
) -> None:
    """The tasks on a Dask cluster (the grasp file and the dataset's object files must be
    readable by the workers at the same paths), at most `DASK_WINDOW` per worker thread in
    flight, submitted as others finish."""
    with dask_client(cluster) as client:
        from distributed import as_completed

        todo = iter(tasks)
        limit = DASK_WINDOW * max(1, sum(client.nthreads().values()))
        running = as_completed(
            [client.submit(_solve_chunk, grasp, t, *opts, pure=False) for t in islice(todo, limit)]
        )
        for fut in running:
            finished(fut.result())
            for t in islice(todo, 1):
                running.add(client.submit(_solve_chunk, grasp, t, *opts, pure=False))
