r"""The rows of a running ``mjtvm rank`` kept on disk, not in memory: ``NAME.partial.jsonl``.

A dataset of any size is ranked with a memory that does not grow with it
(``docs/datasets.md``, "Memory"): every finished row is appended to this log as one JSON line
and dropped; the written files are made from the log at the end
([`mjtvm.jobs.rank_files`][mjtvm.jobs.rank_files]), reading one row at a time.

The log is the checkpoint too. Its first line is ``{"schema": "mjtvm.rank-checkpoint/2"}``;
every other line is one row with its ``inputs`` digest. Rows are flushed to the operating
system after every finished task and synced to disk at most every ``every_s`` seconds, so an
interrupted run (Ctrl-C, a kill, a failure) loses no finished row: a process killed in the
middle of a line leaves that line torn, and reading drops a torn *last* line (that row is
evaluated again); a malformed line elsewhere is an error. An append log is not written
atomically as the results are: it is never a result, only what ``--resume`` reads.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import time
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import OutputError, StateError

__all__ = ["LOG_SCHEMA", "IdSet", "RankLog", "RowReader", "id_hash"]

LOG_SCHEMA = "mjtvm.rank-checkpoint/2"
"""The schema of the log's first line."""

Row = dict[str, Any]


def id_hash(grasp_id: str) -> int:
    """A grasp id's 64-bit digest (BLAKE2b): what the run keeps of an id, 8 bytes a grasp."""
    return int.from_bytes(hashlib.blake2b(grasp_id.encode("utf-8"), digest_size=8).digest(), "little")


class IdSet:
    """A set of grasp ids held as their sorted 64-bit digests (`id_hash()`), each with a
    number (the grasp's position in the datasets): 16 bytes a grasp, not a string each.

    Two distinct ids with one digest (odds about n^2 / 2^65) are told apart by the caller,
    which reads the ids again ([`scan_datasets()`][mjtvm.jobs.rank_inputs.scan_datasets]).
    """

    def __init__(self, hashes: Iterable[int] = (), values: Iterable[int] | None = None) -> None:
        h = np.fromiter(hashes, dtype=np.uint64)
        v = np.arange(len(h), dtype=np.int64) if values is None else np.fromiter(values, dtype=np.int64)
        order = np.argsort(h, kind="stable")
        self.hashes: NDArray[np.uint64] = h[order]
        self.values: NDArray[np.int64] = v[order]

    def __len__(self) -> int:
        return len(self.hashes)

    def repeated(self) -> NDArray[np.uint64]:
        """The digests held more than once."""
        same = self.hashes[1:] == self.hashes[:-1]
        return np.unique(self.hashes[1:][same])

    def lookup(self, grasp_id: str) -> int | None:
        """The number of ``grasp_id``, or ``None`` if it is not in the set."""
        h = np.uint64(id_hash(grasp_id))
        i = int(np.searchsorted(self.hashes, h))
        if i < len(self.hashes) and self.hashes[i] == h:
            return int(self.values[i])
        return None

    def __contains__(self, grasp_id: object) -> bool:
        return isinstance(grasp_id, str) and self.lookup(grasp_id) is not None


class RankLog:
    """``NAME.partial.jsonl``: append rows, read them back by position.

    Parameters
    ----------
    path
        The log file.
    every_s
        The least time (s) between two syncs to disk while rows come in.
    again
        How an error on an unreadable log tells the user to start afresh.
    """

    def __init__(
        self, path: Path, *, every_s: float = 5.0, again: str = "run again without --resume"
    ) -> None:
        self.path, self.every_s, self.again = Path(path), every_s, again
        self._file: BinaryIO | None = None
        self._last = time.monotonic()
        self.count = 0

    # -- writing -------------------------------------------------------------------------------

    def start(self, kept: Iterable[Row] = ()) -> int:
        """Begin the log afresh with the rows ``kept`` (read back by ``--resume``): written to a
        temporary file that replaces the log, so that the old log stays whole until then.
        Returns how many rows were kept."""
        tmp = self.path.with_name(f".{self.path.name}.new")
        try:
            with open(tmp, "wb") as f:
                f.write(_line({"schema": LOG_SCHEMA}))
                n = 0
                for row in kept:
                    f.write(_line(row))
                    n += 1
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, self.path)
            self._file = open(self.path, "ab")
        except OSError as e:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise OutputError(
                "--out", str(self.path), f"cannot write the checkpoint ({e.strerror or e})"
            ) from e
        self.count = n
        self._last = time.monotonic()
        return n

    def append(self, rows: Iterable[Row]) -> None:
        """Append finished rows (flushed now; synced to disk at most every ``every_s``)."""
        if self._file is None:
            raise RuntimeError("RankLog.append before start()")
        for row in rows:
            self._file.write(_line(row))
            self.count += 1
        self._file.flush()
        if time.monotonic() - self._last >= self.every_s:
            os.fsync(self._file.fileno())
            self._last = time.monotonic()

    def close(self) -> None:
        """Sync and close the log (kept on disk until `remove()`)."""
        if self._file is not None:
            with contextlib.suppress(OSError):
                self._file.flush()
                os.fsync(self._file.fileno())
            self._file.close()
            self._file = None

    def remove(self) -> None:
        """Close and delete the log (once the results are written)."""
        self.close()
        self.path.unlink(missing_ok=True)

    # -- reading -------------------------------------------------------------------------------

    def entries(self, path: Path | None = None) -> Iterator[tuple[int, Row]]:
        """``(offset, row)`` of every row of the log (or of another log at ``path``), in the
        order written; a torn last line is dropped.

        Raises
        ------
        StateError
            Not a log of this schema, or a malformed line before the last.
        """
        where = self.path if path is None else Path(path)
        try:
            with open(where, "rb") as f:
                head = f.readline()
                try:
                    schema = json.loads(head).get("schema")
                except (ValueError, AttributeError):
                    schema = None
                if schema != LOG_SCHEMA:
                    raise StateError(str(where), f"not a checkpoint of schema {LOG_SCHEMA}; {self.again}")
                offset = f.tell()
                while line := f.readline():
                    try:
                        row = json.loads(line)
                        if not isinstance(row, dict) or "id" not in row:
                            raise ValueError("not a row")
                    except ValueError as e:
                        if not line.endswith(b"\n") and not f.read(1):
                            return  # torn by an interrupted write: that row is evaluated again
                        raise StateError(
                            str(where), f"line at byte {offset} is not a row ({e}); {self.again}"
                        ) from e
                    yield offset, row
                    offset = f.tell()
        except OSError as e:
            raise StateError(
                str(where), f"cannot read the checkpoint ({e.strerror or e}); {self.again}"
            ) from e

    def reader(self) -> RowReader:
        """A [`RowReader`][mjtvm.jobs.rank_log.RowReader] of this log (closed for writing, or flushed)."""
        return RowReader(self.path)


class RowReader:
    """Read rows of a log by their offsets (`RankLog.entries()`); a context manager that
    closes the file.

    Parameters
    ----------
    path
        The log file.
    """

    def __init__(self, path: Path) -> None:
        self._file = open(path, "rb")

    def __call__(self, offset: int) -> Row:
        """The row at ``offset``."""
        self._file.seek(offset)
        row: Row = json.loads(self._file.readline())
        return row

    def close(self) -> None:
        """Close the file."""
        self._file.close()

    def __enter__(self) -> RowReader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _line(obj: Any) -> bytes:
    return (json.dumps(obj, separators=(",", ":")) + "\n").encode("utf-8")
