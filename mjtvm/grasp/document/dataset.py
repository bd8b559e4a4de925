r"""Grasp datasets: many configurations of one grasp file's hand (``docs/datasets.md``).

A dataset file holds, per grasp, either ``grasp_qpos`` (the hand's root pose
``[x, y, z, qw, qx, qy, qz]``, m and a unit quaternion, then the hand's joints in model order:
`hand_joints()`) or ``qpos`` (the model's whole ``qpos``, ``nq`` numbers), and optionally
``obj_pose`` (the object's pose, 7 numbers as the root's), ``obj_scale`` (> 0, default 1) and
``obj_path`` (an MJCF file of the object, relative to the dataset file). Layouts:

* ``.npz``: arrays ``grasp_qpos`` ``(N, 7 + J)`` or ``qpos`` ``(N, nq)``; ``obj_pose``
  ``(N, 7)``, ``obj_scale`` ``(N,)``, ``obj_path`` ``(N,)`` strings; optional ``id`` ``(N,)``;
* ``.npy`` holding a 2-D number array: ``qpos`` when its width is ``nq``, else ``grasp_qpos``;
* ``.npy`` holding one pickled dict (one grasp per file, the layout of grasp-synthesis
  pipelines) with the keys above as 1-D arrays or numbers: loaded with ``allow_pickle=True``,
  which runs the pickle's code, *only* after a plain load found an object array;
* ``.csv`` with a header: ``grasp_qpos_0`` ... or ``qpos_0`` ..., ``obj_pose_0`` ...
  ``obj_pose_6``, ``obj_scale``, ``obj_path``, ``id``.

Every value is checked here: a malformed grasp raises one line naming the file, the grasp's
index and the field.
"""

from __future__ import annotations

import csv
import pickle
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.grasp.document.checks import GraspError

__all__ = ["ROOT_SIZE", "DatasetGrasp", "read_dataset"]

ROOT_SIZE = 7
"""Numbers of a pose: position (3, m) then a unit quaternion (4, w-x-y-z)."""

_KEYS = ("grasp_qpos", "qpos", "obj_pose", "obj_scale", "obj_path", "id")


@dataclass(frozen=True, eq=False)
class DatasetGrasp:
    r"""One configuration of a dataset.

    Attributes
    ----------
    id
        The row's identity: the ``id`` given, else ``<file stem>:<index>`` (``<file stem>`` for
        a per-grasp ``.npy`` dict).
    source, index
        The dataset file and the grasp's index in it (0-based).
    qpos
        ``(nq,)`` the whole ``qpos``, or ``None``.
    root, joints
        ``(7,)`` the root pose and ``(J,)`` the hand's joints (``grasp_qpos``), or ``None``.
    obj_pose
        ``(7,)`` the object's pose (unit quaternion), or ``None``: the grasp file's (or, with
        ``qpos``, the object's free joint in it).
    obj_scale
        The object's scale factor (> 0).
    obj_path
        The object's MJCF file (absolute), or ``None``: the grasp file's object.
    """

    id: str
    source: str
    index: int
    qpos: NDArray[np.float64] | None
    root: NDArray[np.float64] | None
    joints: NDArray[np.float64] | None
    obj_pose: NDArray[np.float64] | None = None
    obj_scale: float = 1.0
    obj_path: str | None = None

    def __post_init__(self) -> None:
        if (self.qpos is None) == (self.root is None):
            raise GraspError(self.source, self._field("grasp_qpos"), "expected grasp_qpos or qpos, not both")

    def _field(self, key: str) -> str:
        return f"grasp {self.index}: {key}"


def _fail(path: Path, index: int, key: str, problem: str) -> GraspError:
    return GraspError(str(path), f"grasp {index}: {key}", problem)


def _vector(path: Path, index: int, key: str, value: Any, size: int) -> NDArray[np.float64]:
    try:
        v = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError) as e:
        raise _fail(path, index, key, f"expected {size} numbers, got {type(value).__name__}") from e
    if v.size != size:
        raise _fail(path, index, key, f"expected {size} numbers, got {v.size}")
    bad = np.flatnonzero(~np.isfinite(v))
    if bad.size:
        raise _fail(path, index, key, f"expected finite numbers, got {v[bad[0]]} at position {bad[0]}")
    return v


def _pose(path: Path, index: int, key: str, value: Any) -> NDArray[np.float64]:
    v = _vector(path, index, key, value, ROOT_SIZE)
    norm = float(np.linalg.norm(v[3:]))
    if norm < 1e-9:
        raise _fail(
            path, index, key, "expected a unit quaternion [qw, qx, qy, qz] after the position, got zeros"
        )
    v[3:] /= norm  # a stored quaternion's round-off; MuJoCo wants it unit
    return v


def _grasp(
    path: Path, index: int, values: dict[str, Any], *, nq: int, num_joints: int, default_id: str
) -> DatasetGrasp:
    """One grasp from its ``values`` (key -> this grasp's value), checked."""
    unknown = sorted(set(values) - set(_KEYS))
    if unknown:
        raise _fail(path, index, unknown[0], f"unknown key (expected some of {', '.join(_KEYS)})")
    has = [k for k in ("grasp_qpos", "qpos") if values.get(k) is not None]
    if len(has) != 1:
        raise _fail(
            path,
            index,
            "grasp_qpos",
            "missing: expected grasp_qpos (root pose + hand joints) or qpos (the model's nq numbers)"
            if not has
            else "expected grasp_qpos or qpos, not both",
        )
    qpos = root = joints = None
    if has[0] == "qpos":
        qpos = _vector(path, index, "qpos", values["qpos"], nq)
    else:
        full = _vector(path, index, "grasp_qpos", values["grasp_qpos"], ROOT_SIZE + num_joints)
        root, joints = _pose(path, index, "grasp_qpos", full[:ROOT_SIZE]), full[ROOT_SIZE:]
    pose = None if values.get("obj_pose") is None else _pose(path, index, "obj_pose", values["obj_pose"])
    scale = 1.0
    if values.get("obj_scale") is not None:
        scale = float(_vector(path, index, "obj_scale", values["obj_scale"], 1)[0])
        if scale <= 0:
            raise _fail(path, index, "obj_scale", f"expected a scale factor > 0, got {scale}")
    obj_path = None
    if values.get("obj_path") not in (None, ""):
        text = str(values["obj_path"])
        where = (path.parent / text).resolve()
        if not where.is_file():
            raise _fail(path, index, "obj_path", f"no such file: {str(where)!r}")
        obj_path = str(where)
    given = values.get("id")
    return DatasetGrasp(
        id=default_id if given in (None, "") else str(given),
        source=str(path),
        index=index,
        qpos=qpos,
        root=root,
        joints=joints,
        obj_pose=pose,
        obj_scale=scale,
        obj_path=obj_path,
    )


def _rows_npz(path: Path) -> list[dict[str, Any]]:
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    if not arrays:
        raise GraspError(str(path), "", "no arrays in the file: expected grasp_qpos or qpos")
    counts = {k: len(a) if a.ndim else 1 for k, a in arrays.items()}
    n = counts.get("grasp_qpos", counts.get("qpos"))
    if n is None:
        raise _fail(path, 0, "grasp_qpos", "missing: expected an array grasp_qpos (N, 7 + J) or qpos (N, nq)")
    for k, c in counts.items():
        if c != n or arrays[k].ndim == 0:
            raise GraspError(str(path), k, f"expected {n} rows (one per grasp), got {c}")
    return [{k: a[i] for k, a in arrays.items()} for i in range(n)]


def _rows_npy(path: Path, nq: int) -> tuple[list[dict[str, Any]], bool]:
    """The rows and whether the file is one per-grasp dict."""
    try:
        array = np.load(path, allow_pickle=False)
    except ValueError:  # an object array: the per-grasp dict layout (a pickle)
        value = np.load(path, allow_pickle=True)
        item = value.item() if isinstance(value, np.ndarray) and value.shape == () else value
        if not isinstance(item, dict):
            raise GraspError(
                str(path), "", "expected a number array or one pickled dict of a grasp"
            ) from None
        return [dict(item)], True
    if array.ndim != 2:
        raise GraspError(str(path), "", f"expected a 2-D array (grasps x numbers), got shape {array.shape}")
    key = "qpos" if array.shape[1] == nq else "grasp_qpos"
    return [{key: row} for row in array], False


def _rows_csv(path: Path) -> list[dict[str, Any]]:
    with path.open(newline="", encoding="utf-8") as f:
        table = list(csv.DictReader(f))
    rows = []
    for i, line in enumerate(table):
        row: dict[str, Any] = {}
        for column, text in line.items():
            if column is None or text is None:
                raise _fail(path, i, "columns", "expected as many values as the header has columns")
            key, _, position = column.rpartition("_")
            if column in ("obj_scale", "obj_path", "id"):
                row[column] = text or None
            elif key in ("grasp_qpos", "qpos", "obj_pose") and position.isdigit():
                if text == "":
                    raise _fail(path, i, column, "empty: expected a number")
                try:
                    row.setdefault(key, []).append((int(position), float(text)))
                except ValueError as e:
                    raise _fail(path, i, column, f"expected a number, got {text!r}") from e
            else:
                raise _fail(
                    path,
                    i,
                    column,
                    "unknown column (expected grasp_qpos_<i>, qpos_<i>, obj_pose_<i>, obj_scale, obj_path, id)",
                )
        for key in ("grasp_qpos", "qpos", "obj_pose"):
            if key in row:
                row[key] = [x for _, x in sorted(row[key])]
        rows.append(row)
    return rows


def read_dataset(path: str | Path, *, nq: int, num_joints: int) -> list[DatasetGrasp]:
    r"""The grasps of one dataset file (``.npz``, ``.npy`` or ``.csv``; layouts in the module's doc).

    Parameters
    ----------
    path
        The file.
    nq
        The model's ``nq`` (the width of ``qpos``).
    num_joints
        ``J``: the hand's joints (`hand_joints()`): ``grasp_qpos`` has ``7 + J`` numbers.

    Raises
    ------
    GraspError
        An unreadable file, or a grasp with a missing, misshapen or non-finite field: ``FILE:
        grasp I: FIELD: problem``.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if not p.is_file():
        raise GraspError(str(p), "", "no such dataset file")
    single = False
    try:
        if suffix == ".npz":
            rows = _rows_npz(p)
        elif suffix == ".npy":
            rows, single = _rows_npy(p, nq)
        elif suffix == ".csv":
            rows = _rows_csv(p)
        else:
            raise GraspError(
                str(p), "", f"expected a .npz, .npy or .csv dataset, got {suffix or 'no suffix'!r}"
            )
    except GraspError:
        raise
    # A damaged pickle or zip, an over-long CSV field, a pickle naming a missing class:
    except (
        OSError,
        ValueError,
        EOFError,
        pickle.UnpicklingError,
        csv.Error,
        AttributeError,
        ImportError,
    ) as e:
        raise GraspError(str(p), "", f"cannot read the dataset ({' '.join(str(e).split())[:200]})") from e
    if not rows:
        raise GraspError(str(p), "", "no grasps in the file")
    return [
        _grasp(p, i, row, nq=nq, num_joints=num_joints, default_id=p.stem if single else f"{p.stem}:{i}")
        for i, row in enumerate(rows)
    ]
