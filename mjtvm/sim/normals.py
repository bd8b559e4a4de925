r"""Exact surface normals of an object's primitive geom at a contact point.

MuJoCo computes contact normals in closed form for pairs with a dedicated collision function
(sphere, capsule and plane pairs, sphere-box, box-box, ...) but by its iterative convex
collision (GJK/EPA, ``opt.ccd_tolerance`` 1e-6) for the others, e.g. a cylinder, an ellipsoid
or a box against a box-, cylinder- or ellipsoid-tipped finger. Where two such surfaces
touch within a micrometre, the normal is the direction between two nearly equal witness
points and is off by up to a few 1e-3 (measured: 4e-3 for an ellipsoid fingertip on a
cylinder's side). :func:`object_normal` gives the exact normal of a sphere, capsule, box,
cylinder or ellipsoid object at the contact point; the grasp state uses it for every pair
MuJoCo may collide iteratively (:func:`needs_exact_normal`). World frame.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

__all__ = ["ITERATIVE_TYPES", "needs_exact_normal", "object_normal"]

_G = mujoco.mjtGeom
#: Geom types whose pairs MuJoCo may collide iteratively (GJK/EPA).
ITERATIVE_TYPES = (int(_G.mjGEOM_BOX), int(_G.mjGEOM_CYLINDER), int(_G.mjGEOM_ELLIPSOID))
_OBJECT_TYPES = (*ITERATIVE_TYPES, int(_G.mjGEOM_SPHERE), int(_G.mjGEOM_CAPSULE))


def needs_exact_normal(model: mujoco.MjModel, object_geom: int, other_geom: int) -> bool:
    """Whether the pair's MuJoCo normal may come from GJK/EPA (either geom a box, cylinder or
    ellipsoid) while :func:`object_normal` knows the object's shape. Sphere, capsule and plane
    pairs keep MuJoCo's closed-form normals (bit for bit)."""
    kinds = {int(model.geom_type[object_geom]), int(model.geom_type[other_geom])}
    return int(model.geom_type[object_geom]) in _OBJECT_TYPES and bool(kinds & set(ITERATIVE_TYPES))


def object_normal(
    model: mujoco.MjModel, data: mujoco.MjData, geom: int, point: NDArray[np.float64]
) -> NDArray[np.float64]:
    r"""``(3,)`` outward unit normal of object geom ``geom`` at ``point``.

    ``point`` (m, world) is a contact point on or within a small distance of the surface. In
    the geom frame, with half-sizes ``a``: a box's normal is that of the face whose plane is
    nearest to the point (relative to its half-size); a cylinder's the radial direction or
    the cap's axis, whichever surface is nearer; a sphere's and a capsule's the direction from
    the centre or the nearest axis point; an ellipsoid's the gradient
    :math:`(x/a_x^2, y/a_y^2, z/a_z^2)` at the point scaled onto the surface.
    """
    rot = np.array(data.geom_xmat[geom], dtype=float).reshape(3, 3)
    local = rot.T @ (np.asarray(point, dtype=float) - np.array(data.geom_xpos[geom], dtype=float))
    size = np.array(model.geom_size[geom], dtype=float)
    kind = int(model.geom_type[geom])
    n = np.zeros(3)
    if kind == int(_G.mjGEOM_BOX):
        k = int(np.argmax(np.abs(local) - size))  # the face the point is nearest to (or beyond)
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
        raise ValueError(f"geom type {kind} has no exact normal here")
    return rot @ n
