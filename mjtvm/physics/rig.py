"""Per-step pieces of a rollout ([`rollout()`][mjtvm.physics.simulate.rollout]): the model's and
drive's indices with the tracked joint speeds ([`Rig`][mjtvm.physics.rig.Rig]), the object's twist errors, and
each finger's gap, slip and contact force.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.transmission import dense_moment
from mjtvm.grasp.resolve.state import geom_id, model_id
from mjtvm.physics.motors import dcmotor_of_actuator, dcmotor_of_joint
from mjtvm.physics.witness import Drive

__all__ = ["Nearest", "Rig", "cross", "finger_contacts", "geom_force", "twist_errors", "unit"]

_F64 = NDArray[np.float64]
Nearest = tuple[float, int, _F64, _F64, _F64]
"""[`Rig.nearest()`][mjtvm.physics.rig.Rig.nearest]: distance, object geom, finger point, object point, normal."""


class Rig:
    r"""Indices of one model and drive, reused by every step.

    Any hand: each driven joint's actuator is the single ``<dcmotor>`` (``input="vel ff"``)
    whose transmission is that joint ([`dcmotor_of_joint()`][mjtvm.physics.motors.dcmotor_of_joint]), not
    an actuator of the joint's name; finger geoms are found by label
    ([`geom_id()`][mjtvm.grasp.resolve.state.geom_id]: a name or ``"<body>/geom<n>"``); each finger's
    contact point is its nearest point to the object (``mj_geomDistance``), so fingertips and
    objects of any primitive or mesh shape work.

    Attributes
    ----------
    ob, ogs
        The object's body id and its colliding geoms (its subtree's geoms with a non-zero
        ``contype`` or ``conaffinity``; all of its geoms if none).
    radius
        Length scale R (m) of the twist error [v; R omega]: the object's bounding radius
        about its body origin, max over ``ogs`` of (distance of the geom's centre from the
        origin + ``geom_rbound``). For a sphere centred on its body: its radius.
    fingers
        Per drive contact: (label, geom id, body id, columns of the drive's joints moving it, type).
    finger_dofs
        Per drive contact: the model's dofs of those columns (``dofs[columns]``).
    coupled
        The drive has a transmission (`Drive.actuators`): ``acts`` are the actuators'
        ``<dcmotor>`` s (found by name), ``gear`` their ratio ``c`` to the state's moment rows
        (set by `bind()`: motor moment = ``c x P``, so motor torque ``u / c`` and motor speed
        ``c x P qd``), ``friction`` each actuator's share of its joints' friction loss,
        ``max_j frictionloss_j / |P_aj|`` (what [`actuator_ranges()`][mjtvm.grasp.actuation.ranges.actuator_ranges]
        takes off its range).
    """

    def __init__(self, model: mujoco.MjModel, drive: Drive, object_body: str) -> None:
        m = self.m = model
        self.ob = model_id(m, mujoco.mjtObj.mjOBJ_BODY, object_body, "body")
        self.ogs, self.radius = _object_geoms(m, self.ob)
        self.og = self.ogs[0]
        self.fadr = int(m.jnt_dofadr[m.body_jntadr[self.ob]])
        jids = [model_id(m, mujoco.mjtObj.mjOBJ_JOINT, j, "joint") for j in drive.joints]
        self.dofs = np.array([int(m.jnt_dofadr[j]) for j in jids])
        self.coupled = bool(drive.actuators)
        if self.coupled:
            self.acts = np.array([dcmotor_of_actuator(m, a) for a in drive.actuators], dtype=int)
            self.gear = np.ones(len(self.acts))  # until bind()
            self.moment = np.asarray(drive.moment, dtype=float)
            p = np.abs(np.asarray(drive.moment))
            fl = m.dof_frictionloss[self.dofs]
            self.friction = np.array([float(np.max(fl[row > 0] / row[row > 0], initial=0.0)) for row in p])
            # damping_share's least squares: P^T is constant, its pseudo-inverse solved once
            self.damping_solve = np.linalg.pinv(self.moment.T)
        else:
            self.acts = np.array([_motor(m, j) for j in drive.joints], dtype=int)
            self.gear = m.actuator_gear[self.acts, 0].copy()
        self.cadr = m.actuator_ctrladr[self.acts].copy()
        self.fmax = m.actuator_forcerange[self.acts, 1].copy()
        self.r_k, self.kd, self.vmax = (m.actuator_gainprm[self.acts, i].copy() for i in (0, 6, 7))
        self.kt = m.actuator_gainprm[self.acts, 1].copy()
        self.fingers: list[tuple[str, int, int, NDArray[np.int64], str]] = []
        jbody = [int(m.jnt_bodyid[j]) for j in jids]
        for label, kind in drive.contacts:
            g = geom_id(m, label, "finger geom")
            chain: set[int] = set()
            b = int(m.geom_bodyid[g])
            while b > 0:
                chain, b = chain | {b}, int(m.body_parentid[b])
            cols = np.array([i for i, jb in enumerate(jbody) if jb in chain], dtype=int)
            self.fingers.append((label, g, int(m.geom_bodyid[g]), cols, kind))
        self.jac = np.zeros((3, m.nv))
        self.jac2 = np.zeros((3, m.nv))
        self.fromto = np.zeros(6)
        self.finger_dofs = [self.dofs[f[3]] for f in self.fingers]  # each finger's columns' dofs
        self._null: tuple[_F64, _F64, _F64] | None = None  # J_eq, its row space and null space

    def nearest(self, d: mujoco.MjData, g: int) -> Nearest:
        """Signed distance (m) from finger geom ``g`` to the nearest object geom, that geom, the
        nearest point on the finger and on the object (world, m), and the unit normal from the
        finger into the object (``mj_geomDistance``; its segment reverses under penetration)."""
        best, ft = (np.inf, -1), self.fromto
        for og in self.ogs:
            dist = mujoco.mj_geomDistance(self.m, d, g, og, _DISTMAX, self.fromto)
            if dist < best[0]:
                best, ft = (dist, og), self.fromto.copy()
        dist, og = best
        on_f, on_o = ft[:3], ft[3:]
        n = unit((on_o - on_f) * (1.0 if dist >= 0 else -1.0))
        if not np.any(n):  # touching exactly: towards the object's centre
            n = unit(d.geom_xpos[og] - on_f)
        return float(dist), og, on_f, on_o, n

    def bind(self, d: mujoco.MjData, drive: Drive) -> None:
        """With a transmission: each motor's ratio ``c`` to the state's moment row, from MuJoCo's
        moment at ``d`` (after ``mj_forward`` at the state's configuration).

        Raises
        ------
        ModelError
            A motor whose moment is not a multiple of the state's row (not the same transmission).
        """
        if not self.coupled or drive.moment is None:
            return
        mm, p = self.motor_moment(d), np.asarray(drive.moment)
        for a, name in enumerate(drive.actuators):
            c = float(mm[a] @ p[a]) / float(p[a] @ p[a])
            if not (c > 0 and np.allclose(mm[a], c * p[a], rtol=1e-6, atol=1e-9 * float(np.abs(p[a]).max()))):
                raise ModelError(
                    f"actuator {name!r}", "its <dcmotor> moves the joints unlike the state's moment row"
                )
            self.gear[a] = c

    def damping_share(self, qd: _F64) -> _F64:
        """``(A,)`` actuator forces whose joint torques ``P^T u`` best match the joints' damping
        ``b qd`` (least squares; with independent joints exactly ``b qd``)."""
        tau = self.m.dof_damping[self.dofs] * qd
        if not np.any(tau):
            return np.zeros(len(self.acts))
        return np.asarray(self.damping_solve @ tau, dtype=float)  # the least-norm least squares

    def hold_torques(self, drive: Drive) -> _F64:
        """The feedforward that holds the state at rest (settle, hold test): the drive's torques,
        which hold the grasp and carry no damping (the LP's damping is a loss,
        [`assembly`][mjtvm.problem2.assembly])."""
        return drive.torques

    def command(self, d: mujoco.MjData, drive: Drive, qset: _F64) -> tuple[_F64, _F64]:
        """With a transmission: ``(A,)`` motor speed setpoints of the tracked joint speeds ``qset``
        and ``(A,)`` feedforward forces (actuator units, before the motors' ratio).

        The LP's forces ``u`` hold the grasp; the joints' damping is a loss the motors overcome
        (its range paid for it), so the share of the damping ``b qset`` of the tracked speeds is
        added; each actuator's friction share was taken off its range (``actuator_ranges``) and
        is added with the sign of the witness's actuator speed, not the tracked one's (whose
        round-off flips at rest).
        """
        ff = drive.torques + self.damping_share(qset) + self.friction * np.sign(drive.actuator_speeds)
        return self.motor_speeds(d, qset), ff

    def controls(self, d: mujoco.MjData, drive: Drive, qset: _F64) -> tuple[_F64, _F64]:
        """``(A,)`` speed setpoints (actuator-length units) and feedforward torques (joint side,
        before the motors' gear) of the tracked joint speeds ``qset`` (a rollout's step 5).

        With a transmission `command()`; without, ``qset`` x gear and the drive's torques
        plus the joints' own damping and friction loss at ``qset`` (passive torques of the
        model, which the grasp's operation ranges leave out of the torque budget,
        ``OperationRange.with_losses``).
        """
        if self.coupled:
            return self.command(d, drive, qset)
        m = self.m
        ff = drive.torques + m.dof_damping[self.dofs] * qset + m.dof_frictionloss[self.dofs] * np.sign(qset)
        return qset * self.gear, ff

    def motor_moment(self, d: mujoco.MjData) -> _F64:
        """``(A, M)`` the motors' moment rows over the drive's joints at ``d`` (gear included)."""
        return dense_moment(self.m, d)[self.acts][:, self.dofs]

    def motor_speeds(self, d: mujoco.MjData, qd: _F64) -> _F64:
        """``(A,)`` the motors' speed setpoints (``actuator_velocity`` units) of joint speeds ``qd``."""
        return self.motor_moment(d) @ qd

    def equality_rows(self, d: mujoco.MjData) -> _F64:
        """``(C, M)`` the equality constraints' rows of ``efc_J`` over the drive's joints at ``d``
        (those of its last forward pass: for a rollout step, the configuration one step before)."""
        nefc, nv = int(d.nefc), self.m.nv
        rows = np.flatnonzero(d.efc_type[:nefc] == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY))
        if not len(rows):
            return np.zeros((0, len(self.dofs)))
        if not mujoco.mj_isSparse(self.m):
            return d.efc_J[: nefc * nv].reshape(nefc, nv)[rows][:, self.dofs]
        # only the equality rows of the sparse efc_J, as mju_sparse2dense writes them
        out = np.zeros((len(rows), nv))
        for i, r in enumerate(rows):
            adr, nnz = int(d.efc_J_rowadr[r]), int(d.efc_J_rownnz[r])
            out[i, d.efc_J_colind[adr : adr + nnz]] = d.efc_J[adr : adr + nnz]
        return out[:, self.dofs]

    def null_space(self, jeq: _F64) -> tuple[_F64, _F64]:
        """``(r, M)`` an orthonormal basis of the row space of ``jeq`` (``(C, M)``, `equality_rows()`)
        and ``(M, M - r)`` one of its null space (SVD, rank at 1e-10 of the largest singular
        value); kept while ``jeq`` is unchanged (a linear coupling's rows are constant)."""
        if self._null is not None and np.array_equal(self._null[0], jeq):
            return self._null[1], self._null[2]
        _u, sv, vt = np.linalg.svd(jeq)
        rank = int(np.sum(sv > 1e-10 * max(float(sv.max(initial=0.0)), 1e-300)))
        self._null = (jeq.copy(), vt[:rank], vt[rank:].T)
        return self._null[1], self._null[2]

    def setpoints(self, d: mujoco.MjData, drive: Drive, near: Sequence[Nearest] | None = None) -> _F64:
        """Least-norm correction of the drive's speeds at the configuration ``d`` (step 5).

        With a transmission the correction is one least-squares solve over every finger's rows
        in the null space of the equality rows (`equality_rows()`), so the speeds keep
        ``J_eq qd = 0``; without, finger by finger (the fingers' joints are disjoint).
        ``near``: each finger's [`nearest()`][mjtvm.physics.rig.Rig.nearest] at ``d`` when
        already computed (by [`finger_contacts()`][mjtvm.physics.rig.finger_contacts] at the
        same positions), else computed here.
        """
        near = near if near is not None else [self.nearest(d, f[1]) for f in self.fingers]
        if self.coupled:
            return self._coupled_setpoints(d, drive, near)
        q, c, v, w = drive.speeds.copy(), d.xpos[self.ob], drive.twist[:3], drive.twist[3:]
        for (label, _g, body, cols, kind), (_dist, _og, p, _po, n) in zip(self.fingers, near, strict=True):
            mujoco.mj_jac(self.m, d, self.jac, None, p, body)
            jm = self.jac[:, self.dofs[cols]]
            want = v + cross(w, p - c)
            if kind == "L":
                jn = n @ jm
                q[cols] += jn * (n @ want - jn @ q[cols]) / max(float(jn @ jn), 1e-12)
            else:
                if kind == "S" and label in drive.slips:
                    rho, hat = drive.slips[label]
                    tang = hat - (hat @ n) * n
                    want = want - rho * tang / max(float(np.linalg.norm(tang)), 1e-12)
                q[cols] += np.linalg.lstsq(jm, want - jm @ q[cols], rcond=None)[0]
        return q

    def _coupled_setpoints(self, d: mujoco.MjData, drive: Drive, near: Sequence[Nearest]) -> _F64:
        q, c, v, w = drive.speeds.copy(), d.xpos[self.ob], drive.twist[:3], drive.twist[3:]
        rows, rhs = [], []
        for (label, _g, body, cols, kind), fdofs, (_dist, _og, p, _po, n) in zip(
            self.fingers, self.finger_dofs, near, strict=True
        ):
            mujoco.mj_jac(self.m, d, self.jac, None, p, body)
            jm = np.zeros((3, len(q)))
            jm[:, cols] = self.jac[:, fdofs]
            want = v + cross(w, p - c)
            if kind == "L":
                rows.append((n @ jm)[None, :])
                rhs.append(np.array([n @ want]))
                continue
            if kind == "S" and label in drive.slips:
                rho, hat = drive.slips[label]
                tang = hat - (hat @ n) * n
                want = want - rho * tang / max(float(np.linalg.norm(tang)), 1e-12)
            rows.append(jm)
            rhs.append(want)
        jeq = self.equality_rows(d)
        null = np.eye(len(q))
        if len(jeq):  # q onto the null space of J_eq (pinv(J) J = V_r V_r^T), and its basis
            vr, null = self.null_space(jeq)
            q -= vr.T @ (vr @ q)
        if rows and null.shape[1]:
            a = np.vstack(rows)
            q += null @ np.linalg.lstsq(a @ null, np.concatenate(rhs) - a @ q, rcond=None)[0]
        return q


_DISTMAX = 1.0  # m: mj_geomDistance's search radius; fingers are within mm of the object


def _object_geoms(m: mujoco.MjModel, ob: int) -> tuple[list[int], float]:
    """The object's colliding geoms and its bounding radius about the body origin (m)."""
    inside = {ob}
    for b in range(ob + 1, m.nbody):  # parents precede children
        if int(m.body_parentid[b]) in inside:
            inside.add(b)
    geoms = [g for g in range(m.ngeom) if int(m.geom_bodyid[g]) in inside]
    colliding = [g for g in geoms if int(m.geom_contype[g]) or int(m.geom_conaffinity[g])]
    ogs = colliding or geoms
    if not ogs:
        raise ModelError(f"body {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, ob)!r}", "has no geom")
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)  # at qpos0: only the geoms' placement in the object matters
    radius = max(float(np.linalg.norm(d.geom_xpos[g] - d.xpos[ob])) + float(m.geom_rbound[g]) for g in ogs)
    return ogs, radius


def _motor(m: mujoco.MjModel, joint: str) -> int:
    a = dcmotor_of_joint(m, joint)
    if a is None:
        raise ModelError(
            f"joint {joint!r}",
            'expected one <dcmotor> with input="vel ff" driving it (mjtvm.physics.motors.attach_dcmotors)',
        )
    return a


def cross(a: _F64, b: _F64) -> _F64:
    """``a x b`` of two 3-vectors (``np.cross``'s value, without its general-axis overhead)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]], dtype=float
    )


def unit(x: _F64) -> _F64:
    nrm = float(np.linalg.norm(x))
    return x / nrm if nrm > 1e-12 else np.zeros_like(x)


def twist_errors(worst: dict[str, float], now: _F64, target: _F64, tnorm: float) -> None:
    """Update the worst relative speed error and angle (deg) of the object's twist ``now``."""
    if tnorm > 0:
        worst["speed"] = max(worst["speed"], abs(float(np.linalg.norm(now)) / tnorm - 1.0))
        cosang = float(now @ target) / max(float(np.linalg.norm(now)) * tnorm, 1e-300)
        worst["angle"] = max(worst["angle"], math.degrees(math.acos(max(-1.0, min(1.0, cosang)))))
    else:
        worst["speed"] = max(worst["speed"], float(np.linalg.norm(now)))


def finger_contacts(
    m: mujoco.MjModel,
    d: mujoco.MjData,
    rig: Rig,
    timestep: float,
    slip: dict[str, float],
    ssum: dict[str, _F64],
    fsum: dict[str, _F64],
    f6: _F64,
    near: list[Nearest] | None = None,
) -> list[float]:
    """Each finger's gap to the object (m, returned; [`Rig.nearest()`][mjtvm.physics.rig.Rig.nearest]), and midway between
    the nearest points the object's velocity relative to the finger's, tangential to the
    normal: integrated into ``slip`` for F-contacts, summed with the contact force into
    ``ssum`` and ``fsum`` for the others (keys: the fingers' geom labels). ``near``, when
    given, is filled with each finger's [`Rig.nearest()`][mjtvm.physics.rig.Rig.nearest] (for
    [`Rig.setpoints()`][mjtvm.physics.rig.Rig.setpoints] at the same positions)."""
    gaps = []
    if near is not None:
        near.clear()
    for label, g, body, _cols, kind in rig.fingers:
        found = rig.nearest(d, g)
        dist, _og, on_f, on_o, n = found
        if near is not None:
            near.append(found)
        gaps.append(dist)
        p = 0.5 * (on_f + on_o)  # MuJoCo's contact point: midway between the surfaces
        mujoco.mj_jac(m, d, rig.jac, None, p, rig.ob)
        mujoco.mj_jac(m, d, rig.jac2, None, p, body)
        rel = (rig.jac - rig.jac2) @ d.qvel  # object point relative to finger point
        rel_t = rel - (rel @ n) * n
        if kind == "F":
            slip[label] += float(np.linalg.norm(rel_t)) * timestep
        else:
            ssum[label] += rel_t
            fsum[label] += geom_force(m, d, g, rig.ogs, f6, n)
    return gaps


def geom_force(m: mujoco.MjModel, d: mujoco.MjData, g: int, ogs: Sequence[int], f6: _F64, n: _F64) -> _F64:
    """Tangential force (world) of geom ``g`` on the object (geoms ``ogs``), summed over their
    active contacts; ``n`` is the contact normal (unit)."""
    total = np.zeros(3)
    for i in range(d.ncon):
        c = d.contact[i]
        g1, g2 = int(c.geom1), int(c.geom2)
        if c.exclude or not ((g1 == g and g2 in ogs) or (g2 == g and g1 in ogs)):
            continue
        mujoco.mj_contactForce(m, d, i, f6)
        f = c.frame.reshape(3, 3).T @ f6[:3]  # on geom2
        total += f if g2 in ogs else -f
    return total - (total @ n) * n
