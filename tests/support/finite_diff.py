"""Finite differences of MuJoCo positions: the independent check of the contact Jacobians."""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.grasp.contacts.touch import geom_id
from mjtvm.model.state import GraspState


def contact_jacobians_fd(
    model: mujoco.MjModel, qpos: NDArray[np.float64], state: GraspState, *, h: float = 1e-6
) -> dict[str, NDArray[np.float64]]:
    """Per contact of ``state`` (named by its finger geom, ``"<geom>#k"`` allowed), the
    ``(3, M)`` derivative of the finger-fixed contact point by the state's joints at ``qpos``,
    by central differences of ``mj_kinematics`` with step ``h`` (rad or m)."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    out = {}
    for contact in state.contacts:
        body = int(model.geom_bodyid[geom_id(model, contact.name.split("#")[0])])
        local = data.xmat[body].reshape(3, 3).T @ (contact.position - data.xpos[body])
        fd = np.zeros((3, len(state.joint_names)))
        for col, name in enumerate(state.joint_names):
            adr = int(model.joint(name).qposadr[0])
            points = []
            for step in (h, -h):
                d = mujoco.MjData(model)
                d.qpos[:] = qpos
                d.qpos[adr] += step
                mujoco.mj_kinematics(model, d)
                points.append(d.xpos[body] + d.xmat[body].reshape(3, 3) @ local)
            fd[:, col] = (points[0] - points[1]) / (2 * h)
        out[contact.name] = fd
    return out
