r"""The rows of ``mjtvm rank`` as the files hold them, written one row at a time: ``NAME.json``
([`rows_json_chunks()`][mjtvm.jobs.rank_tables.rows_json_chunks], read back by
[`json_list_rows()`][mjtvm.jobs.rank_tables.json_list_rows]), ``NAME.csv``
([`rows_csv_chunks()`][mjtvm.jobs.rank_tables.rows_csv_chunks]) and ``NAME.parquet`` in row groups
([`rows_parquet_chunks()`][mjtvm.jobs.rank_tables.rows_parquet_chunks]): what one needs in
memory is one row (or one row group), never the table.
"""

from __future__ import annotations

import io
import json
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from mjtvm.errors import StateError
from mjtvm.jobs.files import csv_text
from mjtvm.jobs.rank_index import RankIndex
from mjtvm.jobs.rank_row import flat_row, table_columns

__all__ = [
    "PARQUET_BATCH",
    "has_pyarrow",
    "json_list_rows",
    "rows_csv",
    "rows_csv_chunks",
    "rows_json_chunks",
    "rows_parquet",
    "rows_parquet_chunks",
    "rows_table",
]

AGAIN = "run again without --resume"


def rows_table(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rows flattened for CSV and Parquet ([`flat_row()`][mjtvm.jobs.rank_row.flat_row]):
    ``limiting`` -> ``limiting_k``, ``limiting_l``; ``alpha`` and ``status`` ->
    ``alpha_k<k>_l<l>``, ``status_k<k>_l<l>``; ``None`` -> ``""`` in the caller's CSV."""
    return [flat_row(r) for r in rows]


def rows_csv(rows: Sequence[dict[str, Any]]) -> str:
    """The rows as CSV ([`rows_table()`][mjtvm.jobs.rank_tables.rows_table]; empty cells where a value is ``None``)."""
    return "".join(rows_csv_chunks(rows, table_columns([RankIndex.from_rows(rows).columns])))


def rows_csv_chunks(rows: Iterable[dict[str, Any]], columns: Sequence[str]) -> Iterator[str]:
    """[`rows_csv()`][mjtvm.jobs.rank_tables.rows_csv] line by line: the header (``columns``:
    [`table_columns()`][mjtvm.jobs.rank_row.table_columns]), then each row flattened as it is
    written (one flattened row held at a time, not the table)."""
    columns = list(columns)
    yield csv_text([], columns)
    for row in rows:
        yield csv_text([flat_row(row)], columns, cell=lambda v: "" if v is None else v).split("\r\n", 1)[1]


def rows_json_chunks(rows: Iterable[dict[str, Any]]) -> Iterator[str]:
    """The text of ``json.dumps(rows, indent=1) + "\\n"``, one row at a time."""
    first = True
    for row in rows:
        text = json.dumps(row, indent=1).replace("\n", "\n ")
        yield ("[\n " if first else ",\n ") + text
        first = False
    yield "[]\n" if first else "\n]\n"


def _arrow_type(kinds: set[type]) -> Any:
    """The Parquet column type of a column's Python value types (as pyarrow infers it)."""
    import pyarrow as pa

    if not kinds:
        return pa.null()
    if kinds <= {bool}:
        return pa.bool_()
    if kinds <= {int}:
        return pa.int64()
    if kinds <= {int, float}:
        return pa.float64()
    return pa.string()


PARQUET_BATCH = 2048
"""Rows per Parquet row group while streaming."""


def rows_parquet_chunks(
    rows: Iterable[dict[str, Any]], columns: Sequence[str], kinds: Mapping[str, set[type]]
) -> Iterator[bytes]:
    """The rows as Parquet, [`PARQUET_BATCH`][mjtvm.jobs.rank_tables.PARQUET_BATCH] rows at a
    time: ``columns`` in order, each of the type of its values' Python types ``kinds``
    ([`RankIndex.columns`][mjtvm.jobs.rank_index.RankIndex]). Requires ``pyarrow``."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    schema = pa.schema([(c, _arrow_type(kinds.get(c, set()))) for c in columns])
    out: list[bytes] = []

    class _Sink(io.RawIOBase):
        def writable(self) -> bool:
            return True

        def write(self, b: Any) -> int:
            out.append(bytes(b))
            return len(b)

    sink = _Sink()
    writer = pq.ParquetWriter(sink, schema)
    batch: list[dict[str, Any]] = []

    def flush() -> Iterator[bytes]:
        writer.write_table(pa.Table.from_pylist(batch, schema=schema))
        batch.clear()
        yield b"".join(out)
        out.clear()

    for row in rows:
        flat = flat_row(row)
        batch.append({c: flat.get(c) for c in columns})
        if len(batch) >= PARQUET_BATCH:
            yield from flush()
    if batch:
        yield from flush()
    writer.close()
    yield b"".join(out)


def rows_parquet(rows: Sequence[dict[str, Any]]) -> bytes | None:
    """The rows as Parquet ([`rows_table()`][mjtvm.jobs.rank_tables.rows_table]), or ``None`` when ``pyarrow`` is not installed."""
    if not has_pyarrow():
        return None
    kinds = RankIndex.from_rows(rows).columns
    return b"".join(rows_parquet_chunks(rows, table_columns([kinds]), kinds))


def has_pyarrow() -> bool:
    """Whether ``pyarrow`` imports (``NAME.parquet`` is written only then)."""
    try:
        import pyarrow.parquet  # noqa: F401
    except ImportError:
        return False
    return True


def json_list_rows(path: Path, *, block: int = 1 << 20) -> Iterator[dict[str, Any]]:
    """The rows of a JSON list of objects (``NAME.json``), parsed one at a time from blocks of
    ``block`` characters: the whole list is never held.

    Raises
    ------
    StateError
        Not a JSON list of rows with an ``id``.
    """
    decoder = json.JSONDecoder()
    try:
        with open(path, encoding="utf-8") as f:
            buf, pos, state = "", 0, "["  # "[": the list's start; "{": a row or "]"; ",": "," or "]"
            while True:
                pos = _skip_space(buf, pos)
                while pos >= len(buf):
                    more = f.read(block)
                    if not more:
                        raise ValueError("not a JSON list" if state == "[" else "the list ends early")
                    buf, pos = more, _skip_space(more, 0)
                c = buf[pos]
                if state == "[":
                    if c != "[":
                        raise ValueError("not a JSON list")
                    pos, state = pos + 1, "{"
                elif c == "]":
                    return
                elif state == ",":
                    if c != ",":
                        raise ValueError(f"expected ',' between the rows, got {c!r}")
                    pos, state = pos + 1, "{"
                else:
                    while True:
                        try:
                            row, end = decoder.raw_decode(buf, pos)
                            break
                        except json.JSONDecodeError:
                            more = f.read(block)
                            if not more:
                                raise
                            buf, pos = buf[pos:] + more, 0
                    if not isinstance(row, dict) or "id" not in row:
                        raise ValueError("an element is not a row with an id")
                    yield row
                    buf, pos, state = buf[end:], 0, ","
    except (OSError, ValueError, UnicodeDecodeError) as e:
        raise StateError(str(path), f"cannot read the finished rows ({e}); {AGAIN}") from e


def _skip_space(text: str, pos: int) -> int:
    while pos < len(text) and text[pos] in " \t\r\n":
        pos += 1
    return pos
