r"""The hand's and the object's geometry as plain arrays, for drawing without MuJoCo.

:func:`scene_geometry` reads a model's drawable geoms once: the capsules (links), the spheres
on the hand (tips) and on the object, and the planes (the palm), with their sizes, colours,
names and (planes) fixed positions. :func:`scene_poses` runs MuJoCo's forward kinematics at
each configuration and returns the geoms' world poses. The viewer
(:mod:`~mjtvm.viewer.viz`) draws from these alone, so MuJoCo stays in the coupling layer.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["GeomGroup", "SceneGeometry", "ScenePoses", "scene_geometry", "scene_poses"]


@dataclass(frozen=True, eq=False)
class GeomGroup:
    """Geoms of one kind (MuJoCo's conventions and units: m, RGBA in [0, 1]).

    Attributes
    ----------
    ids
        ``(n,)`` the geom indices in the model.
    names
        The geom names (``""`` where unnamed).
    size
        ``(n, 3)`` MuJoCo's ``geom_size`` (capsule: radius, half-length; sphere: radius;
        plane: half-extents).
    rgba
        ``(n, 4)`` colours.
    pos
        ``(n, 3)`` positions in the parent body's frame (``geom_pos``).
    """

    ids: NDArray[np.int64]
    names: tuple[str, ...]
    size: NDArray[np.float64]
    rgba: NDArray[np.float32]
    pos: NDArray[np.float64]

    def __len__(self) -> int:
        return len(self.ids)


@dataclass(frozen=True, eq=False)
class SceneGeometry:
    """The drawable geoms of a hand and its object: capsule ``links``, sphere ``tips`` (not on the
    object), sphere ``object`` geoms and ``planes``."""

    links: GeomGroup
    tips: GeomGroup
    object: GeomGroup
    planes: GeomGroup


@dataclass(frozen=True, eq=False)
class ScenePoses:
    """World poses of the geoms of a :class:`SceneGeometry` at ``S`` configurations.

    Attributes
    ----------
    link_pos, link_quat, link_axis
        ``(S, links, 3)`` capsule centres, ``(S, links, 4)`` orientations (MuJoCo's ``w, x, y,
        z``), ``(S, links, 3)`` capsule axes (the geom frame's z).
    tip_pos, object_pos
        ``(S, tips, 3)``, ``(S, objects, 3)`` sphere centres.
    """

    link_pos: NDArray[np.float64]
    link_quat: NDArray[np.float64]
    link_axis: NDArray[np.float64]
    tip_pos: NDArray[np.float64]
    object_pos: NDArray[np.float64]


def _group(model: mujoco.MjModel, ids: list[int]) -> GeomGroup:
    idx = np.asarray(ids, dtype=np.int64)
    return GeomGroup(
        ids=idx,
        names=tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or "" for g in ids),
        size=np.array(model.geom_size[idx], dtype=float).reshape(-1, 3),
        rgba=np.array(model.geom_rgba[idx], dtype=np.float32).reshape(-1, 4),
        pos=np.array(model.geom_pos[idx], dtype=float).reshape(-1, 3),
    )


def scene_geometry(model: mujoco.MjModel, object_body: str) -> SceneGeometry:
    """The capsules, spheres (split by whether ``object_body`` carries them) and planes of ``model``."""
    ob = model.body(object_body).id
    kind = [int(model.geom_type[g]) for g in range(model.ngeom)]
    spheres = [g for g in range(model.ngeom) if kind[g] == mujoco.mjtGeom.mjGEOM_SPHERE]
    return SceneGeometry(
        links=_group(model, [g for g in range(model.ngeom) if kind[g] == mujoco.mjtGeom.mjGEOM_CAPSULE]),
        tips=_group(model, [g for g in spheres if model.geom_bodyid[g] != ob]),
        object=_group(model, [g for g in spheres if model.geom_bodyid[g] == ob]),
        planes=_group(model, [g for g in range(model.ngeom) if kind[g] == mujoco.mjtGeom.mjGEOM_PLANE]),
    )


def scene_poses(model: mujoco.MjModel, geometry: SceneGeometry, qpos: ArrayLike) -> ScenePoses:
    """The geoms' world poses at each row of ``qpos`` (``(S, nq)``), by MuJoCo's forward kinematics."""
    configurations = np.atleast_2d(np.asarray(qpos, dtype=float))
    data = mujoco.MjData(model)
    links, tips, obj = geometry.links.ids, geometry.tips.ids, geometry.object.ids
    n = len(configurations)
    out = ScenePoses(
        link_pos=np.zeros((n, len(links), 3)),
        link_quat=np.zeros((n, len(links), 4)),
        link_axis=np.zeros((n, len(links), 3)),
        tip_pos=np.zeros((n, len(tips), 3)),
        object_pos=np.zeros((n, len(obj), 3)),
    )
    for i, q in enumerate(configurations):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        for quat, g in zip(out.link_quat[i], links, strict=True):
            mujoco.mju_mat2Quat(quat, data.geom_xmat[g])
        out.link_pos[i] = data.geom_xpos[links]
        out.link_axis[i] = data.geom_xmat[links][:, [2, 5, 8]]
        out.tip_pos[i] = data.geom_xpos[tips]
        out.object_pos[i] = data.geom_xpos[obj]
    return out
