r"""A grasp document's configuration in a model's ``mjData``: its keyframe, joint values and
poses, and by IK finger geoms or sites brought onto the object's surface
(``configuration.ik`` of a grasp file, ``docs/grasp-format.md``).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError
from mjtvm.grasp.document.checks import GraspError, key_of
from mjtvm.grasp.resolve.base import hold_mocap_poses, set_base_pose, set_joint_values
from mjtvm.grasp.resolve.ik import IkTarget, solve_ik
from mjtvm.grasp.resolve.model import geom_labels, joint_id, names_of, object_geoms, set_object_pose, suggest
from mjtvm.grasp.resolve.state import geom_id, geom_label, precise_collision

__all__ = ["POINT_TOLERANCE", "configured_data", "solve_configuration"]

_OBJ = mujoco.mjtObj


POINT_TOLERANCE = 1e-3  # m: how close a geom's contact must come to its target point along the surface


def _geom_target(
    model: mujoco.MjModel, work: mujoco.MjData, g: int, obj: Sequence[int], point: Any, file: str, field: str
) -> tuple[IkTarget, float, float]:
    """The IK target moving geom ``g``'s point nearest the object onto ``point`` (or onto the
    object's nearest surface point), its surface distance and its offset from ``point`` (m)."""
    d, best, fromto = np.inf, np.zeros(6), np.zeros(6)
    for o in obj:
        dist = float(mujoco.mj_geomDistance(model, work, o, g, 1.0, fromto))
        if dist < d:
            d, best = dist, fromto.copy()
    if not np.isfinite(d) or d >= 1.0:
        raise GraspError(
            file, f"{field}.geom", f"geom {geom_label(model, g)!r} is more than 1 m from the object"
        )
    body = int(model.geom_bodyid[g])
    finger_point = best[3:]
    surface = best[:3] if point is None else np.array(point, dtype=float)
    local = data_xmat(work, body).T @ (finger_point - work.xpos[body])
    name = mujoco.mj_id2name(model, _OBJ.mjOBJ_BODY, body) or ""
    offset = 0.0 if point is None else float(np.linalg.norm(finger_point - surface))
    return IkTarget(geom_label(model, g), name, local, surface), abs(d), offset


def solve_configuration(
    model: mujoco.MjModel, data: mujoco.MjData, ik: Mapping[str, Any], ob: int, file: str
) -> mujoco.MjData:
    r"""IK: each target's finger point onto the object's surface (retargeted until it touches).

    A site goes to its ``point`` (within ``tolerance``). A geom's point nearest the object
    (``mj_geomDistance``) goes to ``point`` when given (a point on the object's surface), else
    to the object's nearest surface point; the nearest points move as the finger turns, so
    the targets are recomputed and the IK rerun until every geom touches the surface (distance
    within ``tolerance``) within [`POINT_TOLERANCE`][mjtvm.grasp.resolve.configure.POINT_TOLERANCE] (1 mm) of its ``point``: where a flat
    face meets a curved surface the nearest point is not unique (it jumps along the line of
    contact as the finger turns), the witness points of curved shapes are iterative (about
    1e-6 m), and a finger may be unable to move along the surface at all (e.g. out of its plane).
    """
    obj = object_geoms(model, ob)
    bounds = dict(ik["bounds"])
    for name in bounds:
        joint_id(model, name, file, f"configuration.ik.bounds.{key_of(name)}")
    resolved = []
    for i, t in enumerate(ik["targets"]):
        field = f"configuration.ik.targets[{i}]"
        if "site" in t:
            s = mujoco.mj_name2id(model, _OBJ.mjOBJ_SITE, t["site"])
            if s < 0:
                raise GraspError(
                    file,
                    f"{field}.site",
                    f"{t['site']!r} is not a site of the model"
                    f"{suggest(t['site'], names_of(model, _OBJ.mjOBJ_SITE, model.nsite))}",
                )
            resolved.append(("site", s, t["point"], field))
            continue
        try:
            resolved.append(("geom", geom_id(model, t["geom"]), t["point"], field))
        except ModelError as e:
            names = geom_labels(model)
            raise GraspError(
                file, f"{field}.geom", f"{t['geom']!r} is not a geom of the model{suggest(t['geom'], names)}"
            ) from e
    with precise_collision(model):
        return _settle_targets(model, data, resolved, obj, bounds, ik, file)


def configured_data(model: mujoco.MjModel, doc: Mapping[str, Any], ob: int, file: str) -> mujoco.MjData:
    """``mjData`` of ``model`` at the grasp document's configuration (its keyframe, then its
    joint values, base pose and the object's pose, then its IK if any), after ``mj_forward``;
    ``ob`` is the object body's id, ``file`` names the document in errors.

    Raises
    ------
    GraspError
        An unknown keyframe, joint or base; an IK that does not converge.
    """
    data, config = mujoco.MjData(model), doc["configuration"]
    if "keyframe" in config:
        key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, config["keyframe"])
        if key < 0:
            keys = names_of(model, mujoco.mjtObj.mjOBJ_KEY, model.nkey)
            raise GraspError(
                file,
                "configuration.keyframe",
                f"{config['keyframe']!r} is not a keyframe of the model (has: {', '.join(keys) or 'none'})",
            )
        mujoco.mj_resetDataKeyframe(model, data, key)
    values = config.get("qpos") or (config["ik"]["start"] if "ik" in config else {})
    where = "configuration.qpos" if "qpos" in config else "configuration.ik.start"
    set_joint_values(model, data, values, file, where)
    if "base" in config:
        set_base_pose(model, data, config["base"], file)
    hold_mocap_poses(model, data)
    set_object_pose(model, data, ob, doc["object"], file)
    mujoco.mj_forward(model, data)
    if "ik" in config:
        data = solve_configuration(model, data, config["ik"], ob, file)
    return data


def _settle_targets(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    resolved: Sequence[tuple[str, int, Any, str]],
    obj: Sequence[int],
    bounds: Mapping[str, tuple[float, float]],
    ik: Mapping[str, Any],
    file: str,
) -> mujoco.MjData:
    """The rounds of `_solve_configuration()`: retarget, solve, until settled."""
    tol = float(ik["tolerance"])
    work = copy.copy(data)
    worst, last = "", np.inf
    for _round in range(30):
        targets, misses = [], []
        for kind, k, point, field in resolved:
            if kind == "site":
                body = int(model.site_bodyid[k])
                name = mujoco.mj_id2name(model, _OBJ.mjOBJ_BODY, body) or ""
                targets.append(
                    IkTarget(
                        str(mujoco.mj_id2name(model, _OBJ.mjOBJ_SITE, k)),
                        name,
                        np.array(model.site_pos[k]),
                        np.array(point),
                    )
                )
                misses.append((float(np.linalg.norm(work.site_xpos[k] - np.array(point))) - tol, 0.0))
            else:
                target, gap, offset = _geom_target(model, work, k, obj, point, file, field)
                targets.append(target)
                misses.append((gap - tol, offset))
        gaps, offsets = [m[0] for m in misses], [m[1] for m in misses]
        if max(gaps) <= 0.0 and (max(offsets) <= tol or max(offsets) >= 0.99 * last):
            if max(offsets) <= POINT_TOLERANCE:  # touching, and as near the points as it gets
                return work
        last = max(offsets)
        w = int(np.argmax([max(g, o - POINT_TOLERANCE) for g, o in misses]))
        worst = (
            f"{resolved[w][3]}: does not settle on the object's surface in 30 rounds (surface "
            f"distance {1e3 * (gaps[w] + tol):.3g} mm, {1e3 * offsets[w]:.3g} mm from its point)"
        )
        result = solve_ik(
            model,
            work,
            targets,
            bounds=bounds,
            tolerance=tol,
            max_iterations=int(ik["max_iterations"]),
            strict=False,
        )
        if float(np.max(result.residuals)) > 1e-4:  # far beyond the witness points' noise: out of reach
            w = int(np.argmax(result.residuals))
            raise GraspError(
                file,
                resolved[w][3],
                f"unreachable: residual {1e3 * float(result.residuals[w]):.3g} mm after {result.iterations} "
                "iterations (joint limits, bounds, or too far)",
            )
        work.qpos[:] = result.qpos
        mujoco.mj_forward(model, work)
    field, problem = worst.split(": ", 1)
    raise GraspError(file, field, problem)


def data_xmat(data: mujoco.MjData, body: int) -> NDArray[np.float64]:
    return np.array(data.xmat[body], dtype=float).reshape(3, 3)
