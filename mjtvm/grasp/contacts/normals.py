r"""Exact surface normals of an object's primitive geom at a contact point.

MuJoCo computes contact normals in closed form for pairs with a dedicated collision function
(sphere, capsule and plane pairs, sphere-box, box-box, ...) but by its iterative convex
collision (GJK/EPA, ``opt.ccd_tolerance`` 1e-6) for the others, e.g. a cylinder, an ellipsoid
or a box against a box-, cylinder- or ellipsoid-tipped finger. Where two such surfaces
touch within a micrometre, the normal is the direction between two nearly equal witness
points and is off by up to a few 1e-3 (measured: 4e-3 for an ellipsoid fingertip on a
cylinder's side). [`object_normal()`][mjtvm.grasp.contacts.normals.object_normal] gives the exact normal of a sphere, capsule, box,
cylinder or ellipsoid object at the contact point; the grasp state uses it for every pair
MuJoCo may collide iteratively ([`needs_exact_normal()`][mjtvm.grasp.contacts.normals.needs_exact_normal]). World frame.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError

__all__ = ["CLOSED_FORM", "needs_exact_normal", "object_normal"]

_G = mujoco.mjtGeom
_S, _C, _E, _Y, _B, _P = (
    int(_G.mjGEOM_SPHERE),
    int(_G.mjGEOM_CAPSULE),
    int(_G.mjGEOM_ELLIPSOID),
    int(_G.mjGEOM_CYLINDER),
    int(_G.mjGEOM_BOX),
    int(_G.mjGEOM_PLANE),
)
#: Primitive pairs MuJoCo collides in closed form (engine_collision_driver's table): every plane
#: pair, sphere with sphere, capsule, cylinder or box, capsule with capsule or box, box with box.
CLOSED_FORM = {frozenset(p) for p in ((_S, _S), (_S, _C), (_S, _Y), (_S, _B), (_C, _C), (_C, _B), (_B, _B))}
_OBJECT_TYPES = (_S, _C, _E, _Y, _B)


def needs_exact_normal(model: mujoco.MjModel, object_geom: int, other_geom: int) -> bool:
    """Whether the pair is collided iteratively (GJK/EPA) while [`object_normal()`][mjtvm.grasp.contacts.normals.object_normal] knows the
    object's shape: an ellipsoid, or a cylinder with a capsule, cylinder or box. Closed-form
    pairs keep MuJoCo's normals, bit for bit."""
    a, b = int(model.geom_type[object_geom]), int(model.geom_type[other_geom])
    if a not in _OBJECT_TYPES or _P in (a, b) or b > _B:  # plane pairs are closed-form; meshes: as MuJoCo
        return False
    return frozenset((a, b)) not in CLOSED_FORM


def object_normal(
    model: mujoco.MjModel, data: mujoco.MjData, geom: int, point: NDArray[np.float64]
) -> NDArray[np.float64] | None:
    r"""``(3,)`` outward unit normal of object geom ``geom`` at ``point`` (``None`` on a box's
    edge or corner, where it is not unique).

    ``point`` (m, world) is a contact point on or within a small distance of the surface. In
    the geom frame, with half-sizes ``a``: a box's normal is that of the face whose plane is
    nearest to the point (relative to its half-size); a cylinder's the radial direction or
    the cap's axis, whichever surface is nearer; a sphere's and a capsule's the direction from
    the centre or the nearest axis point; an ellipsoid's the gradient
    $(x/a_x^2, y/a_y^2, z/a_z^2)$ at the point scaled onto the surface.
    """
    rot = np.array(data.geom_xmat[geom], dtype=float).reshape(3, 3)
    local = rot.T @ (np.asarray(point, dtype=float) - np.array(data.geom_xpos[geom], dtype=float))
    size = np.array(model.geom_size[geom], dtype=float)
    kind = int(model.geom_type[geom])
    n = np.zeros(3)
    if kind == int(_G.mjGEOM_BOX):
        excess = np.abs(local) - size  # per axis, how far beyond (or inside) its pair of faces
        k = int(np.argmax(excess))
        if np.sort(excess)[-2] >= excess[k] - 1e-9 * float(np.max(size)):
            return None  # an edge or a corner: no unique face normal
        n[k] = np.sign(local[k]) or 1.0
    elif kind == int(_G.mjGEOM_CYLINDER):
        radial = float(np.hypot(local[0], local[1]))
        if radial - size[0] >= abs(local[2]) - size[1] and radial > 0:
            n[:2] = local[:2] / radial
        else:
            n[2] = np.sign(local[2]) or 1.0
    elif kind == int(_G.mjGEOM_SPHERE):
        n = local / np.linalg.norm(local)
    elif kind == int(_G.mjGEOM_CAPSULE):
        axis_point = np.array([0.0, 0.0, float(np.clip(local[2], -size[1], size[1]))])
        n = (local - axis_point) / np.linalg.norm(local - axis_point)
    elif kind == int(_G.mjGEOM_ELLIPSOID):
        scaled = local / np.linalg.norm(local / size)  # onto the surface along the ray from the centre
        n = scaled / size**2
        n /= np.linalg.norm(n)
    else:
        raise ModelError(
            f"geom #{geom}", f"type {kind} has no exact normal (sphere, capsule, box, cylinder or ellipsoid)"
        )
    return rot @ n
