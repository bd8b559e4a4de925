r"""Nearest points and normals between an object geom and a finger geom (``mj_geomDistance``).

The lift ([`mjtvm.lift.trajectory`][mjtvm.lift.trajectory]) keeps fingers on the object's surface; it needs, for a
pair (object geom, finger geom), the signed surface distance, the two
*witness points* (the nearest points, or the deepest ones when the geoms penetrate) and the
contact normal. MuJoCo's ``mj_geomDistance`` gives the distance and the witness points; its
normal is the direction between them, which is undefined when the surfaces touch (the case
the lift lives in). [`witness()`][mjtvm.lift.surface.witness] therefore backs the finger geom off along a guess of the
normal (by [`BACKOFF`][mjtvm.lift.surface.BACKOFF], in a scratch copy of its pose) and queries again: for smooth
surfaces the witness pair is unchanged by a shift along the common normal, so the direction
between the backed-off witnesses is the normal, and two or three shifts make the guess exact.

A sphere fingertip on a sphere object is done in closed form (radial projection), so that
the paper's Case 2 keeps today's arithmetic to the last bit.

World frame, m. Normals point *into the object* (from the finger toward the object), as in
[`mjtvm.grasp.resolve.state`][mjtvm.grasp.resolve.state].
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError
from mjtvm.grasp.contacts.touch import CCD_TOLERANCE
from mjtvm.grasp.resolve.state import geom_label

__all__ = ["BACKOFF", "OBJECT_TYPES", "WitnessPoints", "distance_model", "is_sphere", "witness"]

#: m: how far the finger geom is backed off along the normal guess when the surfaces touch.
BACKOFF = 1e-3
_FAR = 10.0  # m: distmax of the queries; anything farther is not a contact of a lift
_GEOM = mujoco.mjtGeom
#: Object geom types the lift moves fingers on: every type ``mj_geomDistance`` measures as a
#: convex solid, meshes included (MuJoCo collides a mesh as its convex hull, so an object made
#: of convex pieces is one mesh geom per piece). Planes and height fields bound no solid.
OBJECT_TYPES = (
    int(_GEOM.mjGEOM_SPHERE),
    int(_GEOM.mjGEOM_CAPSULE),
    int(_GEOM.mjGEOM_ELLIPSOID),
    int(_GEOM.mjGEOM_CYLINDER),
    int(_GEOM.mjGEOM_BOX),
    int(_GEOM.mjGEOM_MESH),
)


@dataclass(frozen=True, eq=False)
class WitnessPoints:
    r"""The nearest (or deepest) points of an object geom and a finger geom.

    Attributes
    ----------
    distance
        Signed surface distance (m), negative when the geoms penetrate.
    object_point, finger_point
        ``(3,)`` the witness points on the object's and on the finger's surface (m).
    normal
        ``(3,)`` unit contact normal into the object: ``object_point - finger_point =
        distance * (-normal)``.
    """

    distance: float
    object_point: NDArray[np.float64]
    finger_point: NDArray[np.float64]
    normal: NDArray[np.float64]


def is_sphere(model: mujoco.MjModel, geom: int) -> bool:
    """Whether ``geom`` is a sphere."""
    return int(model.geom_type[geom]) == int(_GEOM.mjGEOM_SPHERE)


def distance_model(model: mujoco.MjModel) -> mujoco.MjModel:
    """A copy of ``model`` for distance queries: the convex solver (GJK/EPA, used for cylinders
    and ellipsoids) run to [`CCD_TOLERANCE`][mjtvm.grasp.contacts.touch.CCD_TOLERANCE] (1e-12 m, as the grasp is read)
    instead of the model's tolerance (MuJoCo's default 1e-6 is coarser
    than the lift's 1e-10 m); the model itself is left as its author set it."""
    out = copy.deepcopy(model)
    out.opt.ccd_tolerance = min(float(out.opt.ccd_tolerance), CCD_TOLERANCE)
    out.opt.ccd_iterations = max(int(out.opt.ccd_iterations), 200)
    return out


def _query(model: mujoco.MjModel, data: mujoco.MjData, og: int, fg: int) -> tuple[float, NDArray[np.float64]]:
    fromto = np.zeros(6)
    dist = float(mujoco.mj_geomDistance(model, data, og, fg, _FAR, fromto))
    if dist >= _FAR:
        raise ModelError(f"geom {geom_label(model, fg)!r}", f"farther than {_FAR} m from the object")
    return dist, fromto


def witness(model: mujoco.MjModel, data: mujoco.MjData, object_geom: int, finger_geom: int) -> WitnessPoints:
    r"""The witness points and normal of ``object_geom`` and ``finger_geom`` at ``data``'s geom poses.

    Parameters
    ----------
    model
        The model, or its [`distance_model()`][mjtvm.lift.surface.distance_model].
    data
        Geom poses (``mj_kinematics`` done); ``data`` is left as it was.

    Raises
    ------
    ModelError
        Geoms farther apart than 10 m, or no normal (coincident witness points after backing off).
    """
    if is_sphere(model, object_geom) and is_sphere(model, finger_geom):
        c, tip = np.array(data.geom_xpos[object_geom]), np.array(data.geom_xpos[finger_geom])
        u = (tip - c) / np.linalg.norm(tip - c)  # radial projection (Case 2)
        big, small = float(model.geom_size[object_geom, 0]), float(model.geom_size[finger_geom, 0])
        return WitnessPoints(float(np.linalg.norm(tip - c)) - big - small, c + big * u, tip - small * u, -u)
    dist, ft = _query(model, data, object_geom, finger_geom)
    if abs(dist) > 0.1 * BACKOFF:  # far enough apart: the witnesses' direction is the normal
        return WitnessPoints(dist, ft[:3].copy(), ft[3:].copy(), (ft[:3] - ft[3:]) / dist)
    # touching: back the finger off along a guess of the normal (module docstring)
    guess = ft[:3] - np.array(data.geom_xpos[finger_geom])
    if float(np.linalg.norm(guess)) < 1e-12:
        guess = np.array(data.geom_xpos[object_geom]) - np.array(data.geom_xpos[finger_geom])
    n = guess / np.linalg.norm(guess)
    saved = np.array(data.geom_xpos[finger_geom])
    shift, used = BACKOFF - min(dist, 0.0), n
    try:
        for _ in range(8):
            used = n
            data.geom_xpos[finger_geom] = saved - shift * used
            d_b, ft = _query(model, data, object_geom, finger_geom)
            if d_b <= 0.0:
                raise ModelError(f"geom {geom_label(model, finger_geom)!r}", "no contact normal")
            new = (ft[:3] - ft[3:]) / d_b
            done = float(np.linalg.norm(new - n)) < 1e-13
            n = new
            if done:
                break
    finally:
        data.geom_xpos[finger_geom] = saved
    finger = ft[3:] + shift * used  # the backed-off witness, shifted back
    return WitnessPoints(float(d_b - shift), ft[:3].copy(), finger, n)
