"""The 2F-85 grasp configuration of models/robotiq_2f85/robotiq_2f85-sphere.toml: the linkage
closed exactly, the sphere touching both lower pads at their centres.

For a driver angle theta the eight joints solve (Newton on central-difference Jacobians, to
machine precision) the three equalities (two connects, the driver coupling) with both couplers
at :data:`COUPLER` (0.05 rad from their stop at 0, so that no joint limit holds the finger):
each side's four-bar then has one solution. The lower pad's inner face (local -y of pad_box2,
4 mm from its centre) has a centre ``p`` and inward normal ``n``; a sphere on the gripper's axis
touching it there has radius ``r = -p_y / n_y`` and centre ``p + r n``. theta is bisected until
r = 25 mm. Why the lower pads: a pinch on the upper pads with the couplers at their stop is
held by the stop (the 2F-85's parallel mode), a force the state does not have (its LP finds no
balance); on the lower pads the contacts, the actuator and the spring links balance each
finger's two dofs. The Shadow hand's grasp is found by the grasp file's own IK.

Usage::

    python tools/make_coupled_hands.py     # print the joint values and the sphere's centre
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

MODEL = Path(__file__).resolve().parents[1] / "models" / "robotiq_2f85" / "robotiq_2f85.xml"
RADIUS = 0.025
COUPLER = -0.05  # rad, both couplers (range -1.57 to 0)
PAD = "pad2"


def closed_linkage(
    model: mujoco.MjModel, data: mujoco.MjData, theta: float
) -> tuple[NDArray[np.float64], float]:
    """Joint values with both drivers at theta and both couplers at COUPLER; the largest residual."""
    couplers = [int(model.joint(f"{s}_coupler_joint").qposadr[0]) for s in ("right", "left")]
    driver = int(model.joint("right_driver_joint").qposadr[0])

    def residual(q: NDArray[np.float64]) -> NDArray[np.float64]:
        data.qpos[:] = q
        mujoco.mj_forward(model, data)
        return np.array([*data.efc_pos[: data.ne], q[driver] - theta, *(q[couplers] - COUPLER)])

    q = np.zeros(model.nq)
    q[[int(model.joint(f"{s}_driver_joint").qposadr[0]) for s in ("right", "left")]] = theta
    for _ in range(60):
        r = residual(q)
        if np.max(np.abs(r)) < 1e-15:
            break
        jac = np.zeros((len(r), model.nq))
        for k in range(model.nq):
            step = np.zeros(model.nq)
            step[k] = 1e-7
            jac[:, k] = (residual(q + step) - residual(q - step)) / 2e-7
        q = q - np.linalg.lstsq(jac, r, rcond=None)[0]
    return q, float(np.max(np.abs(residual(q))))


def touching_sphere(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[float, NDArray[np.float64]]:
    """Radius and centre of the sphere on the axis touching the right lower pad at its centre."""
    g = int(model.geom(f"right_{PAD}").id)
    rot = data.geom_xmat[g].reshape(3, 3)
    normal = -rot[:, 1]
    face = data.geom_xpos[g] + rot @ np.array([0.0, -float(model.geom_size[g, 1]), 0.0])
    radius = -face[1] / normal[1]
    return float(radius), face + radius * normal


def main() -> None:
    model = mujoco.MjModel.from_xml_path(str(MODEL))
    data = mujoco.MjData(model)
    lo, hi = 0.2, 0.5  # the radius falls as the gripper closes
    for _ in range(60):
        theta = (lo + hi) / 2
        closed_linkage(model, data, theta)
        if touching_sphere(model, data)[0] > RADIUS:
            lo = theta
        else:
            hi = theta
    q, worst = closed_linkage(model, data, theta)
    radius, centre = touching_sphere(model, data)
    print(f"theta {theta!r}  residual {worst:.3g}  radius {radius!r}  centre {centre.tolist()!r}")
    for j in range(model.njnt):
        print(f"{model.joint(j).name} = {float(q[model.jnt_qposadr[j]])!r}")


if __name__ == "__main__":
    main()
