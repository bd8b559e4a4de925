r"""A picture of a loaded grasp by MuJoCo's renderer (``mjtvm show --png``): the model at the
grasp's configuration seen from [`VIEWS`][mjtvm.grasp.contacts.picture.VIEWS] around the object, with its contacts drawn.

Every geom is drawn whatever its visibility group (a hand whose collision geoms sit in group 3,
the menagerie's convention once the visual meshes are removed, is drawn too), on a light
background (the pixels MuJoCo's segmentation leaves empty). Object contacts within the
grasp's tolerance are red points with their normal (an arrow out of the object) and the
friction cone of coefficient ``mu`` (green lines, opening out of the object: the forces the
object can exert on the finger); contacts of the hand with itself are blue points, no cone.
[`Picture`][mjtvm.grasp.contacts.picture.Picture] carries the panels and each panel's scale (m per pixel at the object's centre), so that
[`grasp_png()`][mjtvm.jobs.figures.grasp_png] can label the views and draw a scale bar.

Rendering needs an OpenGL context: headless, MuJoCo's EGL (or OSMesa) back end, chosen by the
environment variable ``MUJOCO_GL`` before MuJoCo is imported (``mjtvm show --png`` sets
``egl`` when it is unset). A context that cannot be made is a [`RenderError`][mjtvm.grasp.contacts.picture.RenderError].
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import MjtvmError
from mjtvm.grasp.contacts.touch import forward_touching, geom_label, subtree

__all__ = ["BACKGROUND", "VIEWS", "Marks", "Picture", "RenderError", "render_grasp"]

#: (label, azimuth, elevation) in degrees of the free camera for each panel, side by side.
VIEWS = (("side, azimuth 135 deg", 135.0, -25.0), ("side, azimuth 45 deg", 45.0, -25.0), ("top", 90.0, -89.0))
#: The camera's distance from the object's centre, in the object's bounding radii.
DISTANCE_RADII = 4.0
#: RGB of the background (uint8).
BACKGROUND = (242, 242, 238)
_CONE_EDGES = 12


_Contact = tuple[NDArray[np.float64], NDArray[np.float64] | None, float | None]
"""(point (3,) m, outward normal (3,) or None for a self-contact, mu or None)."""


class RenderError(MjtvmError, RuntimeError):
    """MuJoCo could not render (no OpenGL context: set ``MUJOCO_GL=egl`` or ``osmesa``)."""

    def __init__(self, problem: str) -> None:
        super().__init__(f"--png: cannot render: {problem}")


@dataclass(frozen=True)
class Picture:
    """The rendered views of a grasp.

    Attributes
    ----------
    panels
        One ``(height, width, 3)`` uint8 RGB image per view of [`VIEWS`][mjtvm.grasp.contacts.picture.VIEWS].
    labels
        The views' names, as ``VIEWS``.
    metres_per_pixel
        Per panel, the length (m) one pixel spans at the object's centre (perspective camera).
    marks
        Per panel, the contacts to draw over it ([`Marks`][mjtvm.grasp.contacts.picture.Marks]).
    object_contacts, self_contacts
        How many object contacts (within the tolerance) and hand self-contacts are drawn.
    """

    panels: tuple[NDArray[np.uint8], ...]
    labels: tuple[str, ...]
    metres_per_pixel: tuple[float, ...]
    marks: tuple[Marks, ...]
    object_contacts: int
    self_contacts: int


@dataclass(frozen=True)
class Marks:
    """The contacts of one panel in pixel coordinates ``(u, v)`` (u right, v down), drawn over it.

    Attributes
    ----------
    points, normal_ends
        ``(k, 2)`` each object contact and the tip of its outward normal (0.8 object radii).
    cone_segments
        ``(m, 2, 2)`` the friction cones' edges (0.5 object radii), start and end.
    self_points
        ``(j, 2)`` the hand's contacts with itself.
    hidden
        ``(k,)`` whether each object contact lies behind a surface in this view (drawn faint).
    """

    points: NDArray[np.float64]
    normal_ends: NDArray[np.float64]
    cone_segments: NDArray[np.float64]
    self_points: NDArray[np.float64]
    hidden: NDArray[np.bool_]


def _projector(cam: mujoco.MjvGLCamera, width: int, height: int) -> Any:
    """World points ``(n, 3)`` -> pixel coordinates ``(n, 2)`` of MuJoCo's perspective camera."""
    pos, fwd, up = np.array(cam.pos), np.array(cam.forward), np.array(cam.up)
    right = np.cross(fwd, up)
    near, half_h = cam.frustum_near, 0.5 * (cam.frustum_top - cam.frustum_bottom)
    mid_h, half_w = 0.5 * (cam.frustum_top + cam.frustum_bottom), half_h * width / height

    def project(points: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(n, 3)`` -> ``(n, 3)``: u, v (pixels) and the depth along the view (m)."""
        d = np.atleast_2d(points) - pos
        z = np.maximum(d @ fwd, 1e-12)
        x = (near * (d @ right) / z - cam.frustum_center) / half_w
        y = (near * (d @ up) / z - mid_h) / half_h
        return np.c_[(x + 1.0) * 0.5 * width, (1.0 - y) * 0.5 * height, z]

    return project


def _marks(project: Any, contacts: list[_Contact], radius: float, depth: NDArray[np.float32]) -> Marks:
    """The contacts' points, normals and cones (`_contacts()`), projected; an object contact
    is hidden (behind the object, say) when the depth image has a surface more than half an
    object radius in front of it: a fingertip around its own contact does not hide it."""
    pts, ends, cones, selfs = [], [], [], []
    for pos, normal, mu in contacts:
        if normal is None:
            selfs.append(pos)
            continue
        pts.append(pos)
        ends.append(pos + 0.8 * radius * normal)
        if mu is None:
            continue
        t1 = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(normal, t1)
        length = 0.5 * radius / math.sqrt(1.0 + mu * mu)
        for k in range(_CONE_EDGES):
            phi = 2.0 * math.pi * k / _CONE_EDGES
            edge = normal + mu * (math.cos(phi) * t1 + math.sin(phi) * t2)  # eq. (3): |f_t| <= mu f_n
            cones.append((pos, pos + length * edge))
    empty = np.zeros((0, 3))
    cone_px = (
        project(np.array(cones).reshape(-1, 3))[:, :2].reshape(-1, 2, 2) if cones else np.zeros((0, 2, 2))
    )
    at = project(np.array(pts)) if pts else empty
    h, w = depth.shape
    u = np.clip(at[:, 0].astype(int), 0, w - 1)
    v = np.clip(at[:, 1].astype(int), 0, h - 1)
    return Marks(
        points=at[:, :2],
        normal_ends=(project(np.array(ends)) if ends else empty)[:, :2],
        cone_segments=cone_px,
        self_points=(project(np.array(selfs)) if selfs else empty)[:, :2],
        hidden=depth[v, u] < at[:, 2] - 0.5 * radius,
    )


def _contacts(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    inside: set[int],
    tolerance: float,
    mu: Mapping[str, float],
) -> list[_Contact]:
    """Each contact of ``data`` as (point, outward normal, mu of the finger geom or None when
    it has none) for the object's, (point, None, None) for the hand's with itself (a pair that
    touches: distance <= 0)."""
    out: list[_Contact] = []
    for c in data.contact[: data.ncon]:
        in1, in2 = int(model.geom_bodyid[c.geom1]) in inside, int(model.geom_bodyid[c.geom2]) in inside
        n = np.array(c.frame[:3], dtype=float)  # from geom1 to geom2
        if in1 != in2 and c.dist <= tolerance:
            finger = geom_label(model, int(c.geom2 if in1 else c.geom1))
            out.append((np.array(c.pos, dtype=float), n if in1 else -n, mu.get(finger)))
        elif not in1 and not in2 and c.dist <= 0.0:
            out.append((np.array(c.pos, dtype=float), None, None))
    return out


def render_grasp(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    object_body: str,
    tolerance: float,
    *,
    mu: Mapping[str, float],
    width: int = 480,
    height: int = 480,
) -> Picture:
    """The grasp from each of [`VIEWS`][mjtvm.grasp.contacts.picture.VIEWS] (module docstring): contacts within ``tolerance`` (m),
    each with the friction cone of its finger geom's coefficient in ``mu`` (geom label -> mu).

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
    contacts = _contacts(model, work, inside, tolerance, mu)
    option = mujoco.MjvOption()
    option.geomgroup[:] = 1  # every group: collision geoms in group 3 too
    try:
        renderer = mujoco.Renderer(model, height=height, width=width)
    except Exception as e:  # MuJoCo raises several kinds when no GL back end loads
        raise RenderError(f"{type(e).__name__}: {e}") from e
    panels, scales, marks = [], [], []
    fovy = math.radians(float(model.vis.global_.fovy))
    try:
        for _, azimuth, elevation in VIEWS:
            camera = mujoco.MjvCamera()
            camera.lookat[:] = work.xpos[ob]
            camera.distance = DISTANCE_RADII * radius
            camera.azimuth, camera.elevation = azimuth, elevation
            renderer.update_scene(work, camera=camera, scene_option=option)
            eye = mujoco.mjv_averageCamera(renderer.scene.camera[0], renderer.scene.camera[1])  # mono
            rgb = renderer.render().copy()
            renderer.enable_segmentation_rendering()
            try:
                empty = renderer.render()[..., 0] < 0  # no geom: the background
            finally:
                renderer.disable_segmentation_rendering()
            renderer.enable_depth_rendering()
            try:
                depth = renderer.render()  # m along the view
            finally:
                renderer.disable_depth_rendering()
            marks.append(_marks(_projector(eye, width, height), contacts, radius, depth))
            rgb[empty] = BACKGROUND
            panels.append(rgb)
            scales.append(2.0 * camera.distance * math.tan(fovy / 2.0) / height)
    finally:
        renderer.close()
    return Picture(
        panels=tuple(panels),
        labels=tuple(v[0] for v in VIEWS),
        metres_per_pixel=tuple(scales),
        marks=tuple(marks),
        object_contacts=sum(1 for _, n, _ in contacts if n is not None),
        self_contacts=sum(1 for _, n, _ in contacts if n is None),
    )
