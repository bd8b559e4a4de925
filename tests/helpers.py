"""Shared test data, computed here from the datasheet by hand (not by the code under test)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog

RPM = 2 * np.pi / 60
#: The RE25 20 W behind the 1/40 gear, from ../shared/data/maxon-re25-20w.md.
T_MAX = 26.3e-3 * 40  # N m: max continuous torque at the joint
Q_NOM = 8330 * RPM / 40  # rad/s at T_MAX (nominal speed)
Q_MAX = 9560 * RPM / 40  # rad/s at zero torque (no-load speed)
G = 9.81


def max_speed(torque: float) -> float:
    """Largest joint speed at |torque| on the RE25 polygon (the speed-torque line)."""
    return Q_MAX - (Q_MAX - Q_NOM) * abs(torque) / T_MAX


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation matrix."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx


def distance_to_hull(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Max-norm distance of each point to the convex hull of ``vertices`` (one LP per point)."""
    n, dim = vertices.shape
    a_ub = np.block([[vertices.T, -np.ones((dim, 1))], [-vertices.T, -np.ones((dim, 1))]])
    a_eq = np.r_[np.ones(n), 0.0][None]
    out = []
    for p in points:
        res = linprog(np.r_[np.zeros(n), 1.0], A_ub=a_ub, b_ub=np.r_[p, -p], A_eq=a_eq, b_eq=[1.0])
        out.append(res.fun)
    return np.array(out)
