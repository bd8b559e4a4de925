r"""The finished rows of a long command (``mjtvm sweep``, ``mjtvm rank``) kept across an
interruption: read back with ``--resume`` when their inputs are unchanged, and written to
``NAME.partial.json`` as they come (atomically, at most every few seconds, and on an
interrupt or a failure), so that an interrupted run loses no finished work.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Hashable, Iterable
from pathlib import Path
from typing import Any, Generic, TypeVar

from mjtvm.errors import StateError
from mjtvm.formats.files import write_files

__all__ = ["RowCheckpoint"]

Row = dict[str, Any]
K = TypeVar("K", bound=Hashable)


class RowCheckpoint(Generic[K]):
    """The checkpoint file of one run and the rows it holds.

    Parameters
    ----------
    path
        ``NAME.partial.json``.
    schema
        Its ``schema`` key, e.g. ``"mjtvm.sweep-checkpoint/1"``.
    key
        A row's identity (the grid point, the grasp's id).
    digest
        A row's ``inputs`` digest now: a row read back is kept only if its ``inputs`` equal it.
    every_s
        The least time between two writes while rows come in.
    again
        How the error on an unreadable file tells the user to start afresh.
    """

    def __init__(
        self,
        path: Path,
        schema: str,
        *,
        key: Callable[[Row], K],
        digest: Callable[[Row], str],
        every_s: float,
        again: str,
    ) -> None:
        self.path, self.schema, self.key, self.digest = path, schema, key, digest
        self.every_s, self.again = every_s, again
        self.done: dict[K, Row] = {}
        self.finished: dict[K, Row] = {}
        self._last = time.monotonic()

    def tagged(self, row: Row) -> Row:
        """``row`` with its ``inputs`` digest."""
        return {**row, "inputs": self.digest(row)}

    def read_rows(self, path: Path, *, checkpoint: bool) -> list[Row]:
        """The rows of an earlier ``NAME.json`` (a list) or of a checkpoint (``{"schema", "rows"}``).

        Raises
        ------
        StateError
            The file cannot be read, or is not such a document.
        """
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
            rows = doc["rows"] if checkpoint else doc
            if checkpoint and doc.get("schema") != self.schema:
                raise ValueError(f"schema {doc.get('schema')!r}, expected {self.schema!r}")
            [self.key(r) for r in rows]
        except (OSError, ValueError, TypeError, KeyError) as e:
            raise StateError(str(path), f"cannot read the finished rows ({e}); {self.again}") from e
        return list(rows)

    def resume(
        self,
        earlier: Path,
        wanted: set[K],
        *,
        quiet: bool,
        emit: Callable[[str], None],
        notice: Callable[[str], None],
    ) -> dict[K, Row]:
        """The rows of ``earlier`` (``NAME.json``) and of the checkpoint that belong to this run
        (``wanted``) and whose inputs are unchanged; ``notice`` says how many changed."""
        changed: set[K] = set()
        for path, is_checkpoint in ((earlier, False), (self.path, True)):
            if path.exists():
                for r in self.read_rows(path, checkpoint=is_checkpoint):
                    k = self.key(r)
                    if k not in wanted:
                        continue
                    if r.get("inputs") == self.digest(r):
                        self.done[k] = r
                    else:
                        changed.add(k)
        changed -= self.done.keys()  # e.g. stale in NAME.json, solved again in the checkpoint
        if changed:
            notice(f"resume: {len(changed)} rows recomputed: inputs changed")
        if not quiet:
            emit(f"resume: {len(self.done)} of {len(wanted)} rows already finished")
        self.finished.update(self.done)
        self._last = time.monotonic()
        return self.done

    def save(self) -> None:
        """Write every finished row (atomically)."""
        doc = {"schema": self.schema, "rows": list(self.finished.values())}
        write_files({self.path: json.dumps(doc, indent=1) + "\n"})

    def record(self, rows: Iterable[Row]) -> None:
        """Keep newly finished rows; write them when `every_s` has passed."""
        self.finished.update((self.key(r), self.tagged(r)) for r in rows)
        if time.monotonic() - self._last >= self.every_s:
            self.save()
            self._last = time.monotonic()

    def save_new(self) -> None:
        """On an interrupt or a failure: write the rows finished since the start, if any."""
        if len(self.finished) > len(self.done):
            self.save()

    def run(
        self,
        solve: Callable[[dict[K, Row], Callable[[Iterable[Row]], None]], list[Row]],
        *,
        resume: bool,
        earlier: Path,
        wanted: set[K],
        quiet: bool,
        emit: Callable[[str], None],
        notice: Callable[[str], None],
    ) -> list[Row]:
        """Every row of the run, tagged with its inputs: the finished ones read back (with
        ``resume``, `resume()`), the rest from ``solve(done, on_rows)``, which calls
        ``on_rows`` (`record()`) as rows finish; on an interrupt or a failure the rows
        finished so far are written (`save_new()`) before it propagates."""
        done = self.resume(earlier, wanted, quiet=quiet, emit=emit, notice=notice) if resume else {}
        try:
            rows = solve(done, self.record)
        except BaseException:
            self.save_new()  # no finished work is lost to an interrupt or a failure
            raise
        return [self.tagged(r) for r in rows]
