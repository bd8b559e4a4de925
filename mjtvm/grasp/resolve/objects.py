r"""Dataset objects and configurations against the model: object folders, joint ranges.

*An object folder* (DexGraspBench's layout, ``src/util/hand_util.py``, ``MjHO._add_object``)
holds the object's convex pieces as ``urdf/meshes/*.obj``; the benchmark makes one body
``object`` on a free joint with a mesh geom per piece, each mesh scaled by ``obj_scale``, and
chooses the density so that the object's mass is its configured ``obj_mass`` at every scale.
[`folder_object()`][mjtvm.grasp.resolve.objects.folder_object] does the same: one collision
geom per piece (``object_collision_<piece>``; the benchmark's visual copies are left out),
scaled, and of the grasp file's object mass.

*Joint ranges.* A dataset's joint value outside its joint's range by more than
[`JOINT_TOLERANCE`][mjtvm.grasp.resolve.objects.JOINT_TOLERANCE] is refused
([`check_joint_ranges()`][mjtvm.grasp.resolve.objects.check_joint_ranges]): synthesized grasps
sit on their limits up to the optimiser's round-off, not beyond.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np

from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.document.dataset import DatasetGrasp

__all__ = [
    "JOINT_TOLERANCE",
    "check_joint_ranges",
    "com_position",
    "folder_object",
    "shift_frame",
    "subtree_mass",
]

JOINT_TOLERANCE = {"hinge": 0.02, "slide": 0.002}
"""How far (rad for a hinge, m for a slide) a dataset's joint may lie outside its range."""

_JNT = mujoco.mjtJoint


def folder_object(folder: str, *, mass: float, scale: float, file: str) -> mujoco.MjSpec:
    """A spec whose one body ``object`` (on a free joint) has the folder's convex pieces.

    Parameters
    ----------
    folder
        The object folder (its pieces in ``urdf/meshes/*.obj``, sorted by name).
    mass
        The object's mass (kg) at this scale (the grasp file's object mass).
    scale
        The pieces' scale factor (``obj_scale``).
    file
        The grasp file, for messages.

    Raises
    ------
    GraspError
        No pieces, a piece MuJoCo cannot load, or pieces without volume.
    """
    pieces = sorted((Path(folder) / "urdf" / "meshes").glob("*.obj"))
    if not pieces:
        raise GraspError(file, "obj_path", f"{folder!r} has no convex pieces urdf/meshes/*.obj")

    def build(density: float) -> mujoco.MjSpec:
        spec = mujoco.MjSpec()
        body = spec.worldbody.add_body(name="object")
        body.add_freejoint(name="object")
        for piece in pieces:
            spec.add_mesh(name=piece.stem, file=str(piece), scale=[scale] * 3)
            body.add_geom(
                name=f"object_collision_{piece.stem.replace('convex_piece_', '')}",
                type=mujoco.mjtGeom.mjGEOM_MESH,
                meshname=piece.stem,
                density=density,
            )
        return spec

    try:
        volume = float(build(1.0).compile().body_mass[1])  # density 1: the mass is the volume
    except ValueError as e:
        raise GraspError(
            file, "obj_path", f"MuJoCo cannot load {folder!r}: {' '.join(str(e).split())}"
        ) from e
    if not volume > 0.0:
        raise GraspError(file, "obj_path", f"the pieces of {folder!r} have no volume")
    return build(mass / volume)


def check_joint_ranges(model: mujoco.MjModel, joints: Sequence[str], entry: DatasetGrasp) -> None:
    """Refuse an entry's joint outside its range by more than ``JOINT_TOLERANCE``.

    Parameters
    ----------
    model
        The compiled model.
    joints
        The hand's joints (``hand_joints``), in ``entry.joints``'s order.
    entry
        The dataset grasp (``joints`` or ``qpos``).

    Raises
    ------
    GraspError
        ``FILE: grasp I: grasp_qpos`` (or ``qpos``) naming the joint, its value and range.
    """
    if entry.joints is not None:
        field = "grasp_qpos"
        items = [(int(model.joint(n).id), float(v)) for n, v in zip(joints, entry.joints, strict=True)]
    else:
        assert entry.qpos is not None
        field = "qpos"
        scalar = (int(_JNT.mjJNT_HINGE), int(_JNT.mjJNT_SLIDE))
        items = [
            (j, float(entry.qpos[int(model.jnt_qposadr[j])]))
            for j in range(model.njnt)
            if int(model.jnt_type[j]) in scalar
        ]
    for j, value in items:
        if not model.jnt_limited[j]:
            continue
        lo, hi = (float(x) for x in model.jnt_range[j])
        kind = "slide" if int(model.jnt_type[j]) == int(_JNT.mjJNT_SLIDE) else "hinge"
        tol = JOINT_TOLERANCE[kind]
        if not lo - tol <= value <= hi + tol:
            unit = "m" if kind == "slide" else "rad"
            raise GraspError(
                entry.source,
                f"grasp {entry.index}: {field}",
                f"joint {model.joint(j).name!r} at {value:.6g} {unit}, outside its range "
                f"[{lo:.6g}, {hi:.6g}] by more than {tol:g} {unit}",
            )


def subtree_mass(model: mujoco.MjModel, body: str) -> float:
    """The mass (kg) of a body and its subtree."""
    return float(np.asarray(model.body_subtreemass)[int(model.body(body).id)])


def shift_frame(spec: mujoco.MjSpec, name: str, offset: np.ndarray) -> None:
    """Move body ``name``'s frame by ``offset`` (its own frame, m), its content staying put:
    its geoms, child bodies and explicit inertia move by ``-offset``."""
    body = spec.body(name)
    for g in body.geoms:
        g.pos = np.asarray(g.pos) - offset
    for child in body.bodies:
        child.pos = np.asarray(child.pos) - offset
    for site in body.sites:
        site.pos = np.asarray(site.pos) - offset
    if body.explicitinertial:
        body.ipos = np.asarray(body.ipos) - offset


def com_position(obj: dict, offset: np.ndarray) -> list[float]:
    """The object's position (m, world) once its frame is moved by ``offset`` (its frame):
    ``p + R(q) offset``."""
    q = np.asarray(obj.get("quaternion", [1.0, 0.0, 0.0, 0.0]), dtype=float)
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, q / np.linalg.norm(q))
    return [float(x) for x in np.asarray(obj["position"], dtype=float) + rot.reshape(3, 3) @ offset]
