r"""The torques that inertia adds to a driven motion, which the quasi-static TVMMP (eq. 19) leaves out.

[`gravity_bias()`][mjtvm.physics.inertia.gravity_bias] splits gravity off MuJoCo's ``qfrc_bias``;
[`inertial_feedforward()`][mjtvm.physics.inertia.inertial_feedforward] is the computed torque a rollout
adds to its feedforward with ``inertial_ff`` (an ablation, [`mjtvm.physics.simulate`][mjtvm.physics.simulate]);
[`inertial_demand()`][mjtvm.physics.inertia.inertial_demand] is the largest such torque along the
ideal motion. The dynamic alpha ([`mjtvm.physics.dynamic`][mjtvm.physics.dynamic]) uses the same
split of ``qfrc_bias``.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.physics.rig import Rig
from mjtvm.physics.witness import Drive

__all__ = ["gravity_bias", "inertial_demand", "inertial_feedforward"]

_F64 = NDArray[np.float64]


def gravity_bias(m: mujoco.MjModel, scratch: mujoco.MjData, qpos: _F64) -> _F64:
    """The gravity part of ``qfrc_bias`` at ``qpos`` (RNE at zero velocity, on ``scratch``).

    Parameters
    ----------
    m
        The model.
    scratch
        Data of ``m`` to compute on; its ``qpos`` and ``qvel`` are overwritten.
    qpos
        ``(nq,)`` the configuration.

    Returns
    -------
    numpy.ndarray
        ``(nv,)`` the generalized gravity force (N m or N), as in ``qfrc_bias``.
    """
    scratch.qpos[:] = qpos
    scratch.qvel[:] = 0.0
    mujoco.mj_kinematics(m, scratch)
    mujoco.mj_comPos(m, scratch)
    mujoco.mj_comVel(m, scratch)
    out = np.zeros(m.nv)
    mujoco.mj_rne(m, scratch, 0, out)
    return out


def inertial_feedforward(
    m: mujoco.MjModel, d: mujoco.MjData, pred: mujoco.MjData, rig: Rig, drive: Drive, qset: _F64
) -> _F64:
    """The computed torque of the tracked setpoints: M qdd (one-step prediction) + Coriolis (ablation).

    What [`SimSettings.inertial_ff`][mjtvm.physics.settings.SimSettings] adds to a rollout's feedforward.

    Parameters
    ----------
    m, d
        The model and the rollout's data at the current step.
    pred
        Scratch data of ``m`` for the prediction one time step ahead (overwritten).
    rig, drive
        The rollout's rig and drive ([`Rig`][mjtvm.physics.rig.Rig], [`Drive`][mjtvm.physics.witness.Drive]).
    qset
        The tracked joint speed setpoints at the current step.

    Returns
    -------
    numpy.ndarray
        The torque on each driven joint (N m), gravity excluded.
    """
    pred.qpos[:] = d.qpos
    mujoco.mj_integratePos(m, pred.qpos, d.qvel, m.opt.timestep)
    mujoco.mj_kinematics(m, pred)
    mujoco.mj_comPos(m, pred)
    acc = np.zeros(m.nv)
    acc[rig.dofs] = (rig.setpoints(pred, drive) - qset) / m.opt.timestep
    out = np.zeros(m.nv)
    mujoco.mj_mulM(m, d, out, acc)
    return np.asarray((out + d.qfrc_bias - gravity_bias(m, pred, d.qpos))[rig.dofs], dtype=float)


def inertial_demand(
    model: mujoco.MjModel, qpos: _F64, drive: Drive, *, duration: float = 0.005, object_body: str = "object"
) -> _F64:
    r"""``(M,)`` largest joint torque (N m) that inertia and Coriolis forces add along the ideal motion.

    The drive's motion (tracked setpoints, object at the drive's twist) is integrated
    kinematically for ``duration``; the torque is $M(q)\ddot q + c(q, \dot q)$ on the
    driven joints (rotor inertia included, object excluded): what the quasi-static TVMMP
    (eq. 19) leaves out.
    """
    m, d, scratch = model, mujoco.MjData(model), mujoco.MjData(model)
    rig = Rig(m, drive, object_body)
    d.qpos[:] = qpos
    dt, fa, worst = m.opt.timestep, rig.fadr, np.zeros(len(drive.joints))
    mujoco.mj_forward(m, d)
    qset = rig.setpoints(d, drive)
    for _ in range(max(2, round(duration / dt))):
        d.qvel[:] = 0.0
        d.qvel[rig.dofs] = qset
        d.qvel[fa : fa + 3] = drive.twist[:3]
        d.qvel[fa + 3 : fa + 6] = d.xmat[rig.ob].reshape(3, 3).T @ drive.twist[3:]
        mujoco.mj_forward(m, d)
        grav = gravity_bias(m, scratch, d.qpos)
        mujoco.mj_integratePos(m, d.qpos, d.qvel, dt)
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        nxt = rig.setpoints(d, drive)
        acc, out = np.zeros(m.nv), np.zeros(m.nv)
        acc[rig.dofs] = (nxt - qset) / dt
        mujoco.mj_mulM(m, d, out, acc)
        worst = np.maximum(worst, np.abs((out + d.qfrc_bias - grav)[rig.dofs]))
        qset = nxt
    return worst
