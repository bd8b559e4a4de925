r"""Rerun recording of one grasp as loaded, before any solve (``mjtvm show GRASP --rrd FILE``).

Entities (world frame, m; static, no timeline):

* ``/grasp/hand/<kind>`` and ``/grasp/object/<kind>``: the colliding geoms
  ([`geom_shapes()`][mjtvm.grasp.contacts.shapes.geom_shapes]), boxes, spheres and ellipsoids, capsules,
  cylinders, planes (a thin box) and meshes, labelled with their geom labels; the object as
  a wireframe;
* ``/grasp/contacts``: the report's pairs ([`contact_rows()`][mjtvm.grasp.contacts.report.contact_rows]) at
  their contact points, coloured by type ([`TYPE_COLORS`][mjtvm.viewer.drawing.TYPE_COLORS]; grey
  when not selected), labelled ``geom type distance``;
* ``/grasp/normals``: unit normals into the object, [`NORMAL_LENGTH`][mjtvm.viewer.grasp_view.NORMAL_LENGTH] m long;
* ``/grasp/cones``: the friction cone (half-angle ``atan(mu)``, [`CONE_HEIGHT`][mjtvm.viewer.grasp_view.CONE_HEIGHT] m high,
  apex at the contact point, opening into the object along the normal) of every selected F
  and S contact.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
from numpy.typing import NDArray

from mjtvm.grasp.contacts.report import ContactRow
from mjtvm.grasp.contacts.shapes import GeomShape
from mjtvm.viewer.drawing import TYPE_COLORS

__all__ = ["APPLICATION_ID", "CONE_HEIGHT", "CONE_SIDES", "NORMAL_LENGTH", "cone_mesh", "record_grasp"]

APPLICATION_ID = "mjtvm_show"
NORMAL_LENGTH = 0.02  #: m: drawn length of a contact normal
CONE_HEIGHT = 0.015  #: m: drawn height of a friction cone along its normal
CONE_SIDES = 24  #: facets of a drawn cone
_UNSELECTED = (170, 170, 170)


def _xyzw(q: NDArray[np.float64]) -> list[float]:
    return [float(q[1]), float(q[2]), float(q[3]), float(q[0])]


def _rgb(rgba: NDArray[np.float64]) -> tuple[int, int, int]:
    r, g, b = (round(255 * float(c)) for c in rgba[:3])
    return r, g, b


def _basis(n: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Two unit vectors completing ``n`` to an orthonormal frame."""
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = np.cross(n, a)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n, t1)


def cone_mesh(
    apex: NDArray[np.float64], normal: NDArray[np.float64], mu: float, *, height: float = CONE_HEIGHT
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    r"""The side of the friction cone ``{f : |f_t| <= mu f_n}``: ``(vertices (CONE_SIDES + 1, 3),
    triangles (CONE_SIDES, 3))``, apex first, the rim a circle of radius ``mu * height`` at
    ``height`` (m) along the unit ``normal``."""
    n = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    t1, t2 = _basis(n)
    phi = 2 * np.pi * np.arange(CONE_SIDES) / CONE_SIDES
    rim = apex + height * n + mu * height * (np.outer(np.cos(phi), t1) + np.outer(np.sin(phi), t2))
    vertices = np.vstack([apex, rim])
    triangles = np.array([[0, 1 + k, 1 + (k + 1) % CONE_SIDES] for k in range(CONE_SIDES)], dtype=np.int64)
    return vertices, triangles


def _log_shapes(rec: rr.RecordingStream, root: str, shapes: Sequence[GeomShape], wire: bool) -> None:
    fill = rr.components.FillMode.MajorWireframe if wire else rr.components.FillMode.Solid
    by_kind: dict[str, list[GeomShape]] = {}
    for s in shapes:
        by_kind.setdefault(s.kind, []).append(s)
    for kind, group in by_kind.items():
        path = f"{root}/{kind}"
        colors, labels = [_rgb(s.rgba) for s in group], [s.label for s in group]
        if kind in ("box", "plane", "sphere", "ellipsoid"):  # a half-size box or ellipsoid
            half: list[Any]
            if kind == "box" or kind == "ellipsoid":
                half = [s.size for s in group]
            elif kind == "plane":
                half = [[s.size[0] or 1.0, s.size[1] or 1.0, 5e-4] for s in group]
            else:
                half = [np.repeat(s.size[:1], 3) for s in group]
            archetype = rr.Boxes3D if kind in ("box", "plane") else rr.Ellipsoids3D
            rec.log(
                path,
                archetype(
                    half_sizes=half,
                    centers=[s.position for s in group],
                    quaternions=[_xyzw(s.quaternion) for s in group],
                    fill_mode=fill,
                    colors=colors,
                    labels=labels,
                ),
                static=True,
            )
        elif kind == "capsule":  # MuJoCo: centre and half-length along z; rerun: from one end along z
            rec.log(
                path,
                rr.Capsules3D(
                    lengths=[2 * s.size[1] for s in group],
                    radii=[s.size[0] for s in group],
                    translations=[s.position - _z(s) * s.size[1] for s in group],
                    quaternions=[_xyzw(s.quaternion) for s in group],
                    colors=colors,
                    labels=labels,
                ),
                static=True,
            )
        elif kind == "cylinder":  # both: centred, along z
            rec.log(
                path,
                rr.Cylinders3D(
                    lengths=[2 * s.size[1] for s in group],
                    radii=[s.size[0] for s in group],
                    centers=[s.position for s in group],
                    quaternions=[_xyzw(s.quaternion) for s in group],
                    fill_mode=fill,
                    colors=colors,
                    labels=labels,
                ),
                static=True,
            )
        else:
            for i, s in enumerate(group):
                assert s.vertices is not None and s.faces is not None
                world = s.position + s.vertices @ _rot(s.quaternion).T
                rec.log(
                    f"{path}/{i}",
                    rr.Mesh3D(vertex_positions=world, triangle_indices=s.faces, albedo_factor=_rgb(s.rgba)),
                    static=True,
                )


def _rot(q: NDArray[np.float64]) -> NDArray[np.float64]:
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _z(s: GeomShape) -> NDArray[np.float64]:
    return _rot(s.quaternion)[:, 2]


def record_grasp(
    path: str | Path,
    shapes: Sequence[GeomShape],
    rows: Sequence[ContactRow],
    mu: Mapping[str, float],
    *,
    name: str = "grasp",
) -> None:
    """Write the grasp's recording (module docstring) to the file ``path`` (``.rrd``).

    ``mu``: geom label -> friction coefficient of its contact (the cones of selected F and S
    contacts; a contact without one gets none).
    """
    rec = rr.RecordingStream(APPLICATION_ID, recording_id=name)
    rec.set_sinks(rr.FileSink(str(path)))
    rec.log("grasp", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    _log_shapes(rec, "grasp/hand", [s for s in shapes if not s.on_object], wire=False)
    _log_shapes(rec, "grasp/object", [s for s in shapes if s.on_object], wire=True)
    drawn = [r for r in rows if r.normal is not None]
    colors = [TYPE_COLORS.get(r.type or "", _UNSELECTED) if r.selected else _UNSELECTED for r in rows]
    rec.log(
        "grasp/contacts",
        rr.Points3D(
            [r.position for r in rows],
            colors=colors,
            radii=-4.0,
            labels=[f"{r.geom} {r.type or '-'} {round(1e3 * r.distance, 6) + 0.0:.3g} mm" for r in rows],
        ),
        static=True,
    )
    rec.log(
        "grasp/normals",
        rr.Arrows3D(
            origins=[r.position for r in drawn],
            vectors=[NORMAL_LENGTH * np.asarray(r.normal) for r in drawn],
            colors=[c for r, c in zip(rows, colors, strict=True) if r.normal is not None],
        ),
        static=True,
    )
    for i, r in enumerate(rows):
        coefficient = mu.get(r.geom)
        if r.selected and r.type in ("F", "S") and r.normal is not None and coefficient is not None:
            vertices, triangles = cone_mesh(r.position, r.normal, coefficient)
            rec.log(
                f"grasp/cones/{i}",
                rr.Mesh3D(
                    vertex_positions=vertices,
                    triangle_indices=triangles,
                    albedo_factor=(*TYPE_COLORS[r.type], 110),
                ),
                static=True,
            )
    rec.flush()
    rec.disconnect()
