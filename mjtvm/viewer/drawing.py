r"""What the replay's rerun recording draws at each state ([`viz`][mjtvm.viewer.viz], whose
docstring lists the entities): the hand's and the object's geoms, the contacts, forces and
slide directions of a run, its velocity polytopes as convex-hull meshes, its scalars and the
joint panels.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import rerun as rr
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError

from mjtvm.grasp.scene import scene_geometry, scene_poses
from mjtvm.jobs.replay_records import Record
from mjtvm.lift.trajectory import Lift
from mjtvm.model.contacts import slide_unit
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.polytopes.lifted import lifted_polytope
from mjtvm.polytopes.projection import project_lp
from mjtvm.polytopes.tvms import default_scale

__all__ = [
    "FORCE_SCALE",
    "SLIDE_LENGTH",
    "TYPE_COLORS",
    "VELOCITY_SCALE",
    "Columns",
    "Scene",
    "hull_mesh",
    "log_run",
    "mirrored",
    "panel",
    "translational_tvms",
]

VELOCITY_SCALE = 0.06  #: m drawn per m/s of object velocity
FORCE_SCALE = 0.05  #: m drawn per N of contact force
SLIDE_LENGTH = 0.03  #: m: length of a slide-direction arrow
TYPE_COLORS = {"F": (40, 170, 70), "L": (60, 120, 235), "S": (240, 150, 20), "D": (150, 150, 150)}
_SATURATED = (230, 30, 30)


def hull_mesh(points: NDArray[np.float64], *, tol: float = 1e-9) -> tuple[NDArray, NDArray] | None:
    r"""Convex hull of 3-D ``points``: ``(vertices (V, 3), triangles (T, 3))``, faces outward.

    Only the hull's vertices are kept (re-indexed). A flat point set gives a polygon fan, a
    point set of lower dimension ``None``.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(pts) < 3:
        return None
    centre = pts.mean(axis=0)
    _, s, vt = np.linalg.svd(pts - centre)
    rank = int(np.sum(s > tol * max(1.0, float(s[0]))))
    try:
        if rank == 3:
            hull = ConvexHull(pts)
            keep, tris = hull.vertices, hull.simplices.copy()
            a, b, c = pts[tris[:, 0]], pts[tris[:, 1]], pts[tris[:, 2]]
            inward = np.einsum("ij,ij->i", np.cross(b - a, c - a), hull.equations[:, :3]) < 0
            tris[inward] = tris[inward][:, [0, 2, 1]]
        elif rank == 2:
            keep = ConvexHull((pts - centre) @ vt[:2].T).vertices  # counter-clockwise in the plane
            tris = np.array([[keep[0], keep[i], keep[i + 1]] for i in range(1, len(keep) - 1)])
        else:
            return None
    except QhullError:
        return None
    index = np.zeros(len(pts), dtype=np.uint32)
    index[keep] = np.arange(len(keep), dtype=np.uint32)
    return pts[keep], index[np.asarray(tris, dtype=np.int64)].reshape(-1, 3)


def translational_tvms(state: GraspState) -> NDArray[np.float64] | None:
    r"""The TVMS of Problem 1 projected onto the translational velocity.

    The projection of [`tvms()`][mjtvm.polytopes.tvms.tvms] (the same call, without the volume, which
    the recording does not show). Returns its vertices' ``(V, 3)`` linear parts (m/s), or
    ``None`` unless it is bounded.
    """
    proj = project_lp(lifted_polytope(state), metric=default_scale(state))
    if proj.status != "bounded" or len(proj.vertices) == 0:
        return None
    return np.asarray(proj.vertices, dtype=float)[:, : state.dim]


def _rgb(rgba: NDArray[np.float32]) -> tuple[int, ...]:
    return tuple(round(255 * float(c)) for c in rgba)


def panel(rng: OperationRange, points: Any) -> NDArray[np.float64]:
    """Joint-panel coordinates of (tau, qdot) points (the panels: [`viz`][mjtvm.viewer.viz]).

    Parameters
    ----------
    rng
        The joint's operation range.
    points
        ``(..., 2)`` (tau, qdot) pairs.

    Returns
    -------
    numpy.ndarray
        The points with tau over the range's maximum torque and -qdot over its maximum speed.
    """
    return np.asarray(points, dtype=float) * [1 / rng.max_torque, -1 / rng.max_speed]


def mirrored(rng: OperationRange) -> NDArray[np.float64]:
    """The closed outline of an operation range mirrored into the four quadrants.

    Parameters
    ----------
    rng
        The joint's operation range.

    Returns
    -------
    numpy.ndarray
        ``(m, 2)`` (tau, qdot) points, the first repeated at the end.
    """
    v = rng.vertices[np.any(rng.vertices > 0, axis=1)]
    v = v[np.argsort(np.arctan2(v[:, 1], v[:, 0]))]  # from the torque axis to the speed axis
    out = np.vstack([v, v[::-1] * [-1, 1], v * [-1, -1], v[::-1] * [1, -1]])
    return np.vstack([out, out[:1]])


class Scene:
    """The hand's and the object's geoms ([`scene`][mjtvm.grasp.scene]) and their poses along the lift.

    Parameters
    ----------
    lift
        The lift whose scenario's geoms are drawn at each of its states.
    """

    def __init__(self, lift: Lift) -> None:
        sc = lift.scenario
        self.geometry = scene_geometry(sc.model, sc.object_body)
        self.poses = scene_poses(sc.model, self.geometry, lift.qpos)

    def static(self, rec: rr.RecordingStream) -> None:
        """Log the geoms' shapes, sizes and colours once (static entities)."""
        geo = self.geometry
        links, planes = geo.links, geo.planes
        rec.log("scene", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        if len(links):
            rec.log(
                "scene/links",
                rr.Capsules3D.from_fields(
                    lengths=2 * links.size[:, 1],
                    radii=links.size[:, 0],
                    colors=[_rgb(c) for c in links.rgba],
                    fill_mode="solid",
                ),
                static=True,
            )
        wire = rr.components.FillMode.MajorWireframe  # the object: see the velocity polytopes inside
        for path, geoms, fill in (
            ("scene/tips", geo.tips, rr.components.FillMode.Solid),
            ("scene/object", geo.object, wire),
        ):
            if len(geoms):
                rec.log(
                    path,
                    rr.Ellipsoids3D.from_fields(
                        half_sizes=np.repeat(geoms.size[:, :1], 3, axis=1),
                        colors=[_rgb(c) for c in geoms.rgba],
                        fill_mode=fill,
                    ),
                    static=True,
                )
        for k in range(len(geo.meshes)):  # each mesh piece in its geom's frame
            rec.log(
                f"scene/meshes/{k}",
                rr.Mesh3D(
                    vertex_positions=geo.meshes.vertices[k],
                    triangle_indices=geo.meshes.triangles[k],
                    albedo_factor=_rgb(geo.meshes.rgba[k]),
                ),
                static=True,
            )
        if len(planes):
            rec.log(
                "scene/palm",
                rr.Boxes3D(
                    half_sizes=[[s[0], s[1], 5e-4] for s in planes.size],
                    centers=[p - [0.0, 0.0, 5e-4] for p in planes.pos],
                    fill_mode="solid",
                    colors=[_rgb(c) for c in planes.rgba],
                    labels=[name or "palm" for name in planes.names],
                ),
                static=True,
            )

    def log(self, cols: Columns, i: int) -> NDArray[np.float64]:
        """Add the geoms' poses at state ``i`` (their sizes and colours are static); returns the
        object body's origin."""
        poses, links = self.poses, self.geometry.links
        if len(links):
            # MuJoCo: a capsule's centre and axis z; rerun: from one end along z
            ends = poses.link_pos[i] - poses.link_axis[i] * links.size[:, 1:2]
            cols.add(
                "scene/links",
                rr.Capsules3D,
                len(links),
                translations=list(ends),
                quaternions=list(poses.link_quat[i][:, [1, 2, 3, 0]]),
            )
        for path, centres in (("scene/tips", poses.tip_pos[i]), ("scene/object", poses.object_pos[i])):
            if len(centres):
                cols.add(path, rr.Ellipsoids3D, len(centres), centers=list(centres))
        for k in range(len(self.geometry.meshes)):
            cols.add(
                f"scene/meshes/{k}",
                rr.Transform3D,
                1,
                translation=[poses.mesh_pos[i, k]],
                quaternion=[poses.mesh_quat[i, k][[1, 2, 3, 0]]],
            )
        return np.array(poses.object_origin[i])


class Columns:
    """Rows of the temporal entities per state, sent with ``send_columns`` at the end (fast).

    One rerun call per entity for the whole replay, instead of one per state.
    """

    def __init__(self) -> None:
        self.rows: dict[str, tuple[Any, dict[str, list[Any]], list[int]]] = {}

    def add(self, path: str, archetype: Any, n: int, **fields: list[Any]) -> None:
        """``n`` rows of ``fields`` (lists of length ``n``) at the current state."""
        _, store, lengths = self.rows.setdefault(path, (archetype, {}, []))
        for key, values in fields.items():
            store.setdefault(key, []).extend(values)
        lengths.append(n)

    def send(self, rec: rr.RecordingStream, times: list[rr.TimeColumn]) -> None:
        """Send every entity's rows, one partition per state of ``times``."""
        for path, (archetype, store, lengths) in self.rows.items():
            rec.send_columns(path, indexes=times, columns=archetype.columns(**store).partition(lengths))


def _log_mesh(
    rec: rr.RecordingStream, path: str, points: NDArray | None, centre: NDArray, rgba: tuple
) -> None:
    mesh = None if points is None else hull_mesh(points)
    if mesh is None:
        rec.log(path, rr.Clear(recursive=False))
    else:
        verts, tris = mesh
        normals = verts - verts.mean(axis=0)  # smooth shading, from the hull's centroid
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
        rec.log(
            path,
            rr.Transform3D(translation=centre, scale=VELOCITY_SCALE),
            rr.Mesh3D(
                vertex_positions=verts,
                triangle_indices=tris,
                vertex_normals=normals,
                albedo_factor=rgba,
            ),
        )


def log_run(
    rec: rr.RecordingStream,
    cols: Columns,
    name: str,
    r: Record,
    state: GraspState,
    centre: NDArray,
    tvms_points: NDArray | None,
    color: tuple[int, ...],
) -> None:
    """Log one run (variant, reading) at one state: contacts, forces, polytopes, scalars, joints.

    Parameters
    ----------
    rec
        The recording.
    cols
        Where the temporal scalars and joint panels are collected.
    name
        The run's entity name.
    r
        The run's replay record at this state.
    state
        The grasp state of the record.
    centre
        Where the velocity polytopes are drawn (the object body's origin).
    tvms_points
        ``(n, 3)`` the translational TVMS's points, or ``None`` (nothing drawn).
    color
        The run's RGB colour.
    """
    res, contacts = r.result, state.contacts
    rec.log(
        f"scene/{name}/contacts",
        rr.Points3D(
            [c.position for c in contacts],
            radii=0.004,
            colors=[TYPE_COLORS[c.type] for c in contacts],
            labels=[f"{c.name.split('#')[0]} {c.type}" for c in contacts],
            show_labels=True,
        ),
    )
    slides = [c for c in contacts if c.type == "S" and c.slide_direction is not None]
    if slides:
        rec.log(
            f"scene/{name}/slides",
            rr.Arrows3D(
                # the tangential unit direction the LP uses
                vectors=[SLIDE_LENGTH * slide_unit(c) for c in slides],
                origins=[c.position for c in slides],
                colors=TYPE_COLORS["S"],
                radii=0.0015,
            ),
        )
    k, l = res.limiting if res.limiting is not None else (-1, -1)
    w = res.witnesses[k][l] if res.limiting is not None else None
    if w is not None and len(w.forces):
        rec.log(
            f"scene/{name}/forces",
            rr.Arrows3D(
                vectors=FORCE_SCALE * w.forces,
                origins=[c.position for c in contacts],
                colors=color,
                radii=0.002,
            ),
        )
    else:
        rec.log(f"scene/{name}/forces", rr.Clear(recursive=False))
    dist = [v[: state.dim] for v in res.distribution if v is not None]
    _log_mesh(
        rec,
        f"scene/{name}/distribution",
        np.vstack([np.zeros(3), *dist]) if dist else None,
        centre,
        (*color, 220),
    )
    _log_mesh(rec, f"scene/{name}/tvms", tvms_points, centre, (235, 235, 235, 90))
    value = [] if res.tvmmp is None else [float(res.tvmmp)]
    cols.add(f"tvmmp/{name}", rr.Scalars, len(value), scalars=value)
    for kk, ll in np.ndindex(*res.alpha.shape):
        value = [float(res.alpha[kk, ll])] if res.status[kk][ll] == "optimal" else []
        cols.add(f"alpha/{name}/k{kk}_l{ll}", rr.Scalars, len(value), scalars=value)
    value = [] if w is None else [float(k), float(l)]
    cols.add(f"limiting/{name}", rr.Scalars, len(value), scalars=value)
    for j, (joint, rng) in enumerate(zip(state.joint_names, state.operation_ranges, strict=True)):
        box, witness = f"joints/{joint}/{name}/box", f"joints/{joint}/{name}/witness"
        if w is None:
            cols.add(box, rr.Boxes2D, 0, half_sizes=[], centers=[])
            cols.add(witness, rr.Points2D, 0, positions=[], colors=[], labels=[], show_labels=[])
            continue
        tau, qd, sat = float(w.torques[j]), float(w.speeds[j]), joint in r.saturated
        lo, hi = panel(rng, w.box[j, [0, 2]]), panel(rng, w.box[j, [1, 3]])
        cols.add(box, rr.Boxes2D, 1, half_sizes=[np.abs(hi - lo) / 2], centers=[(hi + lo) / 2])
        label = f"{name}: {tau:.3g} N m, {qd:.3g} rad/s" + (" (saturated)" if sat else "")
        cols.add(
            witness,
            rr.Points2D,
            1,
            positions=[panel(rng, [tau, qd])],
            colors=[_SATURATED if sat else color],
            labels=[label],
            show_labels=[False],
        )
