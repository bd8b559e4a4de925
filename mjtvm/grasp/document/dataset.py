r"""Grasp datasets: many configurations of one grasp file's hand (``docs/datasets.md``).

A dataset file holds, per grasp, either ``grasp_qpos`` (the hand's root pose
``[x, y, z, qw, qx, qy, qz]``, m and a unit quaternion, then the hand's joints in model order:
`hand_joints()`) or ``qpos`` (the model's whole ``qpos``, ``nq`` numbers), and optionally
``obj_pose`` (the object's pose, 7 numbers as the root's), ``obj_scale`` (default 1) and
``obj_path`` (an MJCF file of the object, or an object folder of DexGraspBench's layout: its
convex pieces in ``urdf/meshes/*.obj``). Layouts:

* ``.npz``: arrays ``grasp_qpos`` ``(N, 7 + J)`` or ``qpos`` ``(N, nq)``; ``obj_pose``
  ``(N, 7)``, ``obj_scale`` ``(N,)``, ``obj_path`` ``(N,)`` strings; optional ``id`` ``(N,)``;
* ``.npy`` holding a 2-D number array: its meaning stated by ``key`` (``qpos`` or
  ``grasp_qpos``), never guessed from its width;
* ``.npy`` holding one dict (DexGraspBench's per-grasp files) or a list of dicts (DexGraspNet's
  per-object files): their keys are mapped by `pipeline_row()`; the pickle is read by
  `DataUnpickler`, which builds numpy arrays, numbers, strings and dicts and runs nothing;
* ``.csv`` with a header: ``grasp_qpos_0`` ... or ``qpos_0`` ..., ``obj_pose_0`` ...
  ``obj_pose_6``, ``obj_scale``, ``obj_path``, ``id`` (numbered columns complete and in order).

Every value is checked here: a malformed grasp raises one line naming the file, the grasp's
index and the field.
"""

from __future__ import annotations

import csv
import pickle
import re
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.document.dataset_csv import csv_rows
from mjtvm.grasp.document.pipelines import POSES, PipelineKeyError, pipeline_row
from mjtvm.grasp.document.safe_npy import load_npy, load_npz

__all__ = ["ROOT_SIZE", "DatasetGrasp", "dataset_files", "iter_dataset", "read_dataset"]

ROOT_SIZE = 7
"""Numbers of a pose: position (3, m) then a unit quaternion (4, w-x-y-z)."""

QUATERNION_TOLERANCE = 1e-6
"""A stored quaternion's norm must be 1 within this (then it is made exactly unit)."""

SCALE_RANGE = (1e-4, 1e4)
"""``obj_scale`` must lie in this range."""

POSITION_BOUND = 1e3
"""Positions (m) must lie within this of the world's origin."""

_KEYS = ("grasp_qpos", "qpos", "obj_pose", "obj_scale", "obj_path", "id")
_SUFFIXES = (".npz", ".npy", ".csv")


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
        The object's MJCF file or object folder (absolute), or ``None``: the grasp file's object.
    com_frame
        The object's frame (the REFS's moments, the RVDS's twists) moved to its centre of mass,
        the object left where ``obj_pose`` puts it (``grasp_qpos`` entries only).
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
    com_frame: bool = False

    def __post_init__(self) -> None:
        if (self.qpos is None) == (self.root is None):
            raise GraspError(self.source, self._field("grasp_qpos"), "expected grasp_qpos or qpos, not both")
        if self.com_frame and self.qpos is not None:
            raise GraspError(
                self.source, self._field("qpos"), "the object's frame at its centre of mass needs grasp_qpos"
            )

    def _field(self, key: str) -> str:
        return f"grasp {self.index}: {key}"


def _fail(path: Path, index: int, key: str, problem: str) -> GraspError:
    return GraspError(str(path), f"grasp {index}: {key}", problem)


def _vector(path: Path, index: int, key: str, value: Any, size: int) -> NDArray[np.float64]:
    """``value`` as ``size`` finite real numbers: booleans, complex numbers, dates, strings and
    objects are refused, not converted (``"12"`` is not 12)."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as e:
        raise _fail(path, index, key, f"expected {size} numbers, got {type(value).__name__}") from e
    if raw.dtype.kind not in "iuf":
        raise _fail(path, index, key, f"expected real numbers, got {raw.dtype} data")
    try:
        with warnings.catch_warnings(), np.errstate(all="raise"):
            warnings.simplefilter("error")
            v = raw.astype(np.float64).reshape(-1)
    except (FloatingPointError, RuntimeWarning, OverflowError) as e:
        raise _fail(path, index, key, f"a number beyond float64's range ({raw.dtype})") from e
    if v.size != size:
        raise _fail(path, index, key, f"expected {size} numbers, got {v.size}")
    bad = np.flatnonzero(~np.isfinite(v))
    if bad.size:
        raise _fail(path, index, key, f"expected finite numbers, got {v[bad[0]]} at position {bad[0]}")
    return v


def _pose(path: Path, index: int, key: str, value: Any) -> NDArray[np.float64]:
    v = _vector(path, index, key, value, ROOT_SIZE)
    far = np.flatnonzero(np.abs(v[:3]) > POSITION_BOUND)
    if far.size:
        raise _fail(path, index, key, f"position {v[far[0]]} m beyond {POSITION_BOUND:g} m")
    norm = float(np.linalg.norm(v[3:]))
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise _fail(
            path,
            index,
            key,
            f"expected a unit quaternion [qw, qx, qy, qz] after the position (norm 1 to "
            f"{QUATERNION_TOLERANCE:g}), got norm {norm:.9g}",
        )
    v[3:] /= norm  # a stored quaternion's round-off (float32 data); MuJoCo wants it unit
    return v


def _object_path(path: Path, index: int, text: str) -> str:
    """An object file or folder: absolute, or relative to the dataset's folder or one above it
    (nearest first: DexGraspBench's ``obj_path`` is relative to the benchmark's root, which
    holds its ``output/`` tree of grasps), or to the working directory."""
    given = Path(text)
    tries = (
        [given] if given.is_absolute() else [d / given for d in path.resolve().parents] + [Path.cwd() / given]
    )
    for where in tries:
        if where.is_file() or where.is_dir():
            where = where.resolve()
            if where.is_dir() and not sorted((where / "urdf" / "meshes").glob("*.obj")):
                raise _fail(
                    path, index, "obj_path", f"folder {str(where)!r} has no convex pieces urdf/meshes/*.obj"
                )
            return str(where)
    raise _fail(path, index, "obj_path", f"no such file or folder: {text!r} (from the dataset's folder up)")


def _text(path: Path, index: int, key: str, value: Any) -> str:
    if isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind == "U":
        value = str(value)
    if isinstance(value, np.str_ | str):
        return str(value)
    raise _fail(path, index, key, f"expected a string, got {type(value).__name__}")


def _grasp(
    path: Path,
    index: int,
    values: dict[str, Any],
    *,
    nq: int,
    num_joints: int,
    default_id: str,
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
        if not SCALE_RANGE[0] <= scale <= SCALE_RANGE[1]:
            raise _fail(
                path,
                index,
                "obj_scale",
                f"expected a scale factor in [{SCALE_RANGE[0]:g}, {SCALE_RANGE[1]:g}], got {scale:g}",
            )
    obj_path = None
    if values.get("obj_path") is not None:
        text = _text(path, index, "obj_path", values["obj_path"])
        obj_path = _object_path(path, index, text) if text else None
    given = values.get("id")
    return DatasetGrasp(
        id=default_id if given is None or given == "" else _text(path, index, "id", given),
        source=str(path),
        index=index,
        qpos=qpos,
        root=root,
        joints=joints,
        obj_pose=pose,
        obj_scale=scale,
        obj_path=obj_path,
    )


def _rows_npz(path: Path) -> Sequence[dict[str, Any]]:
    arrays = load_npz(path)
    if not arrays:
        raise GraspError(str(path), "", "no arrays in the file: expected grasp_qpos or qpos")
    counts = {k: len(a) if a.ndim else 1 for k, a in arrays.items()}
    n = counts.get("grasp_qpos", counts.get("qpos", counts.get("pregrasp_qpos", counts.get("squeeze_qpos"))))
    if n is None:
        raise _fail(path, 0, "grasp_qpos", "missing: expected an array grasp_qpos (N, 7 + J) or qpos (N, nq)")
    for k, c in counts.items():
        if c != n or arrays[k].ndim == 0:
            raise GraspError(str(path), k, f"expected {n} rows (one per grasp), got {c}")
    return _NpzRows(arrays, n)


class _NpzRows(Sequence[dict[str, Any]]):
    """The per-grasp rows of an ``.npz``'s arrays, each made when it is read (a row is a dict
    of views into the arrays: the file's numbers are held once, not a dict per grasp)."""

    def __init__(self, arrays: dict[str, NDArray[Any]], n: int) -> None:
        self.arrays, self.n = arrays, n

    def __len__(self) -> int:
        return self.n

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(self.n))]
        return {k: a[i] for k, a in self.arrays.items()}


def _rows_npy(path: Path, key: str | None) -> tuple[list[dict[str, Any]], bool]:
    """The rows and whether the file is one per-grasp dict."""
    value = load_npy(path)
    if isinstance(value, dict):
        return [value], True
    if isinstance(value, list):
        for i, item in enumerate(value):
            if not isinstance(item, dict):
                raise _fail(path, i, "", f"expected a list of per-grasp dicts, got a {type(item).__name__}")
        return list(value), False
    if not isinstance(value, np.ndarray) or value.ndim != 2:
        shape = getattr(value, "shape", None)
        raise GraspError(
            str(path), "", f"expected a 2-D array (grasps x numbers) or pickled dicts, got shape {shape}"
        )
    if key is None:
        raise GraspError(
            str(path),
            "",
            f"a {value.shape[0]} x {value.shape[1]} array's meaning is not stated: "
            "give --dataset-key grasp_qpos (root pose + hand joints) or qpos (the model's qpos)",
        )
    return [{key: row} for row in value], False


def _natural(p: Path) -> list[Any]:
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", p.as_posix())]


def dataset_files(paths: Sequence[str | Path]) -> list[Path]:
    """The dataset files of ``paths``: a file as given, a folder as its ``.npz``, ``.npy`` and
    ``.csv`` files at any depth, in natural order (``2.npy`` before ``10.npy``).

    Raises
    ------
    GraspError
        A folder without dataset files.
    """
    out: list[Path] = []
    for given in paths:
        p = Path(given)
        if p.is_dir():
            found = sorted(
                (f for f in p.rglob("*") if f.suffix.lower() in _SUFFIXES and f.is_file()), key=_natural
            )
            if not found:
                raise GraspError(str(p), "", "a folder without .npz, .npy or .csv dataset files")
            out.extend(found)
        else:
            out.append(p)
    return out


def read_dataset(
    path: str | Path,
    *,
    nq: int,
    num_joints: int,
    pose: str = "grasp",
    key: str | None = None,
    joint_names: Sequence[str] = (),
    label: str | None = None,
) -> list[DatasetGrasp]:
    r"""The grasps of one dataset file (``.npz``, ``.npy`` or ``.csv``; layouts in the module's doc).

    Parameters
    ----------
    path
        The file.
    nq
        The model's ``nq`` (the width of ``qpos``).
    num_joints
        ``J``: the hand's joints (`hand_joints()`): ``grasp_qpos`` has ``7 + J`` numbers.
    pose
        ``grasp``, ``pregrasp`` or ``squeeze``: the pipeline pose ranked (``<pose>_qpos``).
    key
        What a 2-D ``.npy`` array holds: ``grasp_qpos`` or ``qpos`` (required for that layout).
    joint_names
        The hand's joints by name (``J`` of them), for DexGraspNet's ``qpos`` dicts.
    label
        The file's name in default ids (``<label>:<index>``, ``<label>`` for a per-grasp
        dict); default: the file's stem.

    Raises
    ------
    GraspError
        An unreadable or unsafe file, or a grasp with a missing, misshapen, non-real or
        non-finite field: ``FILE: grasp I: FIELD: problem``.
    """
    return list(
        iter_dataset(
            path, nq=nq, num_joints=num_joints, pose=pose, key=key, joint_names=joint_names, label=label
        )
    )


def iter_dataset(
    path: str | Path,
    *,
    nq: int,
    num_joints: int,
    pose: str = "grasp",
    key: str | None = None,
    joint_names: Sequence[str] = (),
    label: str | None = None,
) -> Iterator[DatasetGrasp]:
    """[`read_dataset()`][mjtvm.grasp.document.dataset.read_dataset] one grasp at a time: the
    file is read (and refused) at the first ``next()``, each grasp made and checked when it is
    reached (a file's numbers are held once, not a grasp object each).

    Raises
    ------
    GraspError
        As [`read_dataset()`][mjtvm.grasp.document.dataset.read_dataset], from ``next()``.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if pose not in POSES:
        raise GraspError(str(p), "pose", f"expected one of {', '.join(POSES)}, got {pose!r}")
    if key not in (None, "grasp_qpos", "qpos"):
        raise GraspError(str(p), "key", f"expected grasp_qpos or qpos, got {key!r}")
    if not p.is_file():
        raise GraspError(str(p), "", "no such dataset file")
    single = False
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a library's warning is the file's problem, not stderr's
            if suffix == ".npz":
                rows = _rows_npz(p)
            elif suffix == ".npy":
                rows, single = _rows_npy(p, key)
            elif suffix == ".csv":
                rows = csv_rows(p)
            else:
                raise GraspError(
                    str(p), "", f"expected a .npz, .npy or .csv dataset, got {suffix or 'no suffix'!r}"
                )
    except GraspError:
        raise
    # A damaged pickle or zip, an over-long CSV field, an unsafe pickle, a stray warning:
    except (
        OSError,
        ValueError,
        EOFError,
        pickle.UnpicklingError,
        csv.Error,
        AttributeError,
        ImportError,
        TypeError,
        IndexError,
        MemoryError,
        Warning,
    ) as e:
        raise GraspError(str(p), "", f"cannot read the dataset ({' '.join(str(e).split())[:200]})") from e
    if not rows:
        raise GraspError(str(p), "", "no grasps in the file")
    name = p.stem if label is None else label
    for i, row in enumerate(rows):
        try:
            values = pipeline_row(row, pose=pose, joint_names=joint_names)
        except PipelineKeyError as e:
            raise _fail(p, i, e.key, e.problem) from None
        yield _grasp(p, i, values, nq=nq, num_joints=num_joints, default_id=name if single else f"{name}:{i}")
