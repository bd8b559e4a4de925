r"""Rerun recording of the lift replay (``mjtvm replay --rrd FILE``); the only module importing rerun.

:func:`record_replay` logs a :class:`~mjtvm.apps.replay.ReplayOutput` on two timelines, ``state``
(the state index) and ``lift_z`` (the object centre's height in micrometres: rerun timelines
are integer sequences, durations or timestamps). Entities (world frame, m; ``docs/rerun.md``):

* ``/scene/palm`` (static), ``/scene/links`` (capsules), ``/scene/tips``, ``/scene/object``
  (spheres): the MuJoCo geoms at each state's pose;
* ``/scene/<run>/contacts`` coloured by type (:data:`TYPE_COLORS`), labelled ``geom type``;
  ``/scene/<run>/forces``: the contact forces of the limiting pair's witness
  (:data:`FORCE_SCALE` m per N); ``/scene/<run>/slides``: S-point slide directions;
* ``/scene/<run>/distribution`` and ``/scene/<run>/tvms``: convex-hull meshes of object
  centre velocities (m/s) under a transform to the object centre scaled by
  :data:`VELOCITY_SCALE` m per m/s: the distribution polytope of Supplement 4 (the origin and
  :math:`\min_k \alpha_{kl} \hat r_l`, translational part) and the TVMS of Problem 1
  (:func:`~mjtvm.polytopes.tvms.tvms`, its vertices projected onto the translational coordinates), the
  latter at every :data:`TVMS_EVERY`-th state and the last by default;
* ``/tvmmp/<run>``, ``/alpha/<run>/k<k>_l<l>``, ``/limiting/<run>`` (``[k, l]``): scalars,
  an empty batch where there is no value;
* ``/joints/<joint>``: ``range`` (static: the operation range mirrored into four quadrants),
  ``<run>/box`` (the witness box of eq. 2) and ``<run>/witness`` (the limiting pair's
  (tau, qdot), red when on the range's edge), in panel coordinates ``x = tau / max_torque``,
  ``y = -qdot / max_speed`` (rerun's 2-D views point y down; the labels give N m and rad/s).

``<run>`` is the contact type of fingers 2 and 4: ``L``, ``S`` (``S_physical`` and
``S_literal`` when both readings ran). The blueprint shows a 3-D view per run, the time series
and a grid of joint panels.
"""

from __future__ import annotations

import os
import shutil
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError

from ..apps.replay import ReplayOutput
from ..apps.replay_records import Record
from ..core.contacts import slide_unit
from ..core.operation_range import OperationRange
from ..core.state import GraspState
from ..polytopes.lifted import lifted_polytope
from ..polytopes.projection import project_lp
from ..polytopes.tvms import default_scale
from ..sim.lift.trajectory import Lift
from ..sim.scene import scene_geometry, scene_poses

__all__ = [
    "APPLICATION_ID",
    "FORCE_SCALE",
    "TVMS_EVERY",
    "TYPE_COLORS",
    "VELOCITY_SCALE",
    "Z_UNIT",
    "blueprint",
    "hull_mesh",
    "record_replay",
    "record_verify",
    "translational_tvms",
]

APPLICATION_ID = "mjtvm_replay"
VELOCITY_SCALE = 0.06  #: m drawn per m/s of object velocity
FORCE_SCALE = 0.05  #: m drawn per N of contact force
SLIDE_LENGTH = 0.03  #: m: length of a slide-direction arrow
Z_UNIT = 1e-6  #: m per step of the ``lift_z`` timeline
TVMS_EVERY = 5  #: default TVMS subsampling (11-28 ms per bounded state; docs/rerun.md)
TYPE_COLORS = {"F": (40, 170, 70), "L": (60, 120, 235), "S": (240, 150, 20), "D": (150, 150, 150)}
_RUN_COLORS = ((60, 120, 235), (240, 150, 20), (190, 80, 200), (30, 190, 190))
_SATURATED = (230, 30, 30)
_Run = tuple[str, str | None]


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

    The projection of :func:`~mjtvm.polytopes.tvms.tvms` (the same call, without the volume, which
    the recording does not show). Returns its vertices' ``(V, 3)`` linear parts (m/s), or
    ``None`` unless it is bounded.
    """
    proj = project_lp(lifted_polytope(state), metric=default_scale(state))
    if proj.status != "bounded" or len(proj.vertices) == 0:
        return None
    return np.asarray(proj.vertices, dtype=float)[:, : state.dim]


def _rgb(rgba: NDArray[np.float32]) -> tuple[int, ...]:
    return tuple(round(255 * float(c)) for c in rgba)


def _panel(rng: OperationRange, points: Any) -> NDArray[np.float64]:
    """(tau, qdot) to joint-panel coordinates (module docstring)."""
    return np.asarray(points, dtype=float) * [1 / rng.max_torque, -1 / rng.max_speed]


def _mirrored(rng: OperationRange) -> NDArray[np.float64]:
    """Closed outline (tau, qdot) of the range mirrored into the four quadrants."""
    v = rng.vertices[np.any(rng.vertices > 0, axis=1)]
    v = v[np.argsort(np.arctan2(v[:, 1], v[:, 0]))]  # from the torque axis to the speed axis
    out = np.vstack([v, v[::-1] * [-1, 1], v * [-1, -1], v[::-1] * [1, -1]])
    return np.vstack([out, out[:1]])


class _Scene:
    """The hand's and the object's geoms (:mod:`~mjtvm.sim.scene`) and their poses along the lift."""

    def __init__(self, lift: Lift) -> None:
        sc = lift.scenario
        self.geometry = scene_geometry(sc.model, sc.object_body)
        self.poses = scene_poses(sc.model, self.geometry, lift.qpos)

    def static(self, rec: rr.RecordingStream) -> None:
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

    def log(self, cols: _Columns, i: int) -> NDArray[np.float64]:
        """Add the geoms' poses at state ``i`` (their sizes and colours are static); returns the
        object's centre."""
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
        return np.array(poses.object_pos[i][0] if len(self.geometry.object) else np.zeros(3))


class _Columns:
    """Rows of the temporal entities per state, sent with ``send_columns`` at the end (fast)."""

    def __init__(self) -> None:
        self.rows: dict[str, tuple[Any, dict[str, list[Any]], list[int]]] = {}

    def add(self, path: str, archetype: Any, n: int, **fields: list[Any]) -> None:
        """``n`` rows of ``fields`` (lists of length ``n``) at the current state."""
        _, store, lengths = self.rows.setdefault(path, (archetype, {}, []))
        for key, values in fields.items():
            store.setdefault(key, []).extend(values)
        lengths.append(n)

    def send(self, rec: rr.RecordingStream, times: list[rr.TimeColumn]) -> None:
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


def _log_run(
    rec: rr.RecordingStream,
    cols: _Columns,
    name: str,
    r: Record,
    state: GraspState,
    centre: NDArray,
    tvms_points: NDArray | None,
    color: tuple[int, ...],
) -> None:
    """One run (variant, reading) at one state: contacts, forces, polytopes, scalars, joints."""
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
        lo, hi = _panel(rng, w.box[j, [0, 2]]), _panel(rng, w.box[j, [1, 3]])
        cols.add(box, rr.Boxes2D, 1, half_sizes=[np.abs(hi - lo) / 2], centers=[(hi + lo) / 2])
        label = f"{name}: {tau:.3g} N m, {qd:.3g} rad/s" + (" (saturated)" if sat else "")
        cols.add(
            witness,
            rr.Points2D,
            1,
            positions=[_panel(rng, [tau, qd])],
            colors=[_SATURATED if sat else color],
            labels=[label],
            show_labels=[False],
        )


def blueprint(joints: Sequence[str], runs: Sequence[str]) -> rrb.Blueprint:
    """The layout: a 3-D view per run over the time series, and a grid of joint panels (a finger per row)."""
    eye = rrb.EyeControls3D(position=[0.4, -0.52, 0.26], look_target=[0.0, 0.0, 0.16], eye_up=[0.0, 0.0, 1.0])
    scenes = [
        rrb.Spatial3DView(
            origin="/scene",
            name=f"{run}: contacts, forces, velocity polytopes",
            eye_controls=eye,
            contents=["+ $origin/**", *(f"- /scene/{o}/**" for o in runs if o != run)],
        )
        for run in runs
    ]
    series = rrb.Horizontal(
        rrb.TimeSeriesView(origin="/tvmmp", name="TVMMP"),
        rrb.TimeSeriesView(origin="/alpha", name="alpha_kl"),
        rrb.TimeSeriesView(origin="/limiting", name="limiting (k, l)"),
    )
    bounds = rrb.VisualBounds2D(x_range=[-1.15, 1.15], y_range=[-1.15, 1.15])
    panels = [rrb.Spatial2DView(origin=f"/joints/{j}", name=j, visual_bounds=bounds) for j in joints]
    fingers = max(1, len({j.split("_")[0] for j in joints}))
    grid = rrb.Grid(*panels, grid_columns=-(-len(joints) // fingers), name="joints (tau, qdot)")
    left = rrb.Vertical(rrb.Horizontal(*scenes), series, row_shares=[3, 1])
    return rrb.Blueprint(
        rrb.Horizontal(left, grid, column_shares=[3, 2]),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline="state", play_state="paused"),
    )


def _run_names(keys: Sequence[_Run]) -> dict[_Run, str]:
    many = len({reading for variant, reading in keys if variant == "S"}) > 1
    return {(v, rd): f"{v}_{rd}" if v == "S" and many else v for v, rd in keys}


def _spawn(rec: rr.RecordingStream) -> rr.GrpcSink | None:
    """Spawn a viewer (the ``rerun`` beside Python or on PATH) if there is a display."""
    beside = Path(sys.executable).with_name("rerun")
    exe = str(beside) if beside.exists() else shutil.which("rerun")
    display = not sys.platform.startswith("linux") or any(
        os.environ.get(v) for v in ("DISPLAY", "WAYLAND_DISPLAY")
    )
    if exe is None or not display:
        print(f"no viewer spawned: {'no display' if exe else 'no rerun executable'}", file=sys.stderr)
        return None
    rr.spawn(connect=False, executable_path=exe, recording=rec)
    return rr.GrpcSink("rerun+http://127.0.0.1:9876/proxy")


def record_replay(
    output: ReplayOutput,
    path: str | Path | None = None,
    *,
    spawn: bool = False,
    tvms_every: int = TVMS_EVERY,
    recording_id: str | None = None,
) -> dict[str, Any]:
    r"""Record ``output`` (module docstring) to the ``.rrd`` file ``path`` and/or a spawned viewer.

    Parameters
    ----------
    output
        :func:`~mjtvm.apps.replay.run_replay`'s result.
    path
        The recording file (``None``: none).
    spawn
        Also stream to a newly spawned rerun viewer when one can run (a ``rerun`` executable
        and, on Linux, a display); otherwise say so on stderr.
    tvms_every
        Compute the TVMS at every ``tvms_every``-th state and the last; 0: never.
    recording_id
        The recording's id (default: random).

    Returns
    -------
    dict
        ``seconds`` (wall time), ``tvms_seconds``, ``tvms_states`` (indices), ``spawned``.
    """
    t0, lift, records = time.perf_counter(), output.lift, output.records
    rec = rr.RecordingStream(APPLICATION_ID, recording_id=recording_id)
    names = _run_names(list(dict.fromkeys((r.variant, r.reading) for r in records)))
    colors = {key: _RUN_COLORS[n % len(_RUN_COLORS)] for n, key in enumerate(names)}
    viewer = _spawn(rec) if spawn else None
    sinks = [s for s in (None if path is None else rr.FileSink(str(path)), viewer) if s is not None]
    info: dict[str, Any] = {"tvms_seconds": 0.0, "tvms_states": [], "spawned": viewer is not None}
    if not sinks:
        return {"seconds": time.perf_counter() - t0, **info}
    first = records[0].state
    joints = first.joint_names
    rec.set_sinks(*sinks, default_blueprint=blueprint(joints, list(names.values())))
    scene = _Scene(lift)
    scene.static(rec)
    axes = [[[-1.1, 0.0], [1.1, 0.0]], [[0.0, -1.1], [0.0, 1.1]]]
    for j, rng in zip(joints, first.operation_ranges, strict=True):
        rec.log(f"joints/{j}/axes", rr.LineStrips2D(axes, colors=(90, 90, 90), radii=-0.75), static=True)
        rec.log(
            f"joints/{j}/range",
            rr.LineStrips2D(
                [_panel(rng, _mirrored(rng))],
                colors=(200, 200, 200),
                radii=-1.5,
                show_labels=False,
                labels=f"{j}: {rng.max_torque:.3g} N m, {rng.max_speed:.3g} rad/s",
            ),
            static=True,
        )
        for key, name in names.items():
            rec.log(
                f"joints/{j}/{name}/box", rr.Boxes2D.from_fields(colors=colors[key], radii=-1.0), static=True
            )
            rec.log(f"joints/{j}/{name}/witness", rr.Points2D.from_fields(radii=-6.0), static=True)
    for key, name in names.items():
        rec.log(f"tvmmp/{name}", rr.SeriesLines(colors=colors[key], names=f"TVMMP {name}"), static=True)
        rec.log(f"limiting/{name}", rr.SeriesLines(names=[f"{name}: k", f"{name}: l"]), static=True)
    by_state = {(r.variant, r.reading, r.index): r for r in records}
    n = lift.num_states
    info["tvms_states"] = [] if tvms_every <= 0 else sorted({*range(0, n, tvms_every), n - 1})
    cols, z_steps = _Columns(), [round(float(z) / Z_UNIT) for z in lift.z]
    for i in range(n):
        rec.set_time("state", sequence=i)
        rec.set_time("lift_z", sequence=z_steps[i])
        centre = scene.log(cols, i)
        for key, name in names.items():
            r = by_state[(key[0], key[1], i)]
            state = r.state  # the state the replay solved
            t1 = time.perf_counter()
            # Problem 2 infeasible: some REFS vertex cannot be balanced, so S_ov is empty.
            wanted = i in info["tvms_states"] and r.result.feasible
            points = translational_tvms(state) if wanted else None
            info["tvms_seconds"] += time.perf_counter() - t1
            _log_run(rec, cols, name, r, state, centre, points, colors[key])
    cols.send(rec, [rr.TimeColumn("state", sequence=range(n)), rr.TimeColumn("lift_z", sequence=z_steps)])
    rec.flush()
    rec.disconnect()
    return {"seconds": time.perf_counter() - t0, **info}


def record_verify(
    rows: Sequence[Mapping[str, Any]], path: str | Path, *, recording_id: str | None = None
) -> dict[str, Any]:
    r"""Record the physics check of ``mjtvm verify`` (:func:`~mjtvm.physics.verify.verify_lift` rows).

    On the ``state`` and ``lift_z`` timelines of :func:`record_replay`, per run (``L``,
    ``S_literal``, ...): ``verify/<run>/tvmmp`` (min over l of the LP's alpha_kl),
    ``verify/<run>/alpha_sim`` (min over l of the simulated alpha_sim), one
    ``verify/<run>/ratio/l<l>`` per RVDS vertex (alpha_sim / alpha_kl), and the rollouts'
    failure reasons as a text log ``verify/<run>/failures``.

    Returns
    -------
    dict
        ``seconds`` (wall time) and ``runs`` (the run names logged).
    """
    t0 = time.perf_counter()
    rec = rr.RecordingStream(APPLICATION_ID, recording_id=recording_id)
    rec.set_sinks(rr.FileSink(str(path)))
    runs = list(dict.fromkeys(str(r["run"]) for r in rows))
    for n, run in enumerate(runs):
        color = _RUN_COLORS[n % len(_RUN_COLORS)]
        rec.log(f"verify/{run}/tvmmp", rr.SeriesLines(colors=color, names=f"TVMMP (LP) {run}"), static=True)
        rec.log(
            f"verify/{run}/alpha_sim",
            rr.SeriesPoints(colors=color, names=f"min alpha_sim {run}"),
            static=True,
        )
    by_state: dict[tuple[str, int], list[Mapping[str, Any]]] = {}
    for r in rows:
        by_state.setdefault((str(r["run"]), int(r["state"])), []).append(r)
    for (run, i), group in sorted(by_state.items(), key=lambda kv: (runs.index(kv[0][0]), kv[0][1])):
        rec.set_time("state", sequence=i)
        rec.set_time("lift_z", sequence=round(float(group[0]["z"]) / Z_UNIT))
        optimal = [r for r in group if r["status"] == "optimal"]
        if optimal:
            rec.log(f"verify/{run}/tvmmp", rr.Scalars(min(float(r["alpha_lp"]) for r in optimal)))
            rec.log(f"verify/{run}/alpha_sim", rr.Scalars(min(float(r["alpha_sim"]) for r in optimal)))
        for r in optimal:
            rec.log(f"verify/{run}/ratio/l{int(r['l'])}", rr.Scalars(float(r["ratio"])))
        reasons = [f"l{int(r['l'])}: {r['fail_reason']}" for r in optimal if r.get("fail_reason")]
        if reasons:
            rec.log(f"verify/{run}/failures", rr.TextLog("; ".join(reasons)))
    rec.flush()
    rec.disconnect()
    return {"seconds": time.perf_counter() - t0, "runs": runs}
