"""The recording beside the main job (mjtvm.viewer.recording): forked where it can be, else here."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from mjtvm.jobs.replay import run_replay
from mjtvm.viewer.recording import RecordingError, start_recording

# Run in a fresh interpreter: this pytest process has rerun loaded (test_viz), where the
# recording does not fork (its runtime's threads would be missing in the child).
CHILD = textwrap.dedent(
    """
    import json, sys
    from mjtvm.viewer.recording import RecordingError, start_recording
    from mjtvm.jobs.replay import run_replay

    out = run_replay(num_states=4, out=sys.argv[1], plots=False, sweeps=False)
    assert "rerun" not in sys.modules
    job = start_recording(out, sys.argv[2], tvms_every=1)
    report = {"forked": job.forked, "rerun_here": "rerun" in sys.modules}
    try:
        info = job.result()
        report.update(ok=True, tvms_states=info["tvms_states"], spawned=info["spawned"])
    except RecordingError as e:
        report.update(ok=False, kind=e.kind, message=e.message)
    print(json.dumps(report))
    """
)


def _fresh(tmp_path: Path, rrd: Path) -> dict[str, object]:
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(tmp_path / "out"), str(rrd)],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    report: dict[str, object] = json.loads(proc.stdout.strip().splitlines()[-1])
    return report


def test_a_fresh_process_records_in_a_forked_child(tmp_path: Path) -> None:
    if sys.platform == "win32":
        pytest.skip("no fork on Windows: the recording runs in-process there (tested below)")
    rrd = tmp_path / "lift.rrd"
    report = _fresh(tmp_path, rrd)
    assert report == {
        "forked": True,
        "rerun_here": False,
        "ok": True,
        "tvms_states": [0, 1, 2, 3],
        "spawned": False,
    }
    assert rrd.stat().st_size > 10_000


def test_a_failure_in_the_child_reaches_the_parent(tmp_path: Path) -> None:
    if sys.platform == "win32":
        pytest.skip("no fork on Windows")
    report = _fresh(tmp_path, tmp_path / "missing" / "dir" / "lift.rrd")
    assert report["forked"] is True and report["ok"] is False
    assert report["kind"] == "RuntimeError" and "missing/dir/lift.rrd" in str(report["message"])


def test_in_process_when_rerun_is_loaded(tmp_path: Path) -> None:
    import rerun  # noqa: F401  (as in a process that recorded before)

    out = run_replay(num_states=3, out=tmp_path, plots=False, sweeps=False)
    job = start_recording(out, tmp_path / "lift.rrd", tvms_every=0)
    assert job.forked is False
    info = job.result()
    assert info["tvms_states"] == [] and (tmp_path / "lift.rrd").stat().st_size > 10_000
    bad = start_recording(out, tmp_path / "missing" / "lift.rrd", tvms_every=0)
    with pytest.raises(RecordingError, match=r"recording failed: RuntimeError: .*missing/lift\.rrd"):
        bad.result()
