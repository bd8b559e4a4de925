r"""A picture of a loaded grasp by MuJoCo's renderer (``mjtvm show --png``): the model at the
grasp's configuration with its contact points, seen from [`VIEWS`][mjtvm.grasp.contacts.picture.VIEWS] around the object.

Rendering needs an OpenGL context: headless, MuJoCo's EGL (or OSMesa) back end, chosen by the
environment variable ``MUJOCO_GL`` before MuJoCo is imported (``mjtvm show --png`` sets
``egl`` when it is unset). A context that cannot be made is a [`RenderError`][mjtvm.grasp.contacts.picture.RenderError].
"""

from __future__ import annotations

import copy

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import MjtvmError
from mjtvm.grasp.contacts.touch import forward_touching, subtree

__all__ = ["VIEWS", "RenderError", "render_grasp"]

#: (azimuth, elevation) in degrees of the free camera for each panel, side by side.
VIEWS = ((135.0, -25.0), (45.0, -25.0), (90.0, -89.0))
#: The camera's distance from the object's centre, in the object's bounding radii.
DISTANCE_RADII = 4.0


class RenderError(MjtvmError, RuntimeError):
    """MuJoCo could not render (no OpenGL context: set ``MUJOCO_GL=egl`` or ``osmesa``)."""

    def __init__(self, problem: str) -> None:
        super().__init__(f"--png: cannot render: {problem}")


def render_grasp(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    object_body: str,
    tolerance: float,
    *,
    width: int = 480,
    height: int = 480,
) -> NDArray[np.uint8]:
    """``(height, len(VIEWS) * width, 3)`` RGB: the grasp from each of [`VIEWS`][mjtvm.grasp.contacts.picture.VIEWS], with the
    contacts within ``tolerance`` (m) drawn as MuJoCo's contact points.

    Raises
    ------
    RenderError
        No OpenGL context.
    """
    work = copy.copy(data)
    ob = model.body(object_body).id
    forward_touching(model, work, ob, tolerance)  # data.contact: the pairs within the tolerance
    inside = subtree(model, ob)
    geoms = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) in inside]
    radius = max(float(model.geom_rbound[g]) for g in geoms) if geoms else 0.05
    option = mujoco.MjvOption()
    option.flags[mujoco.mjtVisFlag.mjVIS_CONTACTPOINT] = True
    try:
        renderer = mujoco.Renderer(model, height=height, width=width)
    except Exception as e:  # MuJoCo raises several kinds when no GL back end loads
        raise RenderError(f"{type(e).__name__}: {e}") from e
    panels = []
    try:
        for azimuth, elevation in VIEWS:
            camera = mujoco.MjvCamera()
            camera.lookat[:] = work.xpos[ob]
            camera.distance = DISTANCE_RADII * radius
            camera.azimuth, camera.elevation = azimuth, elevation
            renderer.update_scene(work, camera=camera, scene_option=option)
            panels.append(renderer.render().copy())
    finally:
        renderer.close()
    return np.concatenate(panels, axis=1)
