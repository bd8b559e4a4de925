r"""The files of ``mjtvm rank``: the rows as JSON, CSV (and Parquet), the plots, the summary,
the checkpoint and ``--resume``.

[`run_rank_files()`][mjtvm.jobs.rank_files.run_rank_files] checks the datasets ([`scan_datasets()`][mjtvm.jobs.rank_inputs.scan_datasets]),
evaluates them ([`stream_rows()`][mjtvm.jobs.rank.stream_rows]) into the log ``NAME.partial.jsonl``
([`mjtvm.jobs.rank_log`][mjtvm.jobs.rank_log], the checkpoint), then writes from it ``NAME.json``, ``NAME.csv``,
``NAME.parquet`` (when ``pyarrow`` imports), ``NAME-objects.csv``, ``NAME-objects.png`` (TVMMP per object),
``NAME-tvmmp.png`` (the TVMMP histogram) and ``NAME-epsilon.png`` (TVMMP against the epsilon),
one row at a time, in rank order ([`mjtvm.jobs.rank_index`][mjtvm.jobs.rank_index]).
"""

from __future__ import annotations

import json
from array import array
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import OptionError, ParamError, StateError
from mjtvm.jobs.figures import ALPHA_UNIT
from mjtvm.jobs.files import csv_text, stderr
from mjtvm.jobs.rank import MEASURES, stream_rows
from mjtvm.jobs.rank_auc import auc_files, auc_summary
from mjtvm.jobs.rank_index import RankIndex, RankIndexBuilder, most_common
from mjtvm.jobs.rank_inputs import DatasetScan, inputs_digest, iter_datasets, scan_datasets
from mjtvm.jobs.rank_log import LOG_SCHEMA, RankLog
from mjtvm.jobs.rank_order import OBJECT_COLUMNS, check_sort, index_objects, objects_summary, with_rank
from mjtvm.jobs.rank_row import table_columns
from mjtvm.jobs.rank_tables import (
    AGAIN,
    has_pyarrow,
    json_list_rows,
    rows_csv_chunks,
    rows_json_chunks,
    rows_parquet_chunks,
)

__all__ = [
    "CHECKPOINT_SCHEMA",
    "RankFiles",
    "index_plots",
    "index_summary",
    "rank_plots",
    "rank_summary",
    "run_rank_files",
]

CHECKPOINT_SCHEMA = LOG_SCHEMA
LEGACY_SCHEMA = "mjtvm.rank-checkpoint/1"
"""The schema of an older version's ``NAME.partial.json``, which ``--resume`` still reads."""
CHECKPOINT_EVERY_S = 5.0
"""At most this often (s) the checkpoint is synced to disk (every finished task is flushed)."""


@dataclass(frozen=True)
class RankFiles:
    """What ``mjtvm rank`` runs.

    Parameters
    ----------
    grasp
        The grasp file (or a shipped grasp's name).
    datasets
        The dataset files (``.npz``, ``.npy``, ``.csv``: ``docs/datasets.md``).
    out, name
        The output folder and the files' stem.
    jobs, cluster
        Local worker processes, or a Dask scheduler address (overrides ``jobs``).
    resume
        Keep the finished rows of an earlier run whose inputs are unchanged.
    quiet
        No progress bar.
    plots
        Write the three PNG figures.
    limit_horizon
        Problem 2's travel horizon of the joint limits (m); ``None``: the grasp file's
        ``joint_limits.horizon``.
    pose
        The pipeline pose ranked: ``grasp``, ``pregrasp`` or ``squeeze`` (``<pose>_qpos``).
    dataset_key
        What a 2-D ``.npy`` array holds: ``grasp_qpos`` or ``qpos`` (``None``: refused).
    com_frame
        The object's frame (REFS moments, RVDS twists) at its centre of mass.
    refuse_penetration
        A grasp deeper than ``max_penetration`` fails (``penetration``) instead of being
        evaluated and flagged.
    measures
        ``classic`` or ``none`` ([`MEASURES`][mjtvm.jobs.rank.MEASURES]).
    sort
        The sort column of the files ([`SORT_COLUMNS`][mjtvm.jobs.rank_order.SORT_COLUMNS]).
    verify
        Also simulate every grasp (the ``sim_*`` columns, [`mjtvm.jobs.rank_sim`][mjtvm.jobs.rank_sim])
        and write ``NAME-auc.csv``, ``NAME-auc.json``, ``NAME-auc.png``
        ([`mjtvm.jobs.rank_auc`][mjtvm.jobs.rank_auc]).
    hold_time
        s each push of the hold test lasts (``None``: the protocol's 2 s); only with ``verify``.
    """

    grasp: str
    datasets: tuple[str, ...]
    out: str | Path = "results"
    name: str = "rank"
    jobs: int = 1
    cluster: str | None = None
    resume: bool = False
    quiet: bool = False
    plots: bool = True
    limit_horizon: float | None = None
    pose: str = "grasp"
    dataset_key: str | None = None
    com_frame: bool = False
    refuse_penetration: bool = False
    measures: str = "classic"
    sort: str = "tvmmp"
    verify: bool = False
    hold_time: float | None = None

    def __post_init__(self) -> None:
        if self.hold_time is not None and not self.verify:
            raise ParamError("hold_time", "the hold test's length is an option of the simulation (verify)")
        if not self.datasets:
            raise ParamError("datasets", "expected at least one dataset file")
        if self.measures not in MEASURES:
            raise ParamError("measures", f"expected one of {', '.join(MEASURES)}, got {self.measures!r}")
        check_sort(self.sort)


def rank_summary(rows: Sequence[dict[str, Any]]) -> str:
    """The summary ``mjtvm rank`` prints on stderr: counts, TVMMP quantiles, failures by reason."""
    return index_summary(RankIndex.from_rows(rows))


def index_summary(index: RankIndex) -> str:
    """[`rank_summary()`][mjtvm.jobs.rank_files.rank_summary] from a [`RankIndex`][mjtvm.jobs.rank_index.RankIndex]
    (counts by name where equal)."""
    ev, t = index.evaluated, index.tvmmp
    with np.errstate(invalid="ignore"):
        positive = np.sort(t[ev & (t > 0.0)])
        zero = int((ev & (t <= 0.0)).sum())
    infeasible = int((ev & np.isnan(t)).sum())
    failed = int((~ev).sum())
    lines = [
        f"rank: {len(index)} grasps: {len(positive)} with TVMMP > 0, {zero} with TVMMP 0, "
        f"{infeasible} infeasible, {failed} failed"
    ]
    if len(positive):
        q = np.quantile(positive, [0.0, 0.25, 0.5, 0.75, 1.0])
        lines.append(
            "TVMMP (> 0): min {:.4g}, q25 {:.4g}, median {:.4g}, q75 {:.4g}, max {:.4g}; max/min {:.3g}".format(
                *q, q[-1] / q[0]
            )
        )
    if failed:
        lines.append("failed: " + ", ".join(f"{k} {n}" for k, n in most_common(index.failures)))
    if index.causes:
        lines.append(
            "TVMMP 0 or infeasible, by cause: " + ", ".join(f"{k} {n}" for k, n in most_common(index.causes))
        )
    if index.uncertified:
        lines.append(
            f"warning: {index.uncertified} rows have an alpha that is not certified (column certified)"
        )
    if index.deep:
        rows_are = "row is" if index.deep == 1 else "rows are"
        lines.append(
            f"{index.deep} evaluated {rows_are} deeper than max_penetration (column penetration_exceeded)"
        )
    per_object = objects_summary(index_objects(index))
    if per_object:
        lines.append(per_object)
    return "\n".join(lines)


TVMMP_AXIS = "TVMMP alpha " + ALPHA_UNIT
"""The label of a TVMMP axis (the unit of [`ALPHA_UNIT`][mjtvm.jobs.figures.ALPHA_UNIT])."""


def _apart(index: RankIndex) -> str:
    """The count of the rows drawn apart: infeasible (evaluated, no TVMMP) and failed."""
    infeasible = int((index.evaluated & np.isnan(index.tvmmp)).sum())
    return f"not drawn: {infeasible} infeasible, {int((~index.evaluated).sum())} failed"


def rank_plots(rows: Sequence[dict[str, Any]]) -> dict[str, bytes]:
    """``objects``: TVMMP per object (one row per object, every feasible grasp a point; its
    infeasible and failed grasps counted in brackets after its name); ``tvmmp``: the histogram of TVMMP;
    ``epsilon``: TVMMP against the L1 epsilon. Infeasible and failed grasps are never drawn at
    0: counted in each figure's title or strip. The points in the order of ``rows``. PNG bytes."""
    index = RankIndex.from_rows(rows)
    return index_plots(index, np.arange(len(index)))


def index_plots(index: RankIndex, order: NDArray[np.int64]) -> dict[str, bytes]:
    """[`rank_plots()`][mjtvm.jobs.rank_files.rank_plots] from a [`RankIndex`][mjtvm.jobs.rank_index.RankIndex],
    the points in the order ``order`` (its positions). ``objects`` draws one row per object
    (its name and its infeasible and failed grasps on the left), so that long names stay legible."""
    from mjtvm.jobs.style import COUNT, FONT, figure, finish, png

    drawn = order[index.evaluated[order] & ~np.isnan(index.tvmmp[order])]
    objects = list(index.objects) or ["(none)"]
    names, points = [], []
    for i, name in enumerate(objects):
        values = index.tvmmp[drawn[index.obj[drawn] == i]]
        jitter = np.linspace(-0.2, 0.2, len(values)) if len(values) > 1 else np.zeros(len(values))
        points.append((values, i + jitter))
        mine = index.obj == i
        inf = int((mine & index.evaluated & np.isnan(index.tvmmp)).sum())
        bad = int((mine & ~index.evaluated).sum())
        names.append(f"{name}  [{inf} inf., {bad} failed]")
    labels = max(len(n) for n in names) * 0.55 * FONT["tick"] / 72.0  # inches
    fig, ax = figure(4.2 + labels, max(2.6, 0.32 * len(objects) + 1.9))
    for x, y in points:
        ax.plot(x, y, "o", ms=3, alpha=0.7, clip_on=False)  # TVMMP 0 on the frame
    ax.set_yticks(range(len(objects)), names, fontsize=FONT["tick"])
    ax.set_ylim(len(objects) - 0.5, -0.5)
    ax.set_xlim(left=0.0)
    title = f"TVMMP per object\n({len(drawn)} feasible grasps; {_apart(index)})"
    finish(
        fig, ax, xlabel=TVMMP_AXIS, ylabel="object [infeasible, failed grasps: not drawn] (-)", title=title
    )
    out = {"objects": png(fig)}
    fig, ax = figure(4.8, 3.4)
    ax.hist(index.tvmmp[drawn], bins=20)
    title = f"TVMMP histogram\n({len(drawn)} feasible grasps; {_apart(index)})"
    finish(fig, ax, xlabel=TVMMP_AXIS, ylabel=f"grasps {COUNT}", title=title)
    out["tvmmp"] = png(fig)
    fig, ax = figure(4.8, 3.4)
    pairs = drawn[~np.isnan(index.epsilon[drawn])]
    ax.plot(index.epsilon[pairs], index.tvmmp[pairs], "o", ms=3, alpha=0.7)
    title = f"TVMMP against the epsilon\n({len(pairs)} feasible grasps; {_apart(index)})"
    finish(
        fig, ax, xlabel="Ferrari-Canny epsilon L1 (N per N of normal force)", ylabel=TVMMP_AXIS, title=title
    )
    out["epsilon"] = png(fig)
    return out


def run_rank_files(
    run: RankFiles, *, emit: Callable[[str], None] = print, notice: Callable[[str], None] = stderr
) -> list[Path]:
    r"""``mjtvm rank``: check the datasets, lock ``run.out``, resume, rank, write the files; the
    summary ([`rank_summary()`][mjtvm.jobs.rank_files.rank_summary]) goes to ``notice``.

    The memory does not grow with the dataset (``docs/datasets.md``, "Memory"): the datasets
    are checked in a first pass ([`scan_datasets()`][mjtvm.jobs.rank_inputs.scan_datasets]) and read
    again one file at a time while the grasps are evaluated; every finished row is appended
    to ``NAME.partial.jsonl`` ([`RankLog`][mjtvm.jobs.rank_log.RankLog], the checkpoint) and
    dropped; the files are written from the log, in rank order, from a
    [`RankIndex`][mjtvm.jobs.rank_index.RankIndex] of a few numbers per row; the log is removed
    once they are written. Every row carries ``inputs``
    ([`inputs_digest()`][mjtvm.jobs.rank_inputs.inputs_digest]); with ``run.resume`` the rows of the
    log, of an older version's ``NAME.partial.json`` and of an earlier ``NAME.json`` whose id is
    in the datasets and whose ``inputs`` are unchanged are kept. The result equals an
    uninterrupted run (tested).

    Raises
    ------
    GraspError
        The grasp file, or a malformed dataset (one line naming the file, index and field).
    OutputError
        ``run.out`` cannot be written, or another run holds its lock.
    StateError
        An unreadable checkpoint or earlier ``NAME.json`` with ``resume``.
    ParamError
        An unreachable ``cluster``.
    """
    from mjtvm.formats.files import check_output_dir, output_lock

    scan = scan_datasets(run.grasp, run.datasets, pose=run.pose, key=run.dataset_key, com_frame=run.com_frame)
    digest = inputs_digest(
        run.grasp,
        run.datasets,
        scan.objects,
        run.limit_horizon,
        pose=run.pose,
        key=run.dataset_key,
        com_frame=run.com_frame,
        refuse_penetration=run.refuse_penetration,
        measures=run.measures,
        verify=run.verify,
        hold_time=run.hold_time,
    )
    outdir = check_output_dir(run.out)
    log = RankLog(outdir / f"{run.name}.partial.jsonl", every_s=CHECKPOINT_EVERY_S)
    with output_lock(outdir):
        done = np.zeros(len(scan), dtype=bool)
        if run.resume:
            changed = np.zeros(len(scan), dtype=bool)
            kept = _kept_rows(log, outdir, run.name, scan, digest, done, changed, run.verify)
            n = log.start(kept)
            if (changed & ~done).any():
                notice(f"resume: {int((changed & ~done).sum())} rows recomputed: inputs changed")
            if not run.quiet:
                emit(f"resume: {n} of {len(scan)} rows already finished")
        else:
            n = log.start()
        todo = (e for i, e in enumerate(iter_datasets(scan)) if not done[i])
        try:
            stream_rows(
                run.grasp,
                todo,
                lambda rows: log.append({**r, "inputs": digest} for r in rows),
                total=len(scan) - n,
                jobs=run.jobs,
                cluster=run.cluster,
                progress=not run.quiet,
                limit_horizon=run.limit_horizon,
                refuse_penetration=run.refuse_penetration,
                measures=run.measures,
                verify=run.verify,
                hold_time=run.hold_time,
            )
        except BaseException:
            log.close()  # every finished row is in it; an empty one would only be in the way
            if log.count == 0:
                log.remove()
            raise
        log.close()
        written, index, auc = _write_from_log(run, log, scan, outdir)
        log.remove()
        (outdir / f"{run.name}.partial.json").unlink(missing_ok=True)  # an older version's checkpoint
    notice("\n".join([index_summary(index), *([auc_summary(auc)] if run.verify else [])]))
    return written


def _kept_rows(
    log: RankLog,
    outdir: Path,
    name: str,
    scan: DatasetScan,
    digest: str,
    done: NDArray[np.bool_],
    changed: NDArray[np.bool_],
    verify: bool = False,
) -> Iterator[dict[str, Any]]:
    """The finished rows ``--resume`` keeps, read one at a time: from the log, an older
    version's checkpoint, the earlier ``NAME.json`` (the first whole copy of a row wins);
    ``done`` and ``changed`` mark the rows kept and those whose inputs changed. A row of a run
    with ``--verify`` when this one has none, or the reverse, is refused: the rows of one set
    have the same columns."""
    legacy = outdir / f"{name}.partial.json"
    sources: list[Iterable[dict[str, Any]]] = []
    if log.path.exists():
        sources.append(row for _, row in log.entries())
    if legacy.exists():
        sources.append(_legacy_checkpoint(legacy))
    if (outdir / f"{name}.json").exists():
        sources.append(json_list_rows(outdir / f"{name}.json"))
    for rows in sources:
        for row in rows:
            if ("sim_hold" in row) != verify:
                had = "with" if verify is False else "without"
                raise OptionError(
                    "--resume",
                    f"the finished rows in {outdir} are of a run {had} --verify: resume with the same "
                    "--verify, or write to another --out or --name",
                )
            i = scan.ids.lookup(str(row["id"]))
            if i is None or done[i]:
                continue
            if row.get("inputs") == digest:
                done[i] = True
                yield row
            else:
                changed[i] = True


def _legacy_checkpoint(path: Path) -> list[dict[str, Any]]:
    """The rows of ``NAME.partial.json`` (schema ``mjtvm.rank-checkpoint/1``, mjtvm <= 0.x)."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        if doc.get("schema") != LEGACY_SCHEMA:
            raise ValueError(f"schema {doc.get('schema')!r}, expected {LEGACY_SCHEMA!r}")
        rows = list(doc["rows"])
        [str(r["id"]) for r in rows]
    except (OSError, ValueError, TypeError, KeyError, AttributeError) as e:
        raise StateError(str(path), f"cannot read the finished rows ({e}); {AGAIN}") from e
    return rows


def _write_from_log(
    run: RankFiles, log: RankLog, scan: DatasetScan, outdir: Path
) -> tuple[list[Path], RankIndex, list[dict[str, Any]]]:
    """Every file of the run from its log, one row at a time, in rank order."""
    from mjtvm.formats.files import write_files

    builder = RankIndexBuilder(run.sort)
    offsets = array("q")
    for offset, row in log.entries():
        builder.add(row, scan.ids.lookup(str(row["id"])) or 0)
        offsets.append(offset)
    index = builder.build()
    with log.reader() as read:
        order = index.order(lambda j: str(read(offsets[j])["id"]))
        ranked = index.ranked

        def rows() -> Iterator[dict[str, Any]]:
            for n, j in enumerate(order, start=1):
                yield with_rank(read(offsets[int(j)]), n, ranked)

        columns = table_columns([index.columns])
        files: dict[Path, bytes | str | Iterable[str | bytes]] = {
            outdir / f"{run.name}.json": rows_json_chunks(rows()),
            outdir / f"{run.name}.csv": rows_csv_chunks(rows(), columns),
            outdir / f"{run.name}-objects.csv": csv_text(
                index_objects(index), list(OBJECT_COLUMNS), cell=lambda v: "" if v is None else v
            ),
        }
        if has_pyarrow():
            rank_kind: set[type] = {int} if ranked else set()  # the log's rows have no rank yet
            kinds = {**index.columns, "rank": rank_kind}
            files[outdir / f"{run.name}.parquet"] = rows_parquet_chunks(rows(), columns, kinds)
        if run.plots:
            for key, png in index_plots(index, order).items():
                files[outdir / f"{run.name}-{key}.png"] = png
        auc: list[dict[str, Any]] = []
        if run.verify:
            more, auc = auc_files((row for _, row in log.entries()), outdir, run.name, plots=run.plots)
            files.update(more)
        return write_files(files), index, auc
