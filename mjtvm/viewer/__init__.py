r"""The rerun viewer: [`mjtvm.viewer.viz`][mjtvm.viewer.viz] records the lift replay and the physics check
(what each state draws: [`mjtvm.viewer.drawing`][mjtvm.viewer.drawing]); [`mjtvm.viewer.recording`][mjtvm.viewer.recording] runs the
replay's recording beside the replay.

The names below are imported on first use: importing this package does not load rerun.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mjtvm._lazy import lazy_attributes

if TYPE_CHECKING:
    from mjtvm.viewer.drawing import (
        FORCE_SCALE,
        SLIDE_LENGTH,
        TYPE_COLORS,
        VELOCITY_SCALE,
        hull_mesh,
        translational_tvms,
    )
    from mjtvm.viewer.recording import RecordingError, RecordingJob, start_recording
    from mjtvm.viewer.viz import APPLICATION_ID, TVMS_EVERY, Z_UNIT, blueprint, record_replay, record_verify

_HOMES = {
    "FORCE_SCALE": "drawing",
    "SLIDE_LENGTH": "drawing",
    "TYPE_COLORS": "drawing",
    "VELOCITY_SCALE": "drawing",
    "hull_mesh": "drawing",
    "translational_tvms": "drawing",
    "RecordingError": "recording",
    "RecordingJob": "recording",
    "start_recording": "recording",
    "APPLICATION_ID": "viz",
    "TVMS_EVERY": "viz",
    "Z_UNIT": "viz",
    "blueprint": "viz",
    "record_replay": "viz",
    "record_verify": "viz",
}

__all__ = [
    "APPLICATION_ID",
    "FORCE_SCALE",
    "SLIDE_LENGTH",
    "TVMS_EVERY",
    "TYPE_COLORS",
    "VELOCITY_SCALE",
    "Z_UNIT",
    "RecordingError",
    "RecordingJob",
    "blueprint",
    "hull_mesh",
    "record_replay",
    "record_verify",
    "start_recording",
    "translational_tvms",
]


__getattr__ = lazy_attributes(__name__, _HOMES)
