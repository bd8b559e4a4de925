r"""The hand's and the object's geometry as plain arrays, for drawing without MuJoCo.

[`scene_geometry()`][mjtvm.grasp.scene.scene_geometry] reads a model's drawable geoms once: the capsules (links), the spheres
on the hand (tips) and on the object, the planes (the palm), with their sizes, colours,
names and (planes) fixed positions, and the colliding mesh geoms (an object's convex pieces)
with their vertices and triangles. [`scene_poses()`][mjtvm.grasp.scene.scene_poses] runs MuJoCo's forward kinematics at
each configuration and returns the geoms' world poses. The viewer
([`viz`][mjtvm.viewer.viz]) draws from these alone, so MuJoCo stays in the coupling layer.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import ParamError

__all__ = ["GeomGroup", "MeshGroup", "SceneGeometry", "ScenePoses", "scene_geometry", "scene_poses"]


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
class MeshGroup:
    """Mesh geoms, each with its own triangles (MuJoCo's units: m, RGBA in [0, 1]).

    Attributes
    ----------
    ids
        ``(n,)`` the geom indices in the model.
    names
        The geom names (``""`` where unnamed).
    rgba
        ``(n, 4)`` colours.
    vertices
        Per geom, ``(V, 3)`` its mesh's vertices in the geom's frame (``mesh_vert``: MuJoCo
        places the mesh frame at the geom's pose).
    triangles
        Per geom, ``(T, 3)`` vertex indices (``mesh_face``).
    """

    ids: NDArray[np.int64]
    names: tuple[str, ...]
    rgba: NDArray[np.float32]
    vertices: tuple[NDArray[np.float64], ...]
    triangles: tuple[NDArray[np.int64], ...]

    def __post_init__(self) -> None:
        n = len(self.ids)
        lengths = (len(self.names), len(self.vertices), len(self.triangles), len(self.rgba))
        if any(k != n for k in lengths):
            raise ParamError(
                "MeshGroup", f"expected {n} names, vertex arrays, triangle arrays and colours", lengths
            )

    def __len__(self) -> int:
        return len(self.ids)


@dataclass(frozen=True, eq=False)
class SceneGeometry:
    """The drawable geoms of a hand and its object: capsule ``links``, sphere ``tips`` (not on the
    object), sphere ``object`` geoms, ``planes``, and colliding ``meshes`` (hand or object),
    with the ``object_body`` id."""

    links: GeomGroup
    tips: GeomGroup
    object: GeomGroup
    planes: GeomGroup
    meshes: MeshGroup
    object_body: int


@dataclass(frozen=True, eq=False)
class ScenePoses:
    """World poses of the geoms of a [`SceneGeometry`][mjtvm.grasp.scene.SceneGeometry] at ``S`` configurations.

    Attributes
    ----------
    link_pos, link_quat, link_axis
        ``(S, links, 3)`` capsule centres, ``(S, links, 4)`` orientations (MuJoCo's ``w, x, y,
        z``), ``(S, links, 3)`` capsule axes (the geom frame's z).
    tip_pos, object_pos
        ``(S, tips, 3)``, ``(S, objects, 3)`` sphere centres.
    mesh_pos, mesh_quat
        ``(S, meshes, 3)`` mesh geom origins, ``(S, meshes, 4)`` orientations (``w, x, y, z``).
    object_origin
        ``(S, 3)`` the object body's origin (whatever its geoms).
    """

    link_pos: NDArray[np.float64]
    link_quat: NDArray[np.float64]
    link_axis: NDArray[np.float64]
    tip_pos: NDArray[np.float64]
    object_pos: NDArray[np.float64]
    mesh_pos: NDArray[np.float64]
    mesh_quat: NDArray[np.float64]
    object_origin: NDArray[np.float64]


def _group(model: mujoco.MjModel, ids: list[int]) -> GeomGroup:
    idx = np.asarray(ids, dtype=np.int64)
    return GeomGroup(
        ids=idx,
        names=tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or "" for g in ids),
        size=np.array(model.geom_size[idx], dtype=float).reshape(-1, 3),
        rgba=np.array(model.geom_rgba[idx], dtype=np.float32).reshape(-1, 4),
        pos=np.array(model.geom_pos[idx], dtype=float).reshape(-1, 3),
    )


def _meshes(model: mujoco.MjModel, ids: list[int]) -> MeshGroup:
    verts, tris = [], []
    for g in ids:
        k = int(model.geom_dataid[g])
        v0, nv = int(model.mesh_vertadr[k]), int(model.mesh_vertnum[k])
        f0, nf = int(model.mesh_faceadr[k]), int(model.mesh_facenum[k])
        verts.append(np.array(model.mesh_vert[v0 : v0 + nv], dtype=float))
        tris.append(np.array(model.mesh_face[f0 : f0 + nf], dtype=np.int64))
    idx = np.asarray(ids, dtype=np.int64)
    return MeshGroup(
        ids=idx,
        names=tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or "" for g in ids),
        rgba=np.array(model.geom_rgba[idx], dtype=np.float32).reshape(-1, 4),
        vertices=tuple(verts),
        triangles=tuple(tris),
    )


def scene_geometry(model: mujoco.MjModel, object_body: str) -> SceneGeometry:
    """The capsules, spheres (split by whether ``object_body`` carries them), planes and
    colliding meshes (``contype`` or ``conaffinity`` non-zero: visual meshes are left out) of
    ``model``."""
    ob = model.body(object_body).id
    kind = [int(model.geom_type[g]) for g in range(model.ngeom)]
    spheres = [g for g in range(model.ngeom) if kind[g] == mujoco.mjtGeom.mjGEOM_SPHERE]
    meshes = [
        g
        for g in range(model.ngeom)
        if kind[g] == mujoco.mjtGeom.mjGEOM_MESH and (model.geom_contype[g] or model.geom_conaffinity[g])
    ]
    return SceneGeometry(
        links=_group(model, [g for g in range(model.ngeom) if kind[g] == mujoco.mjtGeom.mjGEOM_CAPSULE]),
        tips=_group(model, [g for g in spheres if model.geom_bodyid[g] != ob]),
        object=_group(model, [g for g in spheres if model.geom_bodyid[g] == ob]),
        planes=_group(model, [g for g in range(model.ngeom) if kind[g] == mujoco.mjtGeom.mjGEOM_PLANE]),
        meshes=_meshes(model, meshes),
        object_body=int(ob),
    )


def scene_poses(model: mujoco.MjModel, geometry: SceneGeometry, qpos: ArrayLike) -> ScenePoses:
    """The geoms' world poses at each row of ``qpos`` (``(S, nq)``), by MuJoCo's forward kinematics."""
    configurations = np.atleast_2d(np.asarray(qpos, dtype=float))
    data = mujoco.MjData(model)
    links, tips, obj = geometry.links.ids, geometry.tips.ids, geometry.object.ids
    meshes = geometry.meshes.ids
    n = len(configurations)
    out = ScenePoses(
        link_pos=np.zeros((n, len(links), 3)),
        link_quat=np.zeros((n, len(links), 4)),
        link_axis=np.zeros((n, len(links), 3)),
        tip_pos=np.zeros((n, len(tips), 3)),
        object_pos=np.zeros((n, len(obj), 3)),
        mesh_pos=np.zeros((n, len(meshes), 3)),
        mesh_quat=np.zeros((n, len(meshes), 4)),
        object_origin=np.zeros((n, 3)),
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
        for quat, g in zip(out.mesh_quat[i], meshes, strict=True):
            mujoco.mju_mat2Quat(quat, data.geom_xmat[g])
        out.mesh_pos[i] = data.geom_xpos[meshes]
        out.object_origin[i] = data.xpos[geometry.object_body]
    return out
