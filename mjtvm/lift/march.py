r"""The predictor-corrector of a scripted lift ([`mjtvm.lift.trajectory`][mjtvm.lift.trajectory], whose docstring
describes the method): per finger its role, contact geometry and IK target; one step; admissibility.

World frame, m, rad; s is the motion's parameter (`mjtvm.lift.motion`).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.transmission import coupled_joints
from mjtvm.grasp.resolve.ik import IkTarget, body_label, ik_residual, solve_ik
from mjtvm.grasp.resolve.state import detected_contacts, geom_id, geom_label
from mjtvm.lift.motion import Motion, rotate
from mjtvm.lift.surface import OBJECT_TYPES, distance_model, is_sphere, witness

__all__ = ["TOUCH_TOL", "GraspLike", "Marcher", "start_tolerance"]

TOUCH_TOL = 1e-6  # m: a geom within this distance of the object touches it
_MAX_ROUNDS = 30  # retargeting rounds of one correction (each converges quadratically)


class GraspLike(Protocol):
    """What the lift reads of a grasp: a [`Grasp`][mjtvm.grasp.resolve.loaded.Grasp] or the grasp
    file's ``Grasp`` (which adds ``lift`` and ``ik_bounds``, read with ``getattr``)."""

    @property
    def name(self) -> str: ...
    @property
    def model(self) -> mujoco.MjModel: ...
    @property
    def data(self) -> mujoco.MjData: ...
    @property
    def joints(self) -> tuple[str, ...]: ...
    @property
    def contact_types(self) -> Mapping[str, str]: ...
    @property
    def mu(self) -> float | Mapping[str, float]: ...
    @property
    def refs(self) -> NDArray[np.float64]: ...
    @property
    def rvds(self) -> NDArray[np.float64] | None: ...
    @property
    def ignored_geoms(self) -> tuple[str, ...]: ...
    @property
    def object_body(self) -> str: ...
    @property
    def document(self) -> Mapping[str, Any]: ...


@dataclass(frozen=True, eq=False)
class _Finger:
    geom: str  # label
    role: str  # "F" or "N"
    geom_id: int
    body: int
    object_geom: int  # the object geom it touches (nearest at the start; an F-finger's for good)
    sphere: bool  # placed by its centre (module docstring)
    dofs: NDArray[np.int64]  # the finger's columns in the model's nv
    cols: NDArray[np.int64]  # the same in the lift's joints
    rel: NDArray[np.float64]  # F: start contact point minus object origin (m, world frame at the start)
    normal: NDArray[np.float64]  # F: start normal into the object
    local: NDArray[np.float64]  # F, not a sphere: the start contact point in the finger body's frame


def _subtree(model: mujoco.MjModel, roots: set[int]) -> set[int]:
    out = set(roots)
    for b in range(1, model.nbody):  # parents precede children in mjModel
        if int(model.body_parentid[b]) in out:
            out.add(b)
    return out


def _chain(model: mujoco.MjModel, body: int) -> set[int]:
    out: set[int] = set()
    while body > 0:
        out, body = out | {body}, int(model.body_parentid[body])
    return out


class Marcher:
    """The predictor-corrector of one lift (module docstring)."""

    def __init__(
        self,
        grasp: GraspLike,
        motion: Motion,
        *,
        bounds: Mapping[str, tuple[float, float]],
        tolerance: float,
        max_iterations: int,
        stop_margin: float = 0.0,
    ) -> None:
        self.grasp, self.model, self.motion = grasp, grasp.model, motion
        self.stop_margin = stop_margin
        self.scratch = mujoco.MjData(grasp.model)  # reused by the IK and the sampling: no allocations
        self.tol, self.max_it, self.bounds = tolerance, max_iterations, dict(bounds)
        model = grasp.model
        self.dmodel = distance_model(model)
        self.ob = ob = int(model.body(grasp.object_body).id)
        free = [j for j in range(model.njnt) if int(model.jnt_bodyid[j]) == ob]
        if len(free) != 1 or int(model.jnt_type[free[0]]) != int(mujoco.mjtJoint.mjJNT_FREE):
            raise ModelError(f"body {grasp.object_body!r}", "the lift needs the object on one free joint")
        self.padr = int(model.jnt_qposadr[free[0]])
        inside = _subtree(model, {ob})
        # the object is moved by its body pose, whatever its geoms; fingers are kept on its
        # colliding solids (a visual mesh, contype = conaffinity = 0, is not a surface)
        objects = [
            g
            for g in range(model.ngeom)
            if int(model.geom_bodyid[g]) in inside
            and int(model.geom_type[g]) in OBJECT_TYPES
            and (int(model.geom_contype[g]) or int(model.geom_conaffinity[g]))
        ]
        if not objects:
            raise ModelError(
                f"body {grasp.object_body!r}",
                "no colliding sphere, capsule, ellipsoid, cylinder, box or mesh geom to lift",
            )
        self.objects = tuple(objects)
        data = copy.copy(grasp.data)
        mujoco.mj_kinematics(model, data)
        self.c0, self.q0 = np.array(data.xpos[ob]), np.array(data.qpos[self.padr + 3 : self.padr + 7])
        fingers, base = [], []
        for label, kind in grasp.contact_types.items():
            g = geom_id(model, label)
            if kind == "D":
                base.append(label)
                continue
            if int(model.geom_bodyid[g]) in inside:
                raise ModelError(f"contact_types[{label!r}]", f"an {kind} geom of the object itself")
            near = min(((witness(self.dmodel, data, o, g), o) for o in objects), key=lambda w: w[0].distance)
            if kind in ("F", "L", "S") and near[0].distance <= start_tolerance(grasp):
                fingers.append(self._finger(data, label, kind, g, *near))
        if not fingers:
            raise ModelError("contact_types", "no F, L or S geom touches the object at the start")
        self.fingers, self.base = tuple(fingers), tuple(base)
        self.joint_names = tuple(grasp.joints[k] for f in fingers for k in f.cols)
        self.joint_names = tuple(dict.fromkeys(self.joint_names))  # fingers sharing a chain
        if model.neq:  # a linkage: the joints its equalities tie to the fingers' move with them
            tied = set(coupled_joints(model, data, [int(model.joint(j).id) for j in self.joint_names]))
            self.joint_names = tuple(j for j in grasp.joints if int(model.joint(j).id) in tied)
        self.qadr = np.array([int(model.joint(j).qposadr[0]) for j in self.joint_names], dtype=int)
        self.qcols = np.array([grasp.joints.index(j) for j in self.joint_names], dtype=int)
        self.allowed = {f.geom for f in fingers} | set(base) | set(grasp.ignored_geoms)
        moved = _subtree(model, {int(model.joint(j).bodyid[0]) for j in self.joint_names}) - inside
        self.pairs = []  # (finger geom, support geom, start distance): no deeper than at the start
        for b in map(lambda label: geom_id(model, label), base):
            for g in range(model.ngeom):
                if int(model.geom_bodyid[g]) in moved and int(model.geom_bodyid[b]) not in _chain(
                    model, int(model.geom_bodyid[g])
                ):
                    d0 = float(mujoco.mj_geomDistance(self.dmodel, data, b, g, 1.0, None))
                    self.pairs.append((g, b, d0))
        mujoco.mj_forward(model, data)
        start = self._singular_values(data)
        # the rank each finger has at the start (a planar finger moves its point in a plane: 2)
        self.rank0 = [max(1, int(np.sum(sv > 1e-9 * sv[0]))) for sv in start]
        self.sigma0 = np.array([sv[r - 1] for sv, r in zip(start, self.rank0, strict=True)])

    def _singular_values(self, data: mujoco.MjData) -> list[NDArray[np.float64]]:
        jacp, out = np.zeros((3, self.model.nv)), []
        for f in self.fingers:
            point = self._contact(data, f)[0]
            mujoco.mj_jac(self.model, data, jacp, None, point, f.body)
            out.append(np.linalg.svd(jacp[:, f.dofs], compute_uv=False))
        return out

    def sigmas(self, data: mujoco.MjData) -> NDArray[np.float64]:
        """``(G,)`` per finger, the singular value of its contact Jacobian (m/rad; its joints'
        columns, kinematics done) of the rank it has at the start (the smallest of a spatial
        finger's three, the second of a planar finger's): 0 at a singular, stretched pose."""
        return np.array([sv[r - 1] for sv, r in zip(self._singular_values(data), self.rank0, strict=True)])

    def _piece(self, data: mujoco.MjData, f: _Finger) -> int:
        """The object geom the finger is on at ``data`` (geom poses done): an F-finger's from the
        start, fixed to it; an L or S finger slides and may pass from one convex piece of the
        object onto the next, so its piece is the nearest one now."""
        if f.role == "F" or len(self.objects) == 1:
            return f.object_geom
        return min(
            self.objects,
            key=lambda o: float(mujoco.mj_geomDistance(self.dmodel, data, o, f.geom_id, 1.0, None)),
        )

    def _finger(self, data: mujoco.MjData, label: str, kind: str, g: int, w: Any, o: int) -> _Finger:
        model, grasp = self.model, self.grasp
        body = int(model.geom_bodyid[g])
        chain = _chain(model, body)
        joints = [j for j in grasp.joints if int(model.joint(j).bodyid[0]) in chain]
        if not joints:
            raise ModelError(f"geom {label!r}", "no joint of the grasp moves it")
        p0 = 0.5 * (w.object_point + w.finger_point)  # MuJoCo's contact point: midway
        local = data.xmat[body].reshape(3, 3).T @ (p0 - data.xpos[body])
        return _Finger(
            label,
            "F" if kind == "F" else "N",
            g,
            body,
            o,
            is_sphere(model, g),
            np.array([int(model.joint(j).dofadr[0]) for j in joints], dtype=int),
            np.array([grasp.joints.index(j) for j in joints], dtype=int),
            p0 - self.c0,
            np.array(w.normal),
            local,
        )

    def _turn(self, data: mujoco.MjData) -> NDArray[np.float64] | None:
        """The object's rotation since the start (quaternion), ``None`` when it has not turned
        (so that a translation keeps the object-fixed points to the bit)."""
        q = np.array(data.qpos[self.padr + 3 : self.padr + 7])
        if np.array_equal(q, self.q0):
            return None
        out = np.zeros(4)
        mujoco.mju_mulQuat(out, q, np.array([self.q0[0], *(-self.q0[1:])]))
        return out

    def _fixed(self, data: mujoco.MjData, f: _Finger) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """An F-finger's object-fixed contact point and normal now."""
        turn = self._turn(data)
        if turn is None:
            return np.array(data.xpos[self.ob]) + f.rel, f.normal
        return np.array(data.xpos[self.ob]) + rotate(turn, f.rel), rotate(turn, f.normal)

    def _contact(self, data: mujoco.MjData, f: _Finger) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The finger's contact point (on its surface; for F: fixed to it) and the normal into the object."""
        if f.role == "F" and not f.sphere:
            point = data.xpos[f.body] + data.xmat[f.body].reshape(3, 3) @ f.local
            return point, self._fixed(data, f)[1]
        w = witness(self.dmodel, data, self._piece(data, f), f.geom_id)
        return w.finger_point, w.normal

    def kinematics(self, data: mujoco.MjData, s: float) -> tuple[NDArray[np.float64], ...]:
        """Contact points (G, 3), rates (M,) and physical slips (G, 3) at ``data`` (eq. 7-8)."""
        model, g = self.model, len(self.fingers)
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        tw, c = self.motion.twist(s), np.array(data.xpos[self.ob])
        points, slips = np.zeros((g, 3)), np.zeros((g, 3))
        rates, jacp = np.zeros(len(self.grasp.joints)), np.zeros((3, model.nv))
        for k, f in enumerate(self.fingers):
            points[k], n = self._contact(data, f)
            u = tw[:3] + np.cross(tw[3:], points[k] - c)  # G^T rdot: the object's point's velocity
            mujoco.mj_jac(model, data, jacp, None, points[k], f.body)
            jac = jacp[:, f.dofs]
            if f.role == "F":  # J^+ G^T rdot: all three rows (eq. 7)
                qd = np.linalg.pinv(jac) @ u
            else:  # J_n^+ n^T G^T rdot: the normal row only (eq. 8)
                jn = n @ jac
                if float(jn @ jn) < 1e-12:
                    raise ModelError(f"geom {f.geom!r}", f"singular normal row at s = {s:.6g}")
                qd = jn * float(n @ u) / float(jn @ jn)
                rel = u - jac @ qd  # the object's contact-point velocity relative to the finger's
                slips[k] = rel - (rel @ n) * n
            rates[f.cols] = qd
        return points, rates, slips

    def _target(self, data: mujoco.MjData, f: _Finger) -> IkTarget:
        """The IK target of one finger at ``data`` (module docstring; kinematics done)."""
        model, body = self.model, body_label(self.model, f.body)
        if not f.sphere:
            if f.role == "F":
                return IkTarget(f.geom, body, f.local, self._fixed(data, f)[0])
            w = witness(self.dmodel, data, self._piece(data, f), f.geom_id)
            xb, rb = data.xpos[f.body], data.xmat[f.body].reshape(3, 3)
            return IkTarget(f.geom, body, rb.T @ (w.finger_point - xb), w.object_point)
        r = float(model.geom_size[f.geom_id, 0])
        piece = self._piece(data, f)
        if is_sphere(model, piece):  # Case 2's arithmetic: radial projection
            c = np.array(data.geom_xpos[piece])
            if f.role == "F":
                p = self._fixed(data, f)[0]
            else:
                tip = np.array(data.geom_xpos[f.geom_id])
                p = c + float(model.geom_size[piece, 0]) * (tip - c) / np.linalg.norm(tip - c)
            n = (c - p) / float(np.linalg.norm(c - p))
        elif f.role == "F":
            p, n = self._fixed(data, f)
        else:
            w = witness(self.dmodel, data, piece, f.geom_id)
            p, n = w.object_point, w.normal
        return IkTarget(f.geom, body, np.array(model.geom_pos[f.geom_id]), p - r * n)

    def targets(self, data: mujoco.MjData) -> list[IkTarget]:
        return [self._target(data, f) for f in self.fingers]

    def drift(self, data: mujoco.MjData, targets: list[IkTarget]) -> NDArray[np.float64]:
        return np.array([np.linalg.norm(ik_residual(self.model, data, [t], [])[0]) for t in targets])

    def pose(self, data: mujoco.MjData) -> NDArray[np.float64]:
        return np.array(data.qpos[self.padr : self.padr + 7])

    def step(self, data: mujoco.MjData, s: float, ds: float) -> tuple[mujoco.MjData, dict[str, Any]]:
        """One predictor-corrector step from ``s`` to ``s + ds``; ``info["ok"]`` False when it fails."""
        rates = self.kinematics(data, s)[1]
        work = copy.copy(data)
        work.qpos[self.qadr] += ds * rates[self.qcols]
        work.qpos[self.padr : self.padr + 7] = self.motion.advance(self.pose(data), s, ds)
        mujoco.mj_kinematics(self.model, work)
        targets = self.targets(work)
        info: dict[str, Any] = {"drift": self.drift(work, targets), "ok": True}
        where = f"s = {s + ds:.6f} (object at {np.array2string(self.pose(work)[:3], precision=6)} m)"
        retarget = [k for k, f in enumerate(self.fingers) if f.role == "N" and not f.sphere]
        for _ in range(_MAX_ROUNDS):
            res = solve_ik(
                self.model,
                work,
                targets,
                joints=self.joint_names,
                bounds=self.bounds,
                tolerance=self.tol,
                max_iterations=self.max_it,
                strict=False,
                scratch=self.scratch,
            )
            work.qpos[:] = res.qpos
            info["residual"] = np.array(res.residuals)
            if not res.converged:
                w = int(np.argmax(res.residuals))
                info["ok"], info["why"] = (
                    False,
                    (
                        f"IK of {targets[w].name!r} does not converge at {where} "
                        f"(residual {res.residuals[w]:.3g} m > {self.tol:.3g} m)"
                    ),
                )
                return work, info
            mujoco.mj_kinematics(self.model, work)
            gaps = {
                k: abs(
                    witness(
                        self.dmodel, work, self._piece(work, self.fingers[k]), self.fingers[k].geom_id
                    ).distance
                )
                for k in retarget
            }
            for k, gap in gaps.items():
                info["residual"][k] = max(info["residual"][k], gap)
            if all(gap <= self.tol for gap in gaps.values()):
                break
            targets = self.targets(work)
        else:
            k = max(gaps, key=lambda k: gaps[k])
            info["ok"], info["why"] = (
                False,
                (
                    f"{self.fingers[k].geom!r} does not settle on the surface at "
                    f"{where} (distance {gaps[k]:.3g} m)"
                ),
            )
            return work, info
        if why := self.inadmissible(work):
            info["ok"], info["why"] = False, f"{why} at {where}"
        return work, info

    def copy_to_scratch(self, data: mujoco.MjData) -> mujoco.MjData:
        """`scratch` holding a copy of ``data`` (valid until the next use of the scratch)."""
        mujoco.mj_copyData(self.scratch, self.model, data)
        return self.scratch

    def touching(self, data: mujoco.MjData) -> list[tuple[str, float]]:
        # MuJoCo reports a contact only once its margin (0 by default) is reached: detect with a
        # margin of TOUCH_TOL so that surfaces the IK left 1e-9 m apart still touch
        found = detected_contacts(
            self.model, data, object_body=self.grasp.object_body, one_per_body=False, tolerance=TOUCH_TOL
        )
        return [(c.geom, c.distance) for c in found]

    def inadmissible(self, data: mujoco.MjData) -> str | None:
        """Why the pose is not admissible (another geom touching the object, a finger in a support)."""
        for geom, dist in self.touching(data):
            if geom not in self.allowed:
                return f"geom {geom!r} touches the object (distance {dist:.3g} m)"
        for g, b, d0 in self.pairs:
            d = float(mujoco.mj_geomDistance(self.dmodel, data, b, g, 1.0, None))
            if d < min(d0, 0.0) - TOUCH_TOL:
                label, support = geom_label(self.model, g), geom_label(self.model, b)
                return (
                    f"geom {label!r} penetrates the support {support!r} ({d:.3g} m, {d0:.3g} m at the start)"
                )
        if self.stop_margin > 0.0:
            sig = self.sigmas(data)
            k = int(np.argmin(sig / self.sigma0))
            if sig[k] < self.stop_margin * self.sigma0[k]:
                return (
                    f"stop margin: {self.fingers[k].geom!r} near a singular pose (smallest singular value of its "
                    f"contact Jacobian {sig[k]:.3g} m/rad < {self.stop_margin:g} x {self.sigma0[k]:.3g} at the start)"
                )
        return None


def start_tolerance(grasp: GraspLike) -> float:
    """How far a finger geom may be from the object at the start and count as touching (m): the
    grasp file's ``contact_tolerance``, else `TOUCH_TOL`."""
    value = getattr(grasp, "contact_tolerance", None)
    if value is None:
        value = grasp.document.get("contact_tolerance", TOUCH_TOL)
    return max(float(value), TOUCH_TOL)
