r"""What a dataset ranking reads and depends on: the dataset files' grasps, checked against
the grasp file's model in a first pass ([`scan_datasets()`][mjtvm.jobs.rank_inputs.scan_datasets])
and read again one file at a time ([`iter_datasets()`][mjtvm.jobs.rank_inputs.iter_datasets];
[`read_datasets()`][mjtvm.jobs.rank_inputs.read_datasets]: all of them as a list), their default ids
(`dataset_labels()`), and the digest that ``--resume`` matches
([`inputs_digest()`][mjtvm.jobs.rank_inputs.inputs_digest]).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from mjtvm.grasp import GraspError
from mjtvm.grasp.document.dataset import DatasetGrasp, dataset_files, iter_dataset
from mjtvm.grasp.resolve.batch import hand_joints
from mjtvm.grasp.resolve.objects import check_joint_ranges
from mjtvm.jobs.files import model_files
from mjtvm.jobs.rank import batch_models
from mjtvm.jobs.rank_log import IdSet, id_hash

__all__ = [
    "DatasetScan",
    "dataset_labels",
    "inputs_digest",
    "iter_datasets",
    "read_datasets",
    "scan_datasets",
]


def dataset_labels(files: Sequence[Path]) -> list[str]:
    """Each file's name in default ids: its stem, or, when stems repeat (``0.npy`` in every
    folder of a pipeline's tree), its path relative to the files' common folder, suffix dropped."""
    stems = [f.stem for f in files]
    if len(set(stems)) == len(stems):
        return stems
    resolved = [f.resolve() for f in files]
    common = Path(os.path.commonpath([r.parent for r in resolved]))
    return [r.relative_to(common).with_suffix("").as_posix() for r in resolved]


@dataclass(frozen=True, eq=False)
class DatasetScan:
    """What a first pass over the datasets found (`scan_datasets()`): every grasp checked,
    nothing of them kept but their ids' digests, so that a dataset of any size is checked
    before the first grasp is evaluated and then read again one file at a time
    (`iter_datasets()`).

    Attributes
    ----------
    grasp, datasets, pose, key, com_frame
        As given to `scan_datasets()`.
    files, labels
        The dataset files in order, and each file's name in default ids (`dataset_labels()`).
    ids
        The grasps' ids ([`IdSet`][mjtvm.jobs.rank_log.IdSet]), each numbered by its position
        in the datasets (from 0).
    objects
        The distinct object files or folders the grasps name (``obj_path``), sorted.
    """

    grasp: str
    datasets: tuple[str, ...]
    pose: str
    key: str | None
    com_frame: bool
    files: tuple[Path, ...]
    labels: tuple[str, ...]
    ids: IdSet
    objects: tuple[str, ...]

    def __len__(self) -> int:
        return len(self.ids)


def _file_grasps(
    model: Any, joints: Sequence[str], path: Path, label: str, pose: str, key: str | None, com_frame: bool
) -> Iterator[DatasetGrasp]:
    """The grasps of one dataset file, each checked against the model as it is read."""
    for e in iter_dataset(
        path, nq=int(model.nq), num_joints=len(joints), pose=pose, key=key, joint_names=joints, label=label
    ):
        check_joint_ranges(model, joints, e)
        yield replace(e, com_frame=True) if com_frame else e


def _hand(grasp: str) -> tuple[Any, Sequence[str]]:
    batch = batch_models(grasp)
    if batch.doc["rvds"] is None:
        raise GraspError(batch.file, "rvds", "mjtvm rank solves Problem 2 (TVMMP): give the RVDS vertices")
    model = batch.model()
    try:
        return model, hand_joints(model, batch.doc["object"]["body"])
    except KeyError as missing:
        raise GraspError(
            batch.file, "object.body", f"{batch.doc['object']['body']!r} is not a body of the model"
        ) from missing


def scan_datasets(
    grasp: str,
    datasets: Sequence[str],
    *,
    pose: str = "grasp",
    key: str | None = None,
    com_frame: bool = False,
) -> DatasetScan:
    """Check every grasp of the datasets (files, or folders of them: `dataset_files()`)
    against the grasp file's model: shapes, dtypes, poses, joint ranges, unique ids. One
    file's numbers are held at a time, and one grasp object.

    Raises
    ------
    GraspError
        A malformed grasp (naming its file, index and field), an id used twice, a grasp file
        without RVDS, or a root pose (``grasp_qpos``) for a model whose hand root cannot be
        found or posed.
    """
    model, joints = _hand(grasp)
    files = dataset_files(datasets)
    labels = dataset_labels(files)
    hashes: list[int] = []
    objects: set[str] = set()
    rooted = False
    for path, label in zip(files, labels, strict=True):
        for e in _file_grasps(model, joints, path, label, pose, key, com_frame):
            hashes.append(id_hash(e.id))
            rooted = rooted or e.root is not None
            if e.obj_path is not None:
                objects.add(str(e.obj_path))
    ids = IdSet(hashes)
    del hashes
    scan = DatasetScan(
        grasp, tuple(datasets), pose, key, com_frame, tuple(files), tuple(labels), ids, tuple(sorted(objects))
    )
    if len(ids.repeated()):
        _twice(scan, model, joints, {int(h) for h in ids.repeated()})
    if rooted:
        batch_models(grasp).model(root=True)  # a hand root that cannot be posed is the command's error
    return scan


def _twice(scan: DatasetScan, model: Any, joints: Sequence[str], repeated: set[int]) -> None:
    """Name the first id used twice (its digest is in ``repeated``)."""
    seen: dict[str, DatasetGrasp] = {}
    by_hash: dict[int, str] = {}
    for e in _iter(scan, model, joints):
        h = id_hash(e.id)
        if h not in repeated:
            continue
        if e.id in seen:
            first = seen[e.id]
            raise GraspError(
                e.source, f"grasp {e.index}: id", f"{e.id!r} is also grasp {first.index} of {first.source}"
            )
        if h in by_hash:  # two ids, one 64-bit digest: odds of about n^2 / 2^65
            raise GraspError(
                e.source, f"grasp {e.index}: id", f"{e.id!r} and {by_hash[h]!r} share a digest: rename one"
            )
        seen[e.id], by_hash[h] = e, e.id


def _iter(scan: DatasetScan, model: Any, joints: Sequence[str]) -> Iterator[DatasetGrasp]:
    for path, label in zip(scan.files, scan.labels, strict=True):
        yield from _file_grasps(model, joints, path, label, scan.pose, scan.key, scan.com_frame)


def iter_datasets(scan: DatasetScan) -> Iterator[DatasetGrasp]:
    """The grasps of a scan, in order, read again one file at a time."""
    model, joints = _hand(scan.grasp)
    yield from _iter(scan, model, joints)


def read_datasets(
    grasp: str,
    datasets: Sequence[str],
    *,
    pose: str = "grasp",
    key: str | None = None,
    com_frame: bool = False,
) -> list[DatasetGrasp]:
    """Every grasp of the datasets, checked (`scan_datasets()`), as a list.

    Raises
    ------
    GraspError
        As `scan_datasets()`.
    """
    return list(iter_datasets(scan_datasets(grasp, datasets, pose=pose, key=key, com_frame=com_frame)))


def inputs_digest(
    grasp: str,
    datasets: Sequence[str],
    objects: Iterable[str] = (),
    limit_horizon: float | None = None,
    *,
    pose: str = "grasp",
    key: str | None = None,
    com_frame: bool = False,
    refuse_penetration: bool = False,
    measures: str = "classic",
    verify: bool = False,
    hold_time: float | None = None,
) -> str:
    """A digest of what the rows depend on: mjtvm's version, the grasp file, its model's files,
    the dataset files, the object files they name (``objects``: `DatasetScan.objects`), a ``limit_horizon`` other than the grasp
    file's, ``refuse_penetration``, ``measures``, and ``verify`` with its ``hold_time`` and the simulation's protocol (`grasp_sim.protocol()`). ``--resume`` keeps a row only if its
    ``inputs`` equals this (``--sort`` orders the files, not the rows: not in it)."""
    from mjtvm import __version__

    batch = batch_models(grasp)
    h = hashlib.sha256(f"mjtvm {__version__}\n".encode())
    if limit_horizon is not None:  # None: the digest of earlier versions, whose rows had the file's
        h.update(f"limit_horizon {float(limit_horizon)!r}\n".encode())
    if (pose, key) != ("grasp", None):  # the defaults: the digest of earlier versions
        h.update(f"pose {pose} key {key}\n".encode())
    if com_frame:
        h.update(b"com_frame\n")
    h.update(f"refuse_penetration {bool(refuse_penetration)}\nmeasures {measures}\n".encode())
    if verify:  # not verified: the digest of earlier versions
        from mjtvm.physics.grasp_sim import protocol

        h.update(f"verify hold_time {hold_time!r}\n{protocol()}\n".encode())
    h.update(json.dumps(dict(batch.doc), sort_keys=True, default=str).encode())
    objects = sorted(set(objects))
    files = model_files(batch.model_path) + dataset_files(datasets)
    for p in objects:  # an object folder: its convex pieces
        where = Path(p)
        files += sorted((where / "urdf" / "meshes").glob("*.obj")) if where.is_dir() else model_files(where)
    for path in files:
        h.update(f"{path.name}\n".encode())
        h.update(hashlib.sha256(path.read_bytes()).digest())
    return h.hexdigest()[:32]
