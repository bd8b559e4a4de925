"""Dataset CSV files: a header, then one line per grasp (``docs/datasets.md``).

Numbered columns (``grasp_qpos_<i>``, ``qpos_<i>``, ``obj_pose_<i>``) must be complete and in
order: a column out of place is refused, never re-sorted (``grasp_qpos_99`` where
``grasp_qpos_12`` belongs would shift the joints by one).
"""

from __future__ import annotations

import csv
import re
from pathlib import Path
from typing import Any

from mjtvm.grasp.document.checks import GraspError

__all__ = ["csv_rows"]


def _fail(path: Path, index: int, key: str, problem: str) -> GraspError:
    return GraspError(str(path), f"grasp {index}: {key}", problem)


_NUMBERED = re.compile(r"(grasp_qpos|qpos|obj_pose)_(\d+)")


def _csv_columns(path: Path, header: list[str]) -> list[tuple[str, str, int]]:
    """``(column, key, position)`` per column, the numbered ones complete and in order."""
    columns: list[tuple[str, str, int]] = []
    seen: dict[str, int] = {}
    for column in header:
        m = _NUMBERED.fullmatch(column)
        if column in ("obj_scale", "obj_path", "id"):
            key, position = column, -1
        elif m:
            key, position = m.group(1), int(m.group(2))
            expected = seen.get(key, 0)
            if position != expected or m.group(2) != str(position):
                raise _fail(
                    path,
                    0,
                    column,
                    f"expected the column {key}_{expected} here (numbered columns complete and in order)",
                )
            seen[key] = expected + 1
        else:
            raise _fail(
                path,
                0,
                column,
                "unknown column (expected grasp_qpos_<i>, qpos_<i>, obj_pose_<i>, obj_scale, obj_path, id)",
            )
        if any(c == column for c, _, _ in columns):
            raise _fail(path, 0, column, "a column given twice")
        columns.append((column, key, position))
    return columns


def csv_rows(path: Path) -> list[dict[str, Any]]:
    """The rows of a dataset CSV: key -> text, number or list of numbers per grasp.

    Raises
    ------
    GraspError
        An unknown, repeated or misnumbered column, a line of another width, a cell not a number.
    """
    with path.open(newline="", encoding="utf-8") as f:
        table = list(csv.reader(f))
    if not table:
        raise GraspError(str(path), "", "empty: expected a header, then one line per grasp")
    columns = _csv_columns(path, table[0])
    rows = []
    for i, line in enumerate(table[1:]):
        if len(line) != len(columns):
            raise _fail(path, i, "columns", f"expected {len(columns)} values as the header, got {len(line)}")
        row: dict[str, Any] = {}
        for (column, key, position), text in zip(columns, line, strict=True):
            if position < 0 and column != "obj_scale":
                row[column] = text or None
                continue
            if column == "obj_scale" and text.strip() == "":
                continue  # the default scale
            if text.strip() == "":
                raise _fail(path, i, column, "empty: expected a number")
            try:
                number = float(text)
            except ValueError as e:
                raise _fail(path, i, column, f"expected a number, got {text!r}") from e
            if column == "obj_scale":
                row[column] = number
            else:
                row.setdefault(key, []).append(number)
        rows.append(row)
    return rows
