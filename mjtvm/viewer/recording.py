r"""The rerun recording of a replay, made beside the rest of the main job.

[`start_recording()`][mjtvm.viewer.recording.start_recording] starts [`record_replay()`][mjtvm.viewer.viz.record_replay] as soon as the replay's
records exist, in a forked child process, so that the recording (rerun's import, the
TVMSs, the logging) runs on the second core while the parent computes the sweeps and the
plots; [`RecordingJob.result()`][mjtvm.viewer.recording.RecordingJob.result] waits for it. On the default 30-state lift this brings
what the recording adds to ``mjtvm replay`` from 27-31 % down to a few per cent
(docs/rerun.md).

A forked child inherits the parent's threads' locks but not the threads. The parent has
none that matter (OpenBLAS re-creates its pool after a fork, tqdm's monitor only sleeps)
as long as rerun itself has not been loaded: its runtime's threads would be missing in the
child. So the fork is used only where it exists and rerun is not imported yet; otherwise
the recording runs in this process when [`RecordingJob.result()`][mjtvm.viewer.recording.RecordingJob.result] is called, after the
rest of the job, as it would without this module. rerun is imported only by the child (or
then), never here.
"""

from __future__ import annotations

import multiprocessing
import sys
import traceback
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mjtvm.errors import MjtvmError

if TYPE_CHECKING:
    from mjtvm.jobs.replay import ReplayOutput

__all__ = ["RecordingError", "RecordingJob", "start_recording"]


class RecordingError(MjtvmError, RuntimeError):
    r"""The recording failed (in the child process or here).

    Parameters
    ----------
    kind
        The class name of the original exception, e.g. ``"SolverError"``.
    message
        Its message.
    """

    def __init__(self, kind: str, message: str) -> None:
        self.kind = kind
        self.message = message
        super().__init__(f"recording failed: {kind}: {message}")


def _record(
    output: ReplayOutput, path: str | Path | None, spawn: bool, tvms_every: int | None
) -> dict[str, Any]:
    from mjtvm.viewer.viz import TVMS_EVERY, record_replay  # rerun is imported here, in the child

    every = TVMS_EVERY if tvms_every is None else tvms_every
    return record_replay(output, path, spawn=spawn, tvms_every=every)


def _child(
    conn: Any, output: ReplayOutput, path: str | Path | None, spawn: bool, tvms_every: int | None
) -> None:
    try:
        conn.send(("ok", _record(output, path, spawn, tvms_every)))
    except BaseException as e:  # reported to the parent, which raises RecordingError
        conn.send(("error", type(e).__name__, str(e) or traceback.format_exc(limit=3)))
    finally:
        conn.close()


class RecordingJob:
    """A recording under way ([`start_recording()`][mjtvm.viewer.recording.start_recording])."""

    def __init__(
        self,
        output: ReplayOutput,
        path: str | Path | None,
        spawn: bool,
        tvms_every: int | None,
        *,
        fork: bool,
    ) -> None:
        self._args = (output, path, spawn, tvms_every)
        self._process: Any = None
        self._conn: Any = None
        self.forked = fork  #: whether the recording runs in a forked child
        if fork:
            ctx = multiprocessing.get_context("fork")
            self._conn, send = ctx.Pipe(duplex=False)
            self._process = ctx.Process(target=_child, args=(send, *self._args), daemon=True)
            with warnings.catch_warnings():
                # Python >= 3.12 warns about fork() beside other threads; ours are fork-safe
                # (module docstring), and rerun's, which are not, rule the fork out.
                warnings.filterwarnings("ignore", "This process .* is multi-threaded", DeprecationWarning)
                self._process.start()
            send.close()

    def result(self) -> dict[str, Any]:
        """Wait for the recording; its [`record_replay()`][mjtvm.viewer.viz.record_replay] summary.

        Raises
        ------
        RecordingError
            The recording raised (its class name and message) or its process died.
        """
        if self._process is None:
            try:
                return _record(*self._args)
            except MjtvmError:
                raise
            except Exception as e:
                raise RecordingError(type(e).__name__, str(e)) from e
        try:
            reply = self._conn.recv()
        except EOFError as e:
            self._process.join()
            raise RecordingError("process", f"died with exit code {self._process.exitcode}") from e
        finally:
            self._conn.close()
        self._process.join()
        if reply[0] != "ok":
            raise RecordingError(reply[1], reply[2])
        info: dict[str, Any] = reply[1]
        return info

    def cancel(self) -> None:
        """Stop a forked recording that is no longer wanted (the main job failed)."""
        if self._process is not None and self._process.is_alive():
            self._process.kill()
            self._process.join()


def start_recording(
    output: ReplayOutput,
    path: str | Path | None,
    *,
    spawn: bool = False,
    tvms_every: int | None = None,
    fork: bool | None = None,
) -> RecordingJob:
    r"""Start recording ``output`` (the lift and the replay's records are all it reads) to
    the ``.rrd`` file ``path`` and/or a spawned viewer ([`record_replay()`][mjtvm.viewer.viz.record_replay]).

    Parameters
    ----------
    output
        [`run_replay()`][mjtvm.jobs.replay.run_replay]'s result, or the partial one its ``on_replay``
        hook receives.
    path, spawn, tvms_every
        As [`record_replay()`][mjtvm.viewer.viz.record_replay] (``tvms_every=None``: its default).
    fork
        Record in a forked child (the default where the platform forks and rerun is not
        imported yet, see the module docstring) or in this process at
        [`RecordingJob.result()`][mjtvm.viewer.recording.RecordingJob.result].
    """
    can_fork = "fork" in multiprocessing.get_all_start_methods() and "rerun" not in sys.modules
    return RecordingJob(output, path, spawn, tvms_every, fork=can_fork if fork is None else fork and can_fork)
