r"""The applications of Problem 2 along a lift: [`mjtvm.jobs.replay`][mjtvm.jobs.replay] (the replay and the
Fig. 8/9 sweeps; its records and files in [`mjtvm.jobs.replay_records`][mjtvm.jobs.replay_records]),
[`mjtvm.jobs.sweep`][mjtvm.jobs.sweep] (parameter sweeps on a grid, a process pool or a Dask cluster; the
files of ``mjtvm sweep`` in [`mjtvm.jobs.sweep_files`][mjtvm.jobs.sweep_files]), [`mjtvm.jobs.rank`][mjtvm.jobs.rank] (a grasp dataset ranked by TVMMP; the
files of ``mjtvm rank`` in [`mjtvm.jobs.rank_files`][mjtvm.jobs.rank_files]) and [`mjtvm.jobs.figures`][mjtvm.jobs.figures].

The names below are imported on first use: the replay loads matplotlib, which a sweep's
workers do not need.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mjtvm._lazy import lazy_attributes

if TYPE_CHECKING:
    from mjtvm.jobs.rank import rank_row, rank_rows
    from mjtvm.jobs.rank_files import RankFiles, run_rank_files
    from mjtvm.jobs.replay import (
        SCHEMA,
        SWEEP_MG_MU,
        SWEEP_MGS,
        SWEEP_MU_MG,
        SWEEP_MUS,
        ReplayOutput,
        grasp_defaults,
        replay_lift,
        run_replay,
        sweep_lift,
        time_replay,
    )
    from mjtvm.jobs.replay_records import Record, solve_state
    from mjtvm.jobs.sweep import SweepPoint, grid, run_sweep
    from mjtvm.jobs.sweep_files import SweepFiles, run_sweep_files

_HOMES = {
    "SCHEMA": "replay",
    "SWEEP_MGS": "replay",
    "SWEEP_MG_MU": "replay",
    "SWEEP_MUS": "replay",
    "SWEEP_MU_MG": "replay",
    "ReplayOutput": "replay",
    "grasp_defaults": "replay",
    "replay_lift": "replay",
    "run_replay": "replay",
    "sweep_lift": "replay",
    "time_replay": "replay",
    "Record": "replay_records",
    "solve_state": "replay_records",
    "rank_row": "rank",
    "rank_rows": "rank",
    "RankFiles": "rank_files",
    "run_rank_files": "rank_files",
    "SweepPoint": "sweep",
    "grid": "sweep",
    "run_sweep": "sweep",
    "SweepFiles": "sweep_files",
    "run_sweep_files": "sweep_files",
}

__all__ = [
    "SCHEMA",
    "SWEEP_MGS",
    "SWEEP_MG_MU",
    "SWEEP_MUS",
    "SWEEP_MU_MG",
    "RankFiles",
    "Record",
    "ReplayOutput",
    "SweepFiles",
    "SweepPoint",
    "grasp_defaults",
    "grid",
    "rank_row",
    "rank_rows",
    "replay_lift",
    "run_rank_files",
    "run_replay",
    "run_sweep",
    "run_sweep_files",
    "solve_state",
    "sweep_lift",
    "time_replay",
]


__getattr__ = lazy_attributes(__name__, _HOMES)
