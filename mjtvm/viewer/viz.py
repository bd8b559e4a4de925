r"""Rerun recording of the lift replay (``mjtvm replay --rrd FILE``); with [`drawing`][mjtvm.viewer.drawing]
(what is drawn), the only modules importing rerun.

[`record_replay()`][mjtvm.viewer.viz.record_replay] logs a [`ReplayOutput`][mjtvm.jobs.replay.ReplayOutput] on two timelines, ``state``
(the state index) and ``lift_z`` (the object centre's height in micrometres: rerun timelines
are integer sequences, durations or timestamps). Entities (world frame, m; ``docs/rerun.md``):

* ``/scene/palm`` (static), ``/scene/links`` (capsules), ``/scene/tips``, ``/scene/object``
  (spheres), ``/scene/meshes/<k>`` (each colliding mesh geom, e.g. an object's convex pieces:
  its triangles, static, under a transform to the geom's pose): the MuJoCo geoms at each
  state's pose;
* ``/scene/<run>/contacts`` coloured by type ([`TYPE_COLORS`][mjtvm.viewer.drawing.TYPE_COLORS]), labelled ``geom type``;
  ``/scene/<run>/forces``: the contact forces of the limiting pair's witness
  ([`FORCE_SCALE`][mjtvm.viewer.drawing.FORCE_SCALE] m per N); ``/scene/<run>/slides``: S-point slide directions;
* ``/scene/<run>/distribution`` and ``/scene/<run>/tvms``: convex-hull meshes of object
  centre velocities (m/s) under a transform to the object's origin scaled by
  [`VELOCITY_SCALE`][mjtvm.viewer.drawing.VELOCITY_SCALE] m per m/s: the distribution polytope of Supplement 4 (the origin and
  $\min_k \alpha_{kl} \hat r_l$, translational part) and the TVMS of Problem 1
  ([`tvms()`][mjtvm.polytopes.tvms.tvms], its vertices projected onto the translational coordinates), the
  latter at every [`TVMS_EVERY`][mjtvm.viewer.viz.TVMS_EVERY]-th state and the last by default;
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

import rerun as rr
import rerun.blueprint as rrb

from mjtvm.jobs.replay import ReplayOutput
from mjtvm.viewer.drawing import Columns, Scene, log_run, mirrored, panel, translational_tvms

__all__ = [
    "APPLICATION_ID",
    "TVMS_EVERY",
    "Z_UNIT",
    "blueprint",
    "record_replay",
    "record_verify",
]

APPLICATION_ID = "mjtvm_replay"
Z_UNIT = 1e-6  #: m per step of the ``lift_z`` timeline
TVMS_EVERY = 5  #: default TVMS subsampling (11-28 ms per bounded state; docs/rerun.md)
_RUN_COLORS = ((60, 120, 235), (240, 150, 20), (190, 80, 200), (30, 190, 190))
_Run = tuple[str, str | None]


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
        [`run_replay()`][mjtvm.jobs.replay.run_replay]'s result.
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
    scene = Scene(lift)
    scene.static(rec)
    axes = [[[-1.1, 0.0], [1.1, 0.0]], [[0.0, -1.1], [0.0, 1.1]]]
    for j, rng in zip(joints, first.operation_ranges, strict=True):
        rec.log(f"joints/{j}/axes", rr.LineStrips2D(axes, colors=(90, 90, 90), radii=-0.75), static=True)
        rec.log(
            f"joints/{j}/range",
            rr.LineStrips2D(
                [panel(rng, mirrored(rng))],
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
    cols, z_steps = Columns(), [round(float(z) / Z_UNIT) for z in lift.z]
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
            log_run(rec, cols, name, r, state, centre, points, colors[key])
    cols.send(rec, [rr.TimeColumn("state", sequence=range(n)), rr.TimeColumn("lift_z", sequence=z_steps)])
    rec.flush()
    rec.disconnect()
    return {"seconds": time.perf_counter() - t0, **info}


def record_verify(
    rows: Sequence[Mapping[str, Any]], path: str | Path, *, recording_id: str | None = None
) -> dict[str, Any]:
    r"""Record the physics check of ``mjtvm verify`` ([`verify_lift()`][mjtvm.jobs.verify.verify_lift] rows).

    On the ``state`` and ``lift_z`` timelines of [`record_replay()`][mjtvm.viewer.viz.record_replay], per run (``L``,
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
