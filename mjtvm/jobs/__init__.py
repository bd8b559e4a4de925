r"""The jobs: applications of Problem 2 along a lift or over a dataset, run serially, on a local
pool or on Dask, and the files they write.

* [`mjtvm.jobs.replay`][mjtvm.jobs.replay]: the replay of the lift and the Fig. 8/9 sweeps
  (records and their files in [`mjtvm.jobs.replay_records`][mjtvm.jobs.replay_records]);
* [`mjtvm.jobs.sweep`][mjtvm.jobs.sweep]: parameter sweeps on a grid (the files of ``mjtvm sweep``
  in [`mjtvm.jobs.sweep_files`][mjtvm.jobs.sweep_files]);
* [`mjtvm.jobs.rank`][mjtvm.jobs.rank]: a grasp dataset ranked by TVMMP, one
  [`RankRow`][mjtvm.jobs.rank_row.RankRow] per grasp (the files of ``mjtvm rank`` in
  [`mjtvm.jobs.rank_files`][mjtvm.jobs.rank_files]);
* [`mjtvm.jobs.verify`][mjtvm.jobs.verify]: the physics check, alpha_sim against alpha_kl
  ([`mjtvm.jobs.verify_lp`][mjtvm.jobs.verify_lp], [`mjtvm.jobs.verify_report`][mjtvm.jobs.verify_report],
  [`mjtvm.jobs.slide_check`][mjtvm.jobs.slide_check], [`mjtvm.jobs.gears`][mjtvm.jobs.gears]);
* shared by them: [`mjtvm.jobs.pool`][mjtvm.jobs.pool] (local process pools),
  [`mjtvm.jobs.files`][mjtvm.jobs.files] (CSV text, model files, notices),
  [`mjtvm.jobs.checkpoint`][mjtvm.jobs.checkpoint] (checkpoints and ``--resume``) and
  [`mjtvm.jobs.figures`][mjtvm.jobs.figures].

The room may import every room below it (the physics, the lift, the coupling, the core); it
never imports MuJoCo itself (the MuJoCo-using pieces are in ``mjtvm.physics``), the viewer or
the CLI. The names below are imported on first use: the replay loads matplotlib and the
physics check MuJoCo's rollouts, which a sweep's workers do not need.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mjtvm._lazy import lazy_attributes

if TYPE_CHECKING:
    from mjtvm.jobs.gears import gear_sweep
    from mjtvm.jobs.rank import rank_rows
    from mjtvm.jobs.rank_files import RankFiles, run_rank_files
    from mjtvm.jobs.rank_row import RankRow
    from mjtvm.jobs.replay import replay_lift, run_replay, sweep_lift
    from mjtvm.jobs.sweep import SweepPoint, grid, run_sweep
    from mjtvm.jobs.verify import verify_lift, verify_state

_HOMES = {
    "RankFiles": "rank_files",
    "RankRow": "rank_row",
    "SweepPoint": "sweep",
    "gear_sweep": "gears",
    "grid": "sweep",
    "rank_rows": "rank",
    "replay_lift": "replay",
    "run_rank_files": "rank_files",
    "run_replay": "replay",
    "run_sweep": "sweep",
    "sweep_lift": "replay",
    "verify_lift": "verify",
    "verify_state": "verify",
}

__all__ = [
    "RankFiles",
    "RankRow",
    "SweepPoint",
    "gear_sweep",
    "grid",
    "rank_rows",
    "replay_lift",
    "run_rank_files",
    "run_replay",
    "run_sweep",
    "sweep_lift",
    "verify_lift",
    "verify_state",
]


__getattr__ = lazy_attributes(__name__, _HOMES)
