r"""The scripted lift (paper section 5, Fig. 7-8): grasp states along a prescribed object motion.

The object (its free joint) moves from the grasp's configuration along a constant or
piecewise-constant twist $\dot r = (v, \omega)$ about its origin $c$, per unit of a
path parameter s (`mjtvm.lift.motion`: a direction, a twist or a list of poses; default
+z, the paper's Case 2, where s is the height gained in m). F-points stay fixed on the object
(the finger-fixed point on the object-fixed point). Every finger moves by the paper's
minimum-norm joint motion $\dot q = J_c^+ G_c^T \dot r$, where $J_c, G_c$ hold the
constraint rows: the three rows of an F-point (eq. 7), the normal row $n^T$ of an L- or
S-point (eq. 8). $J_c$ is block diagonal, so per finger $\dot q_i = J_i^+ u$ (F)
or $\dot q_i = J_{n,i}^T (n^T u) / |J_{n,i}|^2$, $J_{n,i} = n^T J_i$ (L/S), with
$u = G^T \dot r = v + \omega \times (p - c)$ the velocity of the object's point at the
contact $p$. The motion is integrated (explicit Euler, steps of at most ``max_step`` in s);
after every step an IK correction (`solve_ik()`, within the lift's joint
bounds) puts each F-point back on its object-fixed point and each L/S finger back on the surface:

* contact geometry (`mjtvm.lift.surface`): the finger geom (any primitive) and the nearest
  object geom (sphere, box, cylinder or capsule) give witness points and the normal by
  ``mj_geomDistance``; a sphere fingertip on a sphere object in closed form (radial projection);
* a sphere fingertip is placed by its centre: on an L/S-point at the object's witness point
  plus its radius along the outward normal (exact in one IK solve), on an F-point at the
  object-fixed point of its start contact, offset by its radius along the object-fixed normal;
* any other L/S finger geom: its witness point (fixed to its body) goes onto the object's
  witness point; retargeted and solved again until the surface distance is within
  ``tolerance``; any other F geom: its start contact point, fixed to its body, onto the
  object-fixed point.

*Drift*: the IK residual before the correction that produced a state; *residual*: after it
(for a retargeted L/S geom, the larger of the IK residual and the surface distance).

The lift ends at the *reach limit*, the largest s where the correction converges within
``tolerance`` for every finger and the pose is admissible: no geom other than the grasp's
contacts (the lift's fingers, its D geoms) and ignored geoms touches the object, and no
finger geom penetrates a support (D) geom deeper than at the start (by more than
`TOUCH_TOL`; a link anchored in the palm keeps its start penetration): marching with
``max_step``, then bisecting the failing step to ``limit_tolerance``. The N states are evenly
spaced in s on the marched path (the marched state below each, plus one partial step).

The grasp states along a lift, with the S-points' slide directions, are
[`mjtvm.lift.states`][mjtvm.lift.states].
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import ModelError, StateError
from mjtvm.grasp.resolve.file import load_grasp
from mjtvm.lift.march import TOUCH_TOL, GraspLike, Marcher
from mjtvm.lift.motion import Motion

__all__ = ["STOP_MARGIN", "TOUCH_TOL", "Lift", "LiftSpec", "scripted_lift"]

STOP_MARGIN = 0.25
"""Default stop margin: a finger's contact Jacobian keeps at least a quarter of its smallest
singular value at the start ([`scripted_lift()`][mjtvm.lift.trajectory.scripted_lift])."""
_MAX_STEPS = 100_000  # marched steps: a motion the fingers follow forever is a scripting error
_Path = list[tuple[float, mujoco.MjData, dict[str, Any]]]


@dataclass(frozen=True, eq=False)
class LiftSpec:
    r"""A grasp's scripted lift (the grasp file's ``[lift]``): the motion, its length, the IK bounds.

    Attributes
    ----------
    twist
        ``(6,)`` $(v, \omega)$ per unit s about the object's origin, world frame (m, rad);
        a direction d is the twist ``(d / |d|, 0)`` (`from_direction()`). With ``poses``
        ``None``; both ``None``: +z.
    poses
        ``(K, 7)`` object poses (position m, quaternion w x y z) to pass through, or ``None``.
    height
        Move by this much of s (m for a direction) instead of up to the reach limit (or the
        last pose).
    bounds
        Joint name -> (low, high) rad for the lift's IK, over the grasp's ``ik_bounds``.
    """

    twist: NDArray[np.float64] | None = None
    poses: NDArray[np.float64] | None = None
    height: float | None = None
    bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.twist is not None and self.poses is not None:
            raise StateError("lift", "expected a twist or poses, not both")
        for name in ("twist", "poses"):
            if getattr(self, name) is not None:
                value = np.array(getattr(self, name), dtype=float)
                value.setflags(write=False)
                object.__setattr__(self, name, value)
        Motion(np.array([0, 0, 0, 1.0, 0, 0, 0]), twist=self.twist, poses=self.poses)  # validates
        if self.height is not None and not (math.isfinite(self.height) and self.height > 0):
            raise StateError("height", f"expected a positive length, got {self.height!r}")

    @classmethod
    def from_direction(cls, direction: ArrayLike, **options: Any) -> LiftSpec:
        """The lift translating the object along ``direction`` ``(3,)`` (normalised)."""
        d = np.array(direction, dtype=float)
        if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.linalg.norm(d) > 0:
            raise StateError("direction", f"expected 3 finite numbers, not all 0, got {direction!r}")
        return cls(twist=np.concatenate([d / np.linalg.norm(d), np.zeros(3)]), **options)


@dataclass(frozen=True, eq=False)
class Lift:
    r"""A scripted lift: N states of the hand and the object (world frame, m, rad).

    Attributes
    ----------
    scenario
        The grasp at its initial state (a paper case's or another grasp
        file's ``Grasp``: model, joints, REFS, RVDS, ...).
    s, z, poses, twists
        ``(N,)`` path parameter, evenly spaced from 0 (`mjtvm.lift.motion`; m for a
        direction, the height gained for +z); ``(N,)`` the object origin's height; ``(N, 7)``
        its pose (m; quaternion w x y z); ``(N, 6)`` the twist $\dot r$ per unit s there.
    qpos
        ``(N, nq)`` MuJoCo configuration.
    joints
        The M state joints (the grasp's), the column order of ``rates``.
    geoms, roles
        The G finger contact geoms (labels) and their roles, ``"F"`` (fixed on the object) or
        ``"N"`` (normal row only: an L- or S-point).
    points
        ``(N, G, 3)`` contact point of each geom (on the finger's surface).
    rates
        ``(N, M)`` minimum-norm joint motion per unit s $J_c^+ G_c^T \dot r$ (rad per unit s).
    slips
        ``(N, G, 3)`` physical slip $T^T T (G^T \dot r - J \dot q)$ of each N-geom per unit
        s (not normalised; zero rows for F-geoms).
    drift, residual
        ``(N, G)`` IK residual before and after the correction that produced the state (m);
        the drift is 0 at the initial state.
    base, base_contact
        The support (D) geoms and ``(N,)`` whether one touches the object (a D-point exists).
    touching
        Per state, every geom touching the object.
    limit
        Why the lift ends there (the first failing finger and its residual, or the length).
    max_step, tolerance, marched
        Integration step (in s), IK tolerance (m), and the number of steps marched.
    """

    scenario: Any
    s: NDArray[np.float64]
    z: NDArray[np.float64]
    poses: NDArray[np.float64]
    twists: NDArray[np.float64]
    qpos: NDArray[np.float64]
    joints: tuple[str, ...]
    geoms: tuple[str, ...]
    roles: tuple[str, ...]
    points: NDArray[np.float64]
    rates: NDArray[np.float64]
    slips: NDArray[np.float64]
    drift: NDArray[np.float64]
    residual: NDArray[np.float64]
    base: tuple[str, ...]
    base_contact: NDArray[np.bool_]
    touching: tuple[tuple[str, ...], ...]
    limit: str
    max_step: float
    tolerance: float
    marched: int

    @property
    def num_states(self) -> int:
        """N."""
        return int(self.s.shape[0])


def _as_spec(value: LiftSpec | Mapping[str, Any] | None, grasp: GraspLike) -> LiftSpec | None:
    """A grasp's ``lift``: a [`LiftSpec`][mjtvm.lift.trajectory.LiftSpec], or the grasp file's normalised ``[lift]`` table
    (``direction``/``twist``/``poses`` of ``{position, quaternion}``, ``height``, ``bounds``; a pose
    without quaternion keeps the orientation before it)."""
    if value is None or isinstance(value, LiftSpec):
        return value
    options: dict[str, Any] = {"height": value.get("height"), "bounds": dict(value.get("bounds") or {})}
    if value.get("direction") is not None:
        return LiftSpec.from_direction(value["direction"], **options)
    if value.get("poses") is not None:
        ob = int(grasp.model.body(grasp.object_body).id)
        quat, poses = np.array(grasp.data.xquat[ob], dtype=float), []
        for pose in value["poses"]:
            quat = quat if pose.get("quaternion") is None else np.array(pose["quaternion"], dtype=float)
            poses.append([*pose["position"], *quat])
        return LiftSpec(poses=np.array(poses), **options)
    twist = value.get("twist")
    return LiftSpec(twist=None if twist is None else np.array(twist, dtype=float), **options)


def _motion_options(
    grasp: GraspLike,
    direction: ArrayLike | None,
    twist: ArrayLike | None,
    poses: ArrayLike | None,
    height: float | None,
) -> tuple[LiftSpec, Mapping[str, tuple[float, float]]]:
    """The lift's motion (arguments, else the grasp's ``lift``, else +z) and IK bounds."""
    given = [
        name for name, v in (("direction", direction), ("twist", twist), ("poses", poses)) if v is not None
    ]
    if len(given) > 1:
        raise StateError(given[1], f"give one of direction, twist and poses, got {' and '.join(given)}")
    spec = _as_spec(getattr(grasp, "lift", None), grasp)
    if direction is not None:
        motion = LiftSpec.from_direction(direction, height=height)
    elif twist is not None or poses is not None:
        motion = LiftSpec(
            twist=None if twist is None else np.asarray(twist, dtype=float),
            poses=None if poses is None else np.asarray(poses, dtype=float),
            height=height,
        )
    elif spec is not None:
        motion = spec if height is None else replace(spec, height=height)
    else:
        motion = LiftSpec(height=height)
    bounds: Mapping[str, Any] | None = getattr(grasp, "ik_bounds", None)
    if bounds is None:  # a shipped scenario: its variant's bounds
        bounds = grasp.document.get("variants", {}).get(getattr(grasp, "variant", None), {}).get("bounds", {})
    merged = {
        k: (float(lo), float(hi))
        for k, (lo, hi) in {**(bounds or {}), **(spec.bounds if spec else {})}.items()
    }
    return motion, merged


def scripted_lift(
    grasp: str | GraspLike = "case2",
    *,
    variant: str = "default",
    num_states: int = 30,
    direction: ArrayLike | None = None,
    twist: ArrayLike | None = None,
    poses: ArrayLike | None = None,
    height: float | None = None,
    max_step: float = 1e-3,
    tolerance: float = 1e-10,
    limit_tolerance: float = 1e-5,
    max_iterations: int = 100,
    stop_margin: float | None = None,
) -> Lift:
    r"""Move the grasp's object (module docstring) and sample ``num_states`` states.

    Parameters
    ----------
    grasp, variant
        A shipped scenario name and hand variant (``"default"``, ``"humanlike"``), or a grasp
        at its initial state: a paper case's or another grasp file's ``Grasp``.
    num_states
        N >= 2, evenly spaced in s from the start to the end of the lift; 1: the grasp's own
        state alone, nothing marched (its ``rates`` and ``slips`` those of the motion at s = 0).
    direction, twist, poses
        At most one: the object's motion (`mjtvm.lift.motion`): ``(3,)`` a direction
        (normalised), ``(6,)`` a twist $(v, \omega)$ about the object's origin (world
        frame), or ``(K, 7)`` poses (position, quaternion w x y z). Default: the grasp's
        ``lift`` ([`LiftSpec`][mjtvm.lift.trajectory.LiftSpec]), else +z.
    height
        Move by this much of s (m for a direction) instead of up to the reach limit (or the
        last pose); must be within reach.
    max_step, tolerance, limit_tolerance, max_iterations
        Largest integration step in s, IK tolerance per target (m), bisection width of the
        reach limit (in s); IK iteration budget per correction.
    stop_margin
        End the lift where a finger's contact Jacobian's smallest singular value falls below
        this fraction of its value at the start (a margin from the singular, stretched pose
        where the paper's "nearly stretched" finger ends; 0: go to the reach limit). Default:
        the grasp's ``lift.stop_margin``, else [`STOP_MARGIN`][mjtvm.lift.trajectory.STOP_MARGIN].

    Raises
    ------
    StateError
        Bad options.
    ModelError
        A grasp the lift cannot move, an initial state not admissible, or a ``height``
        beyond reach (naming the failing finger).
    """
    if isinstance(num_states, bool) or not isinstance(num_states, int) or num_states < 1:
        raise StateError("num_states", f"expected an integer >= 1, got {num_states!r}")
    for name, value in (
        ("max_step", max_step),
        ("tolerance", tolerance),
        ("limit_tolerance", limit_tolerance),
        ("height", 1.0 if height is None else height),
    ):
        if not (math.isfinite(value) and value > 0):
            raise StateError(name, f"expected a positive length (m), got {value!r}")
    sc: GraspLike = load_grasp(grasp, hand=variant) if isinstance(grasp, str) else grasp
    spec, bounds = _motion_options(sc, direction, twist, poses, height)
    ob = int(sc.model.body(sc.object_body).id)
    start = np.concatenate([sc.data.xpos[ob], sc.data.xquat[ob]])
    motion = Motion(start, twist=spec.twist, poses=spec.poses)
    if stop_margin is None:
        lift_doc = getattr(sc, "lift", None)
        stop_margin = lift_doc.get("stop_margin") if isinstance(lift_doc, Mapping) else None
        stop_margin = STOP_MARGIN if stop_margin is None else float(stop_margin)
    if not (math.isfinite(stop_margin) and 0.0 <= stop_margin < 1.0):
        raise StateError("stop_margin", f"expected a fraction in [0, 1), got {stop_margin!r}")
    m = Marcher(
        sc, motion, bounds=bounds, tolerance=tolerance, max_iterations=max_iterations, stop_margin=stop_margin
    )
    data = copy.copy(sc.data)
    if why := m.inadmissible(data):
        raise ModelError(f"grasp {sc.name!r}", f"initial state not admissible: {why}")
    mujoco.mj_kinematics(sc.model, data)
    res0 = m.drift(data, m.targets(data))
    path: _Path = [(0.0, data, {"drift": np.zeros(len(m.fingers)), "residual": res0})]
    if num_states == 1:  # the grasp's own state: nothing to march
        return _sample(m, path, 1, limit="one state", max_step=max_step, tolerance=tolerance)
    length = spec.height if spec.height is not None else motion.length
    limit = f"requested height {spec.height} m" if spec.height is not None else "the last pose"
    while path[-1][0] < length:
        s, d, _ = path[-1]
        if len(path) > _MAX_STEPS:
            raise ModelError("lift", f"no reach limit within {_MAX_STEPS} steps: give a height")
        ds = min(max_step, length - s, motion.segment_end(s) - s)
        nxt, info = m.step(d, s, ds)
        if info["ok"]:
            path.append((s + ds, nxt, info))
            continue
        if math.isfinite(length):
            raise ModelError(
                "lift.height",
                f"{length:g} m is beyond reach (omit it to lift to the reach limit): {info['why']}",
            )
        limit, lo, hi, best = info["why"], 0.0, ds, None
        while hi - lo > limit_tolerance:  # bisect the failing step
            mid = 0.5 * (lo + hi)
            trial, tinfo = m.step(d, s, mid)
            if tinfo["ok"]:
                lo, best = mid, (s + mid, trial, tinfo)
            else:
                hi, limit = mid, tinfo["why"]
        path += [best] if best is not None else []
        limit = limit if limit.startswith("stop margin") else f"reach limit: {limit}"
        break
    if len(path) < 2:
        raise ModelError(f"grasp {sc.name!r}", f"the object cannot be moved: {limit}")
    return _sample(m, path, num_states, limit=limit, max_step=max_step, tolerance=tolerance)


def _sample(m: Marcher, path: _Path, n: int, **meta: Any) -> Lift:
    """``n`` states evenly spaced in s along the marched ``path`` (one partial step from below)."""
    ss = np.array([p[0] for p in path])
    grid, g, sc = np.linspace(ss[0], ss[-1], n), len(m.fingers), m.grasp
    qpos, poses, twists = np.zeros((n, sc.model.nq)), np.zeros((n, 7)), np.zeros((n, 6))
    points, slips = np.zeros((n, g, 3)), np.zeros((n, g, 3))
    rates, drift, residual = np.zeros((n, len(sc.joints))), np.zeros((n, g)), np.zeros((n, g))
    touching = []
    for i, s in enumerate(grid):
        sk, data, info = path[min(int(np.searchsorted(ss, s, side="right")) - 1, len(path) - 1)]
        if s - sk <= 1e-12:
            grid[i] = s = sk
        elif not (step := m.step(data, sk, float(s - sk)))[1]["ok"]:
            raise ModelError("lift", f"a state between two reached states failed: {step[1]['why']}")
        else:
            data, info = step
        qpos[i], poses[i], twists[i] = data.qpos, m.pose(data), m.motion.twist(float(s))
        points[i], rates[i], slips[i] = m.kinematics(m.copy_to_scratch(data), float(s))
        drift[i], residual[i] = info["drift"], info["residual"]
        touching.append(tuple(dict.fromkeys(geom for geom, _ in m.touching(m.copy_to_scratch(data)))))
    base_contact = np.array([any(b in t for b in m.base) for t in touching])
    z = poses[:, 2].copy()
    for a in (grid, z, poses, twists, qpos, points, rates, slips, drift, residual, base_contact):
        a.setflags(write=False)
    return Lift(
        scenario=sc,
        s=grid,
        z=z,
        poses=poses,
        twists=twists,
        qpos=qpos,
        joints=sc.joints,
        geoms=tuple(f.geom for f in m.fingers),
        roles=tuple(f.role for f in m.fingers),
        points=points,
        rates=rates,
        slips=slips,
        drift=drift,
        residual=residual,
        base=m.base,
        base_contact=base_contact,
        touching=tuple(touching),
        marched=len(path) - 1,
        **meta,
    )
