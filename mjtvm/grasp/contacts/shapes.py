r"""Every colliding geom of a grasp as plain arrays (type, size, world pose, colour; a mesh's
vertices and faces), for drawing a grasp without MuJoCo (``mjtvm show``,
[`mjtvm.viewer.grasp_view`][mjtvm.viewer.grasp_view]). World frame, m; quaternions ``(w, x, y, z)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.grasp.contacts.touch import geom_label, subtree

__all__ = ["GeomShape", "geom_shapes"]

_KINDS = {
    int(mujoco.mjtGeom.mjGEOM_PLANE): "plane",
    int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
    int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule",
    int(mujoco.mjtGeom.mjGEOM_ELLIPSOID): "ellipsoid",
    int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder",
    int(mujoco.mjtGeom.mjGEOM_BOX): "box",
    int(mujoco.mjtGeom.mjGEOM_MESH): "mesh",
}


@dataclass(frozen=True, eq=False)
class GeomShape:
    r"""One geom, posed.

    Attributes
    ----------
    label
        `geom_label()`.
    kind
        ``"plane"``, ``"sphere"``, ``"capsule"``, ``"ellipsoid"``, ``"cylinder"``, ``"box"`` or ``"mesh"``.
    size
        ``(3,)`` MuJoCo's ``geom_size`` (m): radius, half-length or half-sizes by kind.
    position, quaternion
        ``(3,)`` the geom frame's origin, ``(4,)`` its orientation (w, x, y, z), world.
    rgba
        ``(4,)`` colour in [0, 1].
    on_object
        Whether the geom belongs to the object.
    vertices, faces
        A mesh's ``(V, 3)`` vertices in the geom frame (m) and ``(F, 3)`` triangles; ``None``
        for the other kinds.
    """

    label: str
    kind: str
    size: NDArray[np.float64]
    position: NDArray[np.float64]
    quaternion: NDArray[np.float64]
    rgba: NDArray[np.float64]
    on_object: bool
    vertices: NDArray[np.float64] | None = None
    faces: NDArray[np.int64] | None = None


def geom_shapes(model: mujoco.MjModel, data: mujoco.MjData, object_body: str) -> tuple[GeomShape, ...]:
    """The geoms that can collide (``contype`` or ``conaffinity`` non-zero) of a kind in
    ``_KINDS`` (height fields and SDFs are left out), at the poses of ``data`` (after
    ``mj_kinematics``)."""
    inside = subtree(model, model.body(object_body).id)
    out = []
    for g in range(model.ngeom):
        kind = _KINDS.get(int(model.geom_type[g]))
        if kind is None or not (model.geom_contype[g] or model.geom_conaffinity[g]):
            continue
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, data.geom_xmat[g])
        vertices = faces = None
        if kind == "mesh":
            m = int(model.geom_dataid[g])
            v0, nv = int(model.mesh_vertadr[m]), int(model.mesh_vertnum[m])
            f0, nf = int(model.mesh_faceadr[m]), int(model.mesh_facenum[m])
            vertices = np.array(model.mesh_vert[v0 : v0 + nv], dtype=float)
            faces = np.array(model.mesh_face[f0 : f0 + nf], dtype=np.int64)
        out.append(
            GeomShape(
                label=geom_label(model, g),
                kind=kind,
                size=np.array(model.geom_size[g], dtype=float),
                position=np.array(data.geom_xpos[g], dtype=float),
                quaternion=quat,
                rgba=np.array(model.geom_rgba[g], dtype=float),
                on_object=int(model.geom_bodyid[g]) in inside,
                vertices=vertices,
                faces=faces,
            )
        )
    return tuple(out)
