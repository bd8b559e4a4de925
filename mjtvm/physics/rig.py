"""Per-step pieces of a rollout (:func:`~mjtvm.physics.simulate.rollout`): the model's and
drive's indices with the tracked joint speeds (:class:`Rig`), the object's twist errors, and
each finger's gap, slip and contact force.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import NDArray

from .witness import Drive

__all__ = ["Rig", "finger_contacts", "geom_force", "twist_errors", "unit"]

_F64 = NDArray[np.float64]


class Rig:
    """Indices of one model and drive, reused by every step."""

    def __init__(self, model: mujoco.MjModel, drive: Drive, object_body: str) -> None:
        m = self.m = model
        self.ob = model.body(object_body).id
        self.og = next(g for g in range(m.ngeom) if int(m.geom_bodyid[g]) == self.ob)
        self.radius = float(m.geom_size[self.og, 0])
        self.fadr = int(m.jnt_dofadr[m.body_jntadr[self.ob]])
        self.dofs = np.array([int(m.joint(j).dofadr[0]) for j in drive.joints])
        self.acts = np.array([int(m.actuator(j).id) for j in drive.joints])
        self.gear = m.actuator_gear[self.acts, 0].copy()
        self.cadr = m.actuator_ctrladr[self.acts].copy()
        self.fmax = m.actuator_forcerange[self.acts, 1].copy()
        self.r_k, self.kd, self.vmax = (m.actuator_gainprm[self.acts, i].copy() for i in (0, 6, 7))
        self.kt = m.actuator_gainprm[self.acts, 1].copy()
        self.fingers = []
        jbody = {j: int(m.jnt_bodyid[m.joint(j).id]) for j in drive.joints}
        for geom, kind in drive.contacts:
            g = m.geom(geom).id
            chain: set[int] = set()
            b = int(m.geom_bodyid[g])
            while b > 0:
                chain, b = chain | {b}, int(m.body_parentid[b])
            cols = np.array([i for i, j in enumerate(drive.joints) if jbody[j] in chain], dtype=int)
            self.fingers.append((geom, g, int(m.geom_bodyid[g]), cols, kind, float(m.geom_size[g, 0])))
        self.jac = np.zeros((3, m.nv))
        self.jac2 = np.zeros((3, m.nv))

    def setpoints(self, d: mujoco.MjData, drive: Drive) -> _F64:
        """Least-norm correction of the drive's speeds at the configuration ``d`` (step 5)."""
        q, c, v, w = drive.speeds.copy(), d.xpos[self.ob], drive.twist[:3], drive.twist[3:]
        for geom, g, body, cols, kind, rad in self.fingers:
            tip = d.geom_xpos[g]
            n = (c - tip) / np.linalg.norm(c - tip)
            p = tip + rad * n
            mujoco.mj_jac(self.m, d, self.jac, None, p, body)
            jm = self.jac[:, self.dofs[cols]]
            want = v + np.cross(w, p - c)
            if kind == "L":
                jn = n @ jm
                q[cols] += jn * (n @ want - jn @ q[cols]) / max(float(jn @ jn), 1e-12)
            else:
                if kind == "S" and geom in drive.slips:
                    rho, hat = drive.slips[geom]
                    tang = hat - (hat @ n) * n
                    want = want - rho * tang / max(float(np.linalg.norm(tang)), 1e-12)
                q[cols] += np.linalg.lstsq(jm, want - jm @ q[cols], rcond=None)[0]
        return q


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
    fromto: _F64,
    f6: _F64,
) -> list[float]:
    """Each finger's gap to the object (returned), and at its nearest points the relative
    tangential velocity: integrated into ``slip`` for F-contacts, summed with the contact
    force into ``ssum`` and ``fsum`` for the others."""
    gaps = []
    for geom, g, body, _cols, kind, _rad in rig.fingers:
        dist = mujoco.mj_geomDistance(m, d, g, rig.og, 0.01, fromto)
        gaps.append(dist)
        p = 0.5 * (fromto[:3] + fromto[3:])
        n = unit(d.xpos[rig.ob] - p)
        mujoco.mj_jac(m, d, rig.jac, None, p, rig.ob)
        mujoco.mj_jac(m, d, rig.jac2, None, p, body)
        rel = (rig.jac - rig.jac2) @ d.qvel  # object point relative to finger point
        rel_t = rel - (rel @ n) * n
        if kind == "F":
            slip[geom] += float(np.linalg.norm(rel_t)) * timestep
        else:
            ssum[geom] += rel_t
            fsum[geom] += geom_force(m, d, g, rig.og, f6, n)
    return gaps


def geom_force(m: mujoco.MjModel, d: mujoco.MjData, g: int, og: int, f6: _F64, n: _F64) -> _F64:
    """Tangential force (world) of geom ``g`` on the object, summed over their active contacts."""
    total = np.zeros(3)
    for i in range(d.ncon):
        c = d.contact[i]
        if c.exclude or {int(c.geom1), int(c.geom2)} != {g, og}:
            continue
        mujoco.mj_contactForce(m, d, i, f6)
        f = c.frame.reshape(3, 3).T @ f6[:3]  # on geom2
        total += f if int(c.geom2) == og else -f
    return total - (total @ n) * n
