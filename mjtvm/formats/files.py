r"""Output files: checked before work, written atomically as one set, one run per folder.

Every command that writes files (``replay``, ``sweep``, ``verify``, ``bench``) does so through
this module:

* [`check_output_dir()`][mjtvm.formats.files.check_output_dir] creates the output folder and proves it writable (by creating and
  removing a probe file) *before* any computation, so a bad ``--out`` costs nothing;
* [`output_lock()`][mjtvm.formats.files.output_lock] takes an exclusive, non-blocking `fcntl.flock()` on
  ``<folder>/.mjtvm.lock`` for the whole run and writes its process id into the file; a
  second run into the same folder fails at once with [`OutputError`][mjtvm.errors.OutputError]
  instead of interleaving its rows. The lock file stays in the folder (removing it would let
  two runs lock two different files); the lock itself is released by the kernel when the
  last descriptor of it closes. Forked children close their copy of the descriptor at once
  (`os.register_at_fork()`): a flock belongs to the open file, so a child that outlived
  its parent would otherwise keep the folder locked. A lock held while the process id in the
  file is gone (leftover processes of a dead run, e.g. of an older mjtvm) is taken over: the
  lock file is replaced by a new one, locked, under a short lock of the folder itself, and a
  one-line notice goes to stderr;
* [`write_files()`][mjtvm.formats.files.write_files] writes a run's files as one set: every file's content goes first to a
  temporary file in the same folder (``.<name>.<pid>.<random>.tmp``, flushed and fsynced),
  and only when *all* of them are complete are they renamed over their targets with
  `os.replace()`, one after another. Each target is therefore always either its old
  complete content or its new complete content, never a truncated file; and a new file
  sits beside an old one of the same set only for the time the renames take (microseconds,
  no computation or I/O of content in between). A failure while writing the temporary files
  (disk full, ...) removes them and leaves every target untouched; an interrupt does the same.
  A killed process cannot remove its temporaries: [`output_lock()`][mjtvm.formats.files.output_lock] removes those whose
  process id (in the name) no longer runs, never those of a live process.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import re
import sys
import tempfile
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path

from mjtvm.errors import OutputError

__all__ = [
    "LOCK_NAME",
    "atomic_write",
    "check_output_dir",
    "output_lock",
    "process_alive",
    "remove_stale_temporaries",
    "write_files",
]

LOCK_NAME = ".mjtvm.lock"

_TEMPORARY = re.compile(r"\..+\.(?P<pid>[0-9]+)\.[A-Za-z0-9_]+\.tmp")
"""The names of this module's temporary files: ``.<name>.<pid>.<random>.tmp``."""

_HELD: dict[int, Path] = {}
"""Descriptor -> lock file, of the locks this process holds (closed in forked children)."""


def _close_inherited_locks() -> None:
    """In a forked child: close the copies of the parent's lock descriptors. Closing a copy
    leaves the parent's lock in place (a flock lives until the open file's last descriptor
    closes), and a child that outlived its parent no longer keeps the folder locked."""
    for fd in _HELD:
        with contextlib.suppress(OSError):
            os.close(fd)
    _HELD.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_close_inherited_locks)


def _problem(e: OSError) -> str:
    return e.strerror or str(e) if e.errno is not None else str(e)


def process_alive(pid: int) -> bool:
    """Whether a process with this id exists (a zombie counts as gone).

    A process of another user counts as alive: it cannot be signalled, but it exists.
    """
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:  # a zombie (ended, not yet reaped) holds no files: it is gone for our purposes
        with open(f"/proc/{pid}/stat", "rb") as f:
            return f.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except (OSError, IndexError):
        return True


def _temporary(folder: Path, name: str) -> tuple[int, str]:
    """A new temporary file ``.<name>.<pid>.<random>.tmp`` in ``folder`` (its descriptor, path)."""
    return tempfile.mkstemp(prefix=f".{name}.{os.getpid()}.", suffix=".tmp", dir=folder)


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
        fd, probe = _temporary(folder, "mjtvm-probe")
        try:
            os.write(fd, b"x")
            os.fsync(fd)
        finally:
            os.close(fd)
            os.unlink(probe)
    except OSError as e:
        raise OutputError(option, str(folder), f"cannot write in the folder ({_problem(e)})") from e
    return folder


def remove_stale_temporaries(folder: str | Path) -> list[Path]:
    """Remove the temporary files (``.<name>.<pid>.<random>.tmp``) of processes that ended.

    Those of a live process (a run writing into the folder now) are left alone, as is every
    file not named like a temporary of this module. Returns the removed files.
    """
    removed = []
    with contextlib.suppress(OSError):
        for entry in os.scandir(folder):
            match = _TEMPORARY.fullmatch(entry.name)
            if match is None or process_alive(int(match["pid"])) or not entry.is_file(follow_symlinks=False):
                continue
            with contextlib.suppress(FileNotFoundError):
                os.unlink(entry.path)
                removed.append(Path(entry.path))
    return removed


def _identity() -> str:
    """Where this process's id means something: the host and the pid namespace (a folder shared
    between machines or containers holds ids of other process tables)."""
    try:
        namespace = os.stat("/proc/self/ns/pid").st_ino
    except OSError:
        namespace = 0
    return f"{os.uname().nodename} {namespace}"


def _owner(fd: int) -> int | None:
    """The process id written in a lock file, if it reads as one of this process table."""
    try:
        pid, _, where = os.pread(fd, 256, 0).decode("utf-8").strip().partition(" ")
    except (OSError, UnicodeDecodeError):
        return None
    return int(pid) if pid.isdigit() and where == _identity() else None


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` still names the open file ``fd`` (a takeover replaces the lock file)."""
    try:
        a, b = os.fstat(fd), os.stat(path)
    except OSError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def _try_lock(path: Path, option: str) -> tuple[int, int | None]:
    """Open ``path`` and try to lock it: ``(fd, None)`` when locked, ``(fd, owner)`` when held
    by another open file (``owner``: the process id in the file, -1 when unreadable)."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as e:
        raise OutputError(option, str(path), f"cannot create the lock file ({_problem(e)})") from e
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as e:
        if e.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            owner = _owner(fd)
            return fd, -1 if owner is None else owner
        os.close(fd)
        raise OutputError(option, str(path), f"cannot lock ({_problem(e)})") from e
    except BaseException:
        os.close(fd)
        raise
    return fd, None


def _live(owner: int, path: Path) -> bool:
    """Whether the process that wrote ``owner`` into the lock file still runs (an unreadable
    id, or one of another host or pid namespace, counts as live: refusing is the safe side)."""
    if owner < 0:
        return True
    if owner == os.getpid():  # this process: live if it holds this folder's lock itself
        return any(_same_file(fd, path) for fd in _HELD)
    return process_alive(owner)


def _take_over(folder: Path, path: Path, option: str, notice: Callable[[str], None]) -> int:
    """Replace a lock file held by the leftovers of a dead run by a new, locked one.

    Runs under a blocking flock of the folder itself, so that two runs never both replace
    the file; inside it, the lock file is tried again (another run may have taken over).
    """
    try:
        dfd = os.open(folder, os.O_RDONLY)
    except OSError as e:
        raise OutputError(option, str(folder), f"cannot lock ({_problem(e)})") from e
    try:
        fcntl.flock(dfd, fcntl.LOCK_EX)
        fd, owner = _try_lock(path, option)
        if owner is None:
            return fd  # the leftovers ended meanwhile: the old file is free
        os.close(fd)
        if _live(owner, path):
            raise OutputError(
                option, str(folder), "another mjtvm run is writing to this folder (its lock is held)"
            )
        try:
            fd, tmp = _temporary(folder, LOCK_NAME.lstrip("."))
        except OSError as e:
            raise OutputError(option, str(path), f"cannot create the lock file ({_problem(e)})") from e
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # new and unnamed yet: always free
            os.fchmod(fd, 0o644)
            os.replace(tmp, path)
        except BaseException as e:
            os.close(fd)
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            if isinstance(e, OSError):
                raise OutputError(option, str(path), f"cannot replace the lock file ({_problem(e)})") from e
            raise
        notice(
            f"mjtvm: {option}: took over the lock of an ended run (process {owner}; processes it "
            f"left still held the old lock): {folder}"
        )
        return fd
    finally:
        os.close(dfd)  # closing releases the folder's flock


def _stderr(text: str) -> None:
    print(text, file=sys.stderr)


@contextlib.contextmanager
def output_lock(
    folder: str | Path, *, option: str = "--out", notice: Callable[[str], None] = _stderr
) -> Iterator[Path]:
    """Hold an exclusive lock on ``folder`` for the duration of the block.

    The lock file holds this process's id. A lock held by leftovers of a run whose process
    has ended is taken over (``notice`` gets one line). Once locked, the temporary files of
    ended processes are removed ([`remove_stale_temporaries()`][mjtvm.formats.files.remove_stale_temporaries]).

    Raises
    ------
    OutputError
        Another live process holds the lock (another mjtvm run writes to the same folder).
    """
    folder = Path(folder)
    path = folder / LOCK_NAME
    for _ in range(100):  # a takeover between open and flock sends us round again (rare)
        fd, owner = _try_lock(path, option)
        if owner is not None:
            os.close(fd)
            if _live(owner, path):
                raise OutputError(
                    option, str(folder), "another mjtvm run is writing to this folder (its lock is held)"
                )
            fd = _take_over(folder, path, option, notice)
        if _same_file(fd, path):
            break
        os.close(fd)
    else:  # pragma: no cover - a folder whose lock file is replaced without end
        raise OutputError(option, str(path), "cannot lock (the lock file keeps being replaced)")
    _HELD[fd] = path
    try:
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()} {_identity()}\n".encode(), 0)
        except OSError as e:
            raise OutputError(option, str(path), f"cannot write the lock file ({_problem(e)})") from e
        remove_stale_temporaries(folder)
        yield path
    finally:
        if _HELD.pop(fd, None) is not None:
            os.close(fd)  # closing releases the flock


def _write_temp(target: Path, data: bytes | Iterable[str | bytes], option: str) -> Path:
    try:
        fd, tmp = _temporary(target.parent, target.name)
    except OSError as e:
        raise OutputError(option, str(target), f"cannot write ({_problem(e)})") from e
    try:
        with os.fdopen(fd, "wb") as f:
            if isinstance(data, bytes):
                f.write(data)
            else:  # chunks, written as they come: the whole text is never held
                for chunk in data:
                    f.write(chunk.encode("utf-8") if isinstance(chunk, str) else chunk)
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


def write_files(
    files: Mapping[Path, bytes | str | Iterable[str | bytes]], *, option: str = "--out"
) -> list[Path]:
    """Write every file of a set atomically (module docstring); returns the targets in order.

    ``str`` contents are encoded as UTF-8; an iterable of chunks (a generator) is written
    chunk by chunk, ``str`` chunks as UTF-8, ``bytes`` as they are. Nothing is renamed until every temporary file is
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
    """Write one file atomically (temporary file in the same folder, then `os.replace()`)."""
    return write_files({Path(path): data}, option=option)[0]
