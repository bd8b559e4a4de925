r"""What the jobs' files share: rows as CSV text, the files an MJCF model names, notices on stderr.

[`csv_text()`][mjtvm.jobs.files.csv_text] writes the CSV of ``mjtvm sweep``, ``mjtvm rank`` and
``mjtvm verify``; [`model_files()`][mjtvm.jobs.files.model_files] lists what an inputs digest
hashes ([`mjtvm.jobs.sweep_files`][mjtvm.jobs.sweep_files], [`mjtvm.jobs.rank_files`][mjtvm.jobs.rank_files]).
Writing the files themselves (atomically, under a lock) is [`mjtvm.formats.files`][mjtvm.formats.files].
"""

from __future__ import annotations

import csv
import io
import os
import re
import sys
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = ["csv_text", "model_files", "stderr"]


def csv_text(
    rows: Iterable[Mapping[str, Any]],
    columns: Sequence[str] | None = None,
    *,
    cell: Callable[[Any], Any] | None = None,
) -> str:
    """Rows as CSV text (``\\r\\n`` line ends, as the ``csv`` module writes them).

    Parameters
    ----------
    rows
        The rows, each a mapping of column -> value.
    columns
        The header; ``None``: every row's keys in order of first appearance.
    cell
        Applied to every value of a row before it is written (``None``: the values as they are).

    Returns
    -------
    str
        The header and one line per row; a column a row lacks is an empty cell.
    """
    rows = list(rows)
    header = list(dict.fromkeys(k for r in rows for k in r)) if columns is None else list(columns)
    buf = io.StringIO(newline="")
    writer = csv.DictWriter(buf, fieldnames=header, restval="")
    writer.writeheader()
    for r in rows:
        writer.writerow(r if cell is None else {k: cell(v) for k, v in r.items()})
    return buf.getvalue()


_FILE_ATTRIBUTE = re.compile(rb"""\bfile\s*=\s*["']([^"']+)["']""")
"""An MJCF ``file="..."`` attribute (``<include>``, meshes, textures, ...)."""


def model_files(model: Path) -> list[Path]:
    """The MJCF file and the files it names, for an inputs digest.

    Parameters
    ----------
    model
        The MJCF file (or any file: only ``.xml`` files are searched for names).

    Returns
    -------
    list of Path
        ``model`` and the files named by ``file=`` attributes, through ``<include>`` files,
        taken relative to the naming file's folder, where they exist; each once.
    """
    seen: list[Path] = []
    todo = [model]
    while todo:
        path = todo.pop()
        if path in seen or not path.is_file():
            continue
        seen.append(path)
        if path.suffix.lower() == ".xml":
            for name in _FILE_ATTRIBUTE.findall(path.read_bytes()):
                todo.append(path.parent / os.fsdecode(name))
    return seen


def stderr(text: str) -> None:
    """Print ``text`` on stderr: the default ``notice`` of the commands' runners.

    Parameters
    ----------
    text
        The notice (a newline is added).
    """
    print(text, file=sys.stderr)
