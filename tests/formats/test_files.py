"""Output folders: the lock (a forked child does not keep it; a dead run's lock is taken over)
and the temporary files of killed runs."""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys

import pytest

from mjtvm.errors import OutputError
from mjtvm.formats.files import LOCK_NAME, output_lock, remove_stale_temporaries, write_files


def _dead_pid() -> int:
    """The id of a process that has ended (and been reaped)."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _identity() -> str:
    from mjtvm.formats.files import _identity

    return _identity()


def test_the_lock_file_names_its_owner_and_refuses_a_second_run(tmp_path):
    with output_lock(tmp_path):
        pid, _, where = (tmp_path / LOCK_NAME).read_text().strip().partition(" ")
        assert int(pid) == os.getpid() and where
        with pytest.raises(OutputError, match="another mjtvm run is writing to this folder"):
            with output_lock(tmp_path):
                pass
    with output_lock(tmp_path):  # released at the end of the block
        pass


@pytest.mark.skipif(not hasattr(os, "fork"), reason="fork")
def test_a_forked_child_does_not_keep_the_folder_locked(tmp_path):
    """A child forked while the lock is held (a pool worker) and still running after its
    parent's block ended: the folder is free (the child closed its copy of the descriptor)."""
    read, write = os.pipe()
    with output_lock(tmp_path):
        pid = os.fork()
        if pid == 0:  # the child: wait until the parent has left its block
            os.close(write)
            os.read(read, 1)
            os._exit(0)
    os.close(read)
    try:
        with output_lock(tmp_path):  # the child still runs
            pass
    finally:
        os.write(write, b"x")
        os.close(write)
        os.waitpid(pid, 0)


def test_a_lock_held_by_the_leftovers_of_a_dead_run_is_taken_over(tmp_path):
    """The lock file names a process that has ended, yet its lock is held (by a child the dead
    run left, simulated here by a second open file): the next run takes over, says so in one
    line, and then holds the folder against a third run."""
    lock = tmp_path / LOCK_NAME
    dead = _dead_pid()
    lock.write_text(f"{dead} {_identity()}\n")
    leftover = os.open(lock, os.O_RDWR)
    fcntl.flock(leftover, fcntl.LOCK_EX | fcntl.LOCK_NB)
    notices: list[str] = []
    try:
        with output_lock(tmp_path, notice=notices.append):
            assert len(notices) == 1 and "--out: took over the lock of an ended run" in notices[0]
            assert f"process {dead}" in notices[0]
            assert int(lock.read_text().split()[0]) == os.getpid()
            with pytest.raises(OutputError, match="another mjtvm run is writing to this folder"):
                with output_lock(tmp_path, notice=notices.append):
                    pass
        assert sorted(p.name for p in tmp_path.iterdir()) == [LOCK_NAME]  # no temporary left
    finally:
        os.close(leftover)


@pytest.mark.parametrize("content", ["", "garbage\n", "1 another-host 4026531836\n"])
def test_a_held_lock_whose_owner_cannot_be_checked_is_refused(tmp_path, content):
    """No process id, or one of another host or pid namespace (a shared folder): refuse."""
    lock = tmp_path / LOCK_NAME
    lock.write_text(content)
    holder = os.open(lock, os.O_RDWR)
    fcntl.flock(holder, fcntl.LOCK_EX | fcntl.LOCK_NB)
    try:
        with pytest.raises(OutputError, match="another mjtvm run is writing to this folder"):
            with output_lock(tmp_path, notice=pytest.fail):
                pass
    finally:
        os.close(holder)


def test_the_temporaries_of_ended_processes_are_removed_and_live_ones_kept(tmp_path):
    dead, live = _dead_pid(), os.getpid()
    stale = [
        tmp_path / f".sweep.json.{dead}.k2j_3h.tmp",
        tmp_path / f".mjtvm-probe.{dead}.x1y2.tmp",
        tmp_path / f".mjtvm.lock.{dead}.abc.tmp",
    ]
    kept = [
        tmp_path / f".sweep.json.{live}.k2j_3h.tmp",
        tmp_path / ".sweep.json.k2j3h.tmp",
        tmp_path / "sweep.partial.json",
        tmp_path / "notes.tmp",
    ]
    for path in stale + kept:
        path.write_text("x")
    with output_lock(tmp_path):
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted([LOCK_NAME, *(p.name for p in kept)])
    assert sorted(remove_stale_temporaries(tmp_path)) == []


def test_temporaries_are_named_after_their_process(tmp_path, monkeypatch):
    """A write interrupted between its temporary files and the renames leaves nothing; the
    temporaries carry this process's id (so a later run can tell whether they are stale)."""
    seen: list[str] = []

    def replace(src, dst):
        seen.append(os.path.basename(src))
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(KeyboardInterrupt):
        write_files({tmp_path / "a.json": "1"})
    assert seen[0].startswith(f".a.json.{os.getpid()}.") and seen[0].endswith(".tmp")
    assert list(tmp_path.iterdir()) == []
