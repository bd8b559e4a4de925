r"""What a dataset ranking reads and depends on: the dataset files' grasps, checked against
the grasp file's model ([`read_datasets()`][mjtvm.jobs.rank_inputs.read_datasets]), their default ids
(`dataset_labels()`), and the digest that ``--resume`` matches
([`inputs_digest()`][mjtvm.jobs.rank_inputs.inputs_digest]).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from mjtvm.grasp import GraspError
from mjtvm.grasp.document.dataset import DatasetGrasp, dataset_files, read_dataset
from mjtvm.grasp.resolve.batch import hand_joints
from mjtvm.grasp.resolve.objects import check_joint_ranges
from mjtvm.jobs.files import model_files
from mjtvm.jobs.rank import batch_models

__all__ = ["dataset_labels", "inputs_digest", "read_datasets"]


def dataset_labels(files: Sequence[Path]) -> list[str]:
    """Each file's name in default ids: its stem, or, when stems repeat (``0.npy`` in every
    folder of a pipeline's tree), its path relative to the files' common folder, suffix dropped."""
    stems = [f.stem for f in files]
    if len(set(stems)) == len(stems):
        return stems
    resolved = [f.resolve() for f in files]
    common = Path(os.path.commonpath([r.parent for r in resolved]))
    return [r.relative_to(common).with_suffix("").as_posix() for r in resolved]


def read_datasets(
    grasp: str,
    datasets: Sequence[str],
    *,
    pose: str = "grasp",
    key: str | None = None,
    com_frame: bool = False,
) -> list[DatasetGrasp]:
    """Every grasp of the datasets (files, or folders of them: `dataset_files()`), checked
    against the grasp file's model: shapes, dtypes, poses, joint ranges.

    Raises
    ------
    GraspError
        A malformed grasp (naming its file, index and field), an id used twice, a grasp file
        without RVDS, or a root pose (``grasp_qpos``) for a model whose hand root cannot be
        found or posed.
    """
    batch = batch_models(grasp)
    if batch.doc["rvds"] is None:
        raise GraspError(batch.file, "rvds", "mjtvm rank solves Problem 2 (TVMMP): give the RVDS vertices")
    model = batch.model()
    try:
        joints = hand_joints(model, batch.doc["object"]["body"])
    except KeyError as missing:
        raise GraspError(
            batch.file, "object.body", f"{batch.doc['object']['body']!r} is not a body of the model"
        ) from missing
    entries: list[DatasetGrasp] = []
    seen: dict[str, DatasetGrasp] = {}
    files = dataset_files(datasets)
    for path, label in zip(files, dataset_labels(files), strict=True):
        read = read_dataset(
            path,
            nq=int(model.nq),
            num_joints=len(joints),
            pose=pose,
            key=key,
            joint_names=joints,
            label=label,
        )
        for e in read:
            check_joint_ranges(model, joints, e)
            if com_frame:
                e = replace(e, com_frame=True)
            if e.id in seen:
                first = seen[e.id]
                raise GraspError(
                    e.source,
                    f"grasp {e.index}: id",
                    f"{e.id!r} is also grasp {first.index} of {first.source}",
                )
            seen[e.id] = e
            entries.append(e)
    if any(e.root is not None for e in entries):
        batch.model(root=True)  # a hand root that cannot be posed is the command's error, not every row's
    return entries


def inputs_digest(
    grasp: str,
    datasets: Sequence[str],
    entries: Sequence[DatasetGrasp] = (),
    limit_horizon: float | None = None,
    *,
    pose: str = "grasp",
    key: str | None = None,
    com_frame: bool = False,
    refuse_penetration: bool = False,
    measures: str = "classic",
) -> str:
    """A digest of what the rows depend on: mjtvm's version, the grasp file, its model's files,
    the dataset files, the object files they name, a ``limit_horizon`` other than the grasp
    file's, ``refuse_penetration`` and ``measures``. ``--resume`` keeps a row only if its
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
    h.update(json.dumps(dict(batch.doc), sort_keys=True, default=str).encode())
    objects = sorted({str(e.obj_path) for e in entries if e.obj_path is not None})
    files = model_files(batch.model_path) + dataset_files(datasets)
    for p in objects:  # an object folder: its convex pieces
        where = Path(p)
        files += sorted((where / "urdf" / "meshes").glob("*.obj")) if where.is_dir() else model_files(where)
    for path in files:
        h.update(f"{path.name}\n".encode())
        h.update(hashlib.sha256(path.read_bytes()).digest())
    return h.hexdigest()[:32]
