r"""Output files: checked before work, written atomically as one set, one run per folder.

Every command that writes files (``replay``, ``sweep``, ``verify``, ``bench``) does so through
this module:

* :func:`check_output_dir` creates the output folder and proves it writable (by creating and
  removing a probe file) *before* any computation, so a bad ``--out`` costs nothing;
* :func:`output_lock` takes an exclusive, non-blocking :func:`fcntl.flock` on
  ``<folder>/.mjtvm.lock`` for the whole run; a second run into the same folder fails at
  once with :class:`~mjtvm.errors.OutputError` instead of interleaving its rows. The lock
  file stays in the folder (removing it would let two runs lock two different files); the
  lock itself is released by the kernel when the process ends, however it ends;
* :func:`write_files` writes a run's files as one set: every file's content goes first to a
  temporary file in the same folder (``.<name>.<random>.tmp``, flushed and fsynced), and
  only when *all* of them are complete are they renamed over their targets with
  :func:`os.replace`, one after another. Each target is therefore always either its old
  complete content or its new complete content, never a truncated file; and a new file
  sits beside an old one of the same set only for the time the renames take (microseconds,
  no computation or I/O of content in between). A failure while writing the temporary files
  (disk full, ...) removes them and leaves every target untouched; an interrupt does the same.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path

from ..errors import OutputError

__all__ = ["LOCK_NAME", "atomic_write", "check_output_dir", "output_lock", "write_files"]

LOCK_NAME = ".mjtvm.lock"


def _problem(e: OSError) -> str:
    return e.strerror or str(e) if e.errno is not None else str(e)


def check_output_dir(path: str | Path, *, option: str = "--out") -> Path:
    """Create the folder ``path`` (and its parents) and check that files can be created in it.

    Raises
    ------
    OutputError
        ``path`` is a file, cannot be created, or is not writable (read-only, full, ...).
    """
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise OutputError(option, str(folder), "expected a folder, found a file")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise OutputError(option, str(folder), f"cannot create the folder ({_problem(e)})") from e
    try:  # os.access is blind to read-only mounts and full disks: really create a file
        fd, probe = tempfile.mkstemp(prefix=".mjtvm-probe.", dir=folder)
        try:
            os.write(fd, b"x")
            os.fsync(fd)
        finally:
            os.close(fd)
            os.unlink(probe)
    except OSError as e:
        raise OutputError(option, str(folder), f"cannot write in the folder ({_problem(e)})") from e
    return folder


@contextlib.contextmanager
def output_lock(folder: str | Path, *, option: str = "--out") -> Iterator[Path]:
    """Hold an exclusive lock on ``folder`` for the duration of the block.

    Raises
    ------
    OutputError
        Another process holds the lock (another mjtvm run writes to the same folder).
    """
    path = Path(folder) / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as e:
        raise OutputError(option, str(path), f"cannot create the lock file ({_problem(e)})") from e
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as e:
            if e.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise OutputError(
                    option,
                    str(Path(folder)),
                    "another mjtvm run is writing to this folder (its lock is held)",
                ) from e
            raise OutputError(option, str(path), f"cannot lock ({_problem(e)})") from e
        yield path
    finally:
        os.close(fd)  # closing releases the flock


def _write_temp(target: Path, data: bytes, option: str) -> Path:
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as e:
        raise OutputError(option, str(target), f"cannot write ({_problem(e)})") from e
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        # mkstemp's 0600 is meant for secrets, not results: give the mode open() would give.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
    except BaseException as e:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(e, OSError):
            raise OutputError(option, str(target), f"cannot write ({_problem(e)})") from e
        raise
    return Path(tmp)


def write_files(files: Mapping[Path, bytes | str], *, option: str = "--out") -> list[Path]:
    """Write every file of a set atomically (module docstring); returns the targets in order.

    ``str`` contents are encoded as UTF-8. Nothing is renamed until every temporary file is
    complete; on any failure the temporary files are removed and the targets are untouched.

    Raises
    ------
    OutputError
        A file cannot be written; names the target.
    """
    temps: list[tuple[Path, Path]] = []
    try:
        for target, data in files.items():
            path = Path(target)
            raw = data.encode("utf-8") if isinstance(data, str) else data
            temps.append((_write_temp(path, raw, option), path))
        for tmp, path in temps:
            try:
                os.replace(tmp, path)
            except OSError as e:
                raise OutputError(option, str(path), f"cannot replace ({_problem(e)})") from e
    except BaseException:
        for tmp, _ in temps:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        raise
    return [path for _, path in temps]


def atomic_write(path: str | Path, data: bytes | str, *, option: str = "--out") -> Path:
    """Write one file atomically (temporary file in the same folder, then :func:`os.replace`)."""
    return write_files({Path(path): data}, option=option)[0]
