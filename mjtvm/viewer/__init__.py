r"""The rerun viewer, the only room that imports rerun.

[`mjtvm.viewer.viz`][mjtvm.viewer.viz] records the lift replay and the physics check (what each
state draws: [`mjtvm.viewer.drawing`][mjtvm.viewer.drawing]);
[`mjtvm.viewer.recording`][mjtvm.viewer.recording] runs the replay's recording beside the
replay; [`mjtvm.viewer.grasp_view`][mjtvm.viewer.grasp_view] records one grasp
(``mjtvm show --rrd``). This room imports only the rooms below it (``jobs`` and lower), never
MuJoCo itself.

The names below are imported on first use: importing this package does not load rerun.
Every other name (the drawing's scales and colours, the blueprint) lives in its module.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mjtvm._lazy import lazy_attributes

if TYPE_CHECKING:
    from mjtvm.viewer.grasp_view import record_grasp
    from mjtvm.viewer.recording import RecordingError, RecordingJob, start_recording
    from mjtvm.viewer.viz import record_replay, record_verify

__all__ = [
    "RecordingError",
    "RecordingJob",
    "record_grasp",
    "record_replay",
    "record_verify",
    "start_recording",
]

__getattr__ = lazy_attributes(
    __name__,
    {
        "record_grasp": "grasp_view",
        "RecordingError": "recording",
        "RecordingJob": "recording",
        "start_recording": "recording",
        "record_replay": "viz",
        "record_verify": "viz",
    },
)
