r"""The files of ``mjtvm rank``: the rows as JSON, CSV (and Parquet), the plots, the summary,
the checkpoint and ``--resume``.

[`run_rank_files()`][mjtvm.jobs.rank_files.run_rank_files] reads the datasets ([`read_dataset()`][mjtvm.grasp.document.dataset.read_dataset]),
ranks them ([`rank_rows()`][mjtvm.jobs.rank.rank_rows]) into ``NAME.json``, ``NAME.csv``,
``NAME.parquet`` (when ``pyarrow`` imports), ``NAME-objects.png`` (TVMMP per object) and
``NAME-tvmmp.png`` (the TVMMP histogram), ``NAME-epsilon.png`` (TVMMP against the epsilon), keeping every finished row in
``NAME.partial.json`` while it runs, as ``mjtvm sweep`` does ([`mjtvm.jobs.sweep_files`][mjtvm.jobs.sweep_files]).
"""

from __future__ import annotations

import io
import json
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mjtvm.errors import ParamError
from mjtvm.jobs.checkpoint import RowCheckpoint
from mjtvm.jobs.figures import ALPHA_UNIT
from mjtvm.jobs.files import csv_text, stderr
from mjtvm.jobs.rank import MEASURES, rank_rows
from mjtvm.jobs.rank_inputs import inputs_digest, read_datasets
from mjtvm.jobs.rank_order import OBJECT_COLUMNS, check_sort, object_rows, objects_summary, ranked_rows
from mjtvm.jobs.rank_row import flat_row, table_columns

__all__ = ["CHECKPOINT_SCHEMA", "RankFiles", "rank_summary", "rows_table", "run_rank_files"]

CHECKPOINT_SCHEMA = "mjtvm.rank-checkpoint/1"
CHECKPOINT_EVERY_S = 5.0
"""At most this often (s) the checkpoint is rewritten (and always on an interrupt or failure)."""


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

    def __post_init__(self) -> None:
        if not self.datasets:
            raise ParamError("datasets", "expected at least one dataset file")
        if self.measures not in MEASURES:
            raise ParamError("measures", f"expected one of {', '.join(MEASURES)}, got {self.measures!r}")
        check_sort(self.sort)


def rows_table(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rows flattened for CSV and Parquet ([`flat_row()`][mjtvm.jobs.rank_row.flat_row]):
    ``limiting`` -> ``limiting_k``, ``limiting_l``; ``alpha`` and ``status`` ->
    ``alpha_k<k>_l<l>``, ``status_k<k>_l<l>``; ``None`` -> ``""`` in the caller's CSV."""
    return [flat_row(r) for r in rows]


def rows_csv(rows: Sequence[dict[str, Any]]) -> str:
    """The rows as CSV ([`rows_table()`][mjtvm.jobs.rank_files.rows_table]; empty cells where a value is ``None``)."""
    return "".join(rows_csv_chunks(rows))


def rows_csv_chunks(rows: Sequence[dict[str, Any]]) -> Iterator[str]:
    """[`rows_csv()`][mjtvm.jobs.rank_files.rows_csv] line by line: the header, then each row
    flattened as it is written (one flattened row held at a time, not the table)."""
    columns = _columns(rows)
    yield csv_text([], columns)
    for row in rows:
        yield csv_text([flat_row(row)], columns, cell=lambda v: "" if v is None else v).split("\r\n", 1)[1]


def _columns(rows: Sequence[dict[str, Any]]) -> list[str]:
    """[`table_columns()`][mjtvm.jobs.rank_row.table_columns] of the rows, flattening one at a time."""
    keys: dict[str, None] = {}
    for row in rows:
        keys.update(dict.fromkeys(flat_row(row)))
    return table_columns([keys])


def rows_json_chunks(rows: Sequence[dict[str, Any]]) -> Iterator[str]:
    """The text of ``json.dumps(rows, indent=1) + "\\n"``, one row at a time."""
    if not rows:
        yield "[]\n"
        return
    yield "["
    for i, row in enumerate(rows):
        text = json.dumps(row, indent=1).replace("\n", "\n ")
        yield ("\n " if i == 0 else ",\n ") + text
    yield "\n]\n"


def rows_parquet(rows: Sequence[dict[str, Any]]) -> bytes | None:
    """The rows as Parquet ([`rows_table()`][mjtvm.jobs.rank_files.rows_table]), or ``None`` when ``pyarrow`` is not installed."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return None
    flat = rows_table(rows)
    columns = table_columns(flat)
    table = pa.Table.from_pylist([{c: r.get(c) for c in columns} for r in flat])
    buf = io.BytesIO()
    pq.write_table(table, buf)
    return buf.getvalue()


def rank_summary(rows: Sequence[dict[str, Any]]) -> str:
    """The summary ``mjtvm rank`` prints on stderr: counts, TVMMP quantiles, failures by reason."""
    failed = [r for r in rows if r["failure"] is not None]
    solved = [r for r in rows if r["failure"] is None]
    positive = np.array([r["tvmmp"] for r in solved if r["tvmmp"] is not None and r["tvmmp"] > 0.0])
    zero = sum(r["tvmmp"] is not None and r["tvmmp"] <= 0.0 for r in solved)
    infeasible = sum(r["tvmmp"] is None for r in solved)
    lines = [
        f"rank: {len(rows)} grasps: {len(positive)} with TVMMP > 0, {zero} with TVMMP 0, "
        f"{infeasible} infeasible, {len(failed)} failed"
    ]
    if len(positive):
        q = np.quantile(positive, [0.0, 0.25, 0.5, 0.75, 1.0])
        lines.append(
            "TVMMP (> 0): min {:.4g}, q25 {:.4g}, median {:.4g}, q75 {:.4g}, max {:.4g}; max/min {:.3g}".format(
                *q, q[-1] / q[0]
            )
        )
    if failed:
        counts = Counter(r["failure"] for r in failed)
        lines.append("failed: " + ", ".join(f"{k} {n}" for k, n in counts.most_common()))
    causes = Counter(
        r["reason"].split(": ")[1] for r in solved if r["reason"] and (r["tvmmp"] is None or r["tvmmp"] <= 0)
    )
    if causes:
        lines.append(
            "TVMMP 0 or infeasible, by cause: " + ", ".join(f"{k} {n}" for k, n in causes.most_common())
        )
    doubtful = sum(r["certified"] is False for r in rows)
    if doubtful:
        lines.append(f"warning: {doubtful} rows have an alpha that is not certified (column certified)")
    deep = sum(r.get("penetration_exceeded") is True for r in solved)
    if deep:
        rows_are = "row is" if deep == 1 else "rows are"
        lines.append(f"{deep} evaluated {rows_are} deeper than max_penetration (column penetration_exceeded)")
    per_object = objects_summary(rows)
    if per_object:
        lines.append(per_object)
    return "\n".join(lines)


TVMMP_AXIS = "TVMMP alpha " + ALPHA_UNIT
"""The label of a TVMMP axis (the unit of [`ALPHA_UNIT`][mjtvm.jobs.figures.ALPHA_UNIT])."""


def _apart(rows: Sequence[dict[str, Any]]) -> str:
    """The count of the rows drawn apart: infeasible (evaluated, no TVMMP) and failed."""
    infeasible = sum(r["failure"] is None and r["tvmmp"] is None for r in rows)
    failed = sum(r["failure"] is not None for r in rows)
    return f"not drawn: {infeasible} infeasible, {failed} failed"


def rank_plots(rows: Sequence[dict[str, Any]]) -> dict[str, bytes]:
    """``objects``: TVMMP per object (every feasible grasp a point; per object, its infeasible
    and failed grasps counted in a strip below the axis); ``tvmmp``: the histogram of TVMMP;
    ``epsilon``: TVMMP against the L1 epsilon. Infeasible and failed grasps are never drawn at
    0: counted in each figure's title or strip. PNG bytes."""
    from mjtvm.jobs.figures import lift_axes

    solved = [r for r in rows if r["failure"] is None]
    feasible = [r for r in solved if r["tvmmp"] is not None]
    objects = sorted({r["object"] for r in rows}) or ["(none)"]
    fig, ax = lift_axes(max(4.5, 0.8 * len(objects) + 2.0), 4.0)
    for i, name in enumerate(objects):
        values = [r["tvmmp"] for r in feasible if r["object"] == name]
        jitter = np.linspace(-0.2, 0.2, len(values)) if len(values) > 1 else np.zeros(len(values))
        ax.plot(i + jitter, values, "o", ms=3, alpha=0.7)
        mine = [r for r in rows if r["object"] == name]
        inf = sum(r["failure"] is None and r["tvmmp"] is None for r in mine)
        bad = sum(r["failure"] is not None for r in mine)
        ax.annotate(
            f"inf {inf}\nfail {bad}",
            (i, 0.0),
            xycoords=("data", "axes fraction"),
            xytext=(0, -28),
            textcoords="offset points",
            ha="center",
            va="top",
            fontsize=6,
            color="tab:red",
        )
    ax.set_xticks(range(len(objects)), objects, rotation=30, fontsize=7)
    ax.set_xlabel("object (below it: its infeasible and failed grasps, not drawn)", fontsize=7, labelpad=34)
    ax.set_ylabel(TVMMP_AXIS, fontsize=7)
    ax.set_title(f"TVMMP per object\n({len(feasible)} feasible grasps; {_apart(rows)})", fontsize=8)
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    out = {"objects": _png(fig)}
    fig, ax = lift_axes(4.5, 3.2)
    ax.hist([r["tvmmp"] for r in feasible], bins=20)
    ax.set_xlabel(TVMMP_AXIS, fontsize=7)
    ax.set_ylabel("grasps (count)", fontsize=8)
    ax.set_title(f"TVMMP histogram\n({len(feasible)} feasible grasps; {_apart(rows)})", fontsize=8)
    out["tvmmp"] = _png(fig)
    fig, ax = lift_axes(4.5, 3.2)
    pairs = [(r["epsilon_l1"], r["tvmmp"]) for r in feasible if r.get("epsilon_l1") is not None]
    ax.plot([e for e, _ in pairs], [v for _, v in pairs], "o", ms=3, alpha=0.7)
    ax.set_xlabel("Ferrari-Canny epsilon L1 (N per N of normal force)", fontsize=8)
    ax.set_ylabel(TVMMP_AXIS, fontsize=7)
    ax.set_title(f"TVMMP against the epsilon\n({len(pairs)} feasible grasps; {_apart(rows)})", fontsize=8)
    ax.grid(alpha=0.3)
    out["epsilon"] = _png(fig)
    return out


def _png(fig: Any) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()


def run_rank_files(
    run: RankFiles, *, emit: Callable[[str], None] = print, notice: Callable[[str], None] = stderr
) -> list[Path]:
    r"""``mjtvm rank``: read the datasets, lock ``run.out``, resume, rank, write the files; the
    summary ([`rank_summary()`][mjtvm.jobs.rank_files.rank_summary]) goes to ``notice``.

    While it runs, ``NAME.partial.json`` (schema ``mjtvm.rank-checkpoint/1``) holds every
    finished row, rewritten atomically at most every [`CHECKPOINT_EVERY_S`][mjtvm.jobs.rank_files.CHECKPOINT_EVERY_S] s and on an
    interrupt or failure, removed once the outputs are written. Every row carries ``inputs``
    ([`inputs_digest()`][mjtvm.jobs.rank_inputs.inputs_digest]); with ``run.resume`` the rows of the checkpoint and of an earlier
    ``NAME.json`` whose id is in the datasets and whose ``inputs`` are unchanged are kept. The
    result equals an uninterrupted run (tested).

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
    from mjtvm.formats.files import check_output_dir, output_lock, write_files

    entries = read_datasets(
        run.grasp, run.datasets, pose=run.pose, key=run.dataset_key, com_frame=run.com_frame
    )
    digest = inputs_digest(
        run.grasp,
        run.datasets,
        entries,
        run.limit_horizon,
        pose=run.pose,
        key=run.dataset_key,
        com_frame=run.com_frame,
        refuse_penetration=run.refuse_penetration,
        measures=run.measures,
    )
    outdir = check_output_dir(run.out)
    out_json, out_csv = outdir / f"{run.name}.json", outdir / f"{run.name}.csv"
    checkpoint = outdir / f"{run.name}.partial.json"
    ck: RowCheckpoint[str] = RowCheckpoint(
        checkpoint,
        CHECKPOINT_SCHEMA,
        key=lambda r: str(r["id"]),
        digest=lambda _: digest,
        every_s=CHECKPOINT_EVERY_S,
        again="run again without --resume",
    )
    with output_lock(outdir):
        wanted = {e.id for e in entries}
        rows = ck.run(
            lambda done, on_rows: rank_rows(
                run.grasp,
                entries,
                jobs=run.jobs,
                cluster=run.cluster,
                progress=not run.quiet,
                done=done,
                on_rows=on_rows,
                limit_horizon=run.limit_horizon,
                refuse_penetration=run.refuse_penetration,
                measures=run.measures,
            ),
            resume=run.resume,
            earlier=out_json,
            wanted=wanted,
            quiet=run.quiet,
            emit=emit,
            notice=notice,
        )
        rows = ranked_rows(rows, run.sort)
        objects = object_rows(rows)
        files: dict[Path, bytes | str | Iterator[str]] = {
            out_json: rows_json_chunks(rows),  # written row by row
            out_csv: rows_csv_chunks(rows),
            outdir / f"{run.name}-objects.csv": csv_text(
                objects, list(OBJECT_COLUMNS), cell=lambda v: "" if v is None else v
            ),
        }
        parquet = rows_parquet(rows)
        if parquet is not None:
            files[outdir / f"{run.name}.parquet"] = parquet
        if run.plots:
            for key, png in rank_plots(rows).items():
                files[outdir / f"{run.name}-{key}.png"] = png
        written = write_files(files)
        checkpoint.unlink(missing_ok=True)
    notice(rank_summary(rows))
    return written
