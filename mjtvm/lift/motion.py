r"""The object's motion in a scripted lift: a piecewise-constant twist along a path parameter s.

A motion is a sequence of segments; on segment j the object moves with the constant twist
$\dot r_j = (v_j, \omega_j)$ per unit s, world frame, about the object's origin
$c$: the origin moves by $v_j\,\mathrm ds$, the orientation turns by
$\exp(\omega_j\,\mathrm ds)$ (left-multiplied: $\omega$ is a world-frame angular
velocity), and an object-fixed point $p$ moves with $G^T \dot r = v + \omega \times
(p - c)$ (the paper's $G_c^T \dot r$, eq. 7-8).

* a *direction* d: one segment, twist $(d/|d|, 0)$, s the distance travelled (m);
* a *twist*: one segment, s its parameter (time-like: the motion per unit s);
* *poses* $P_1 \dots P_K$ (position, unit quaternion w x y z): from the start pose through
  each in turn, segment j the constant twist (linear position, slerp orientation) taking
  $P_{j-1}$ to $P_j$; s advances by the origin's travel (m), or by the turning
  angle (rad) on a segment that only rotates.

Poses are 7-vectors (position m, quaternion w x y z) as in a free joint's ``qpos``.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import StateError

__all__ = ["Motion", "rotate"]


def _mul(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, a, b)
    return out


def _conj(q: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([q[0], -q[1], -q[2], -q[3]])


def rotate(q: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(3,)`` the vector ``v`` rotated by the unit quaternion ``q`` (w x y z)."""
    out = np.zeros(3)
    mujoco.mju_rotVecQuat(out, np.asarray(v, dtype=float), np.asarray(q, dtype=float))
    return out


class Motion:
    """Segments of constant twist (module docstring) from the object's start pose ``(7,)``."""

    def __init__(
        self, start: ArrayLike, *, twist: ArrayLike | None = None, poses: ArrayLike | None = None
    ) -> None:
        start = np.array(start, dtype=float)
        # (s0, s1, twist (6,), end pose (7,) or None)
        self.segments: list[tuple[float, float, NDArray[np.float64], NDArray[np.float64] | None]] = []
        if poses is None:
            tw = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0] if twist is None else twist, dtype=float)
            if tw.shape != (6,) or not np.all(np.isfinite(tw)) or not np.any(tw):
                raise StateError("twist", f"expected 6 finite numbers, not all 0, got {twist!r}")
            self.segments.append((0.0, math.inf, tw, None))
            return
        ps = np.array(poses, dtype=float)
        if ps.ndim != 2 or ps.shape[1] != 7 or len(ps) == 0 or not np.all(np.isfinite(ps)):
            raise StateError("poses", f"expected K >= 1 poses of 7 finite numbers, got shape {ps.shape}")
        if np.any(np.abs(np.linalg.norm(ps[:, 3:], axis=1) - 1.0) > 1e-6):
            raise StateError("poses", "expected unit quaternions (w, x, y, z)")
        ps[:, 3:] /= np.linalg.norm(ps[:, 3:], axis=1)[:, None]
        s, prev = 0.0, start
        for k, pose in enumerate(ps):
            rel = _mul(pose[3:], _conj(prev[3:]))
            rel *= 1.0 if rel[0] >= 0 else -1.0  # the shorter way round
            w = np.zeros(3)
            mujoco.mju_quat2Vel(w, rel, 1.0)  # axis * angle (rad)
            travel, angle = float(np.linalg.norm(pose[:3] - prev[:3])), float(np.linalg.norm(w))
            length = travel if travel > 1e-12 else angle
            if length <= 1e-12:
                if k == 0:
                    continue  # the first pose is the start pose
                raise StateError("poses", f"pose {k} repeats the one before it")
            tw = np.concatenate([(pose[:3] - prev[:3]) / length, w / length])
            self.segments.append((s, s + length, tw, pose.copy()))
            s, prev = s + length, pose
        if not self.segments:
            raise StateError("poses", "every pose is the start pose: nothing to move")

    @property
    def length(self) -> float:
        """s at the end of the motion (inf for a direction or a twist)."""
        return self.segments[-1][1]

    def _segment(self, s: float) -> int:
        for k, seg in enumerate(self.segments):
            if s < seg[1]:
                return k
        return len(self.segments) - 1

    def twist(self, s: float) -> NDArray[np.float64]:
        r"""``(6,)`` $(v, \omega)$ per unit s at ``s`` (the segment the motion enters there)."""
        return self.segments[self._segment(s)][2]

    def segment_end(self, s: float) -> float:
        """s at the end of the segment the motion enters at ``s``."""
        return self.segments[self._segment(s)][1]

    def advance(self, pose: NDArray[np.float64], s: float, ds: float) -> NDArray[np.float64]:
        """``(7,)`` the pose at ``s + ds`` from ``pose`` at ``s`` (``ds`` within one segment)."""
        _, s1, tw, end = self.segments[self._segment(s)]
        if end is not None and s + ds >= s1:
            return end.copy()  # land on the given pose, not near it
        out = np.array(pose, dtype=float)
        out[:3] += tw[:3] * ds  # a zero component adds exactly 0: a +z lift keeps x, y to the bit
        if np.any(tw[3:]):
            turn = np.zeros(4)
            angle = float(np.linalg.norm(tw[3:])) * ds
            mujoco.mju_axisAngle2Quat(turn, tw[3:] / np.linalg.norm(tw[3:]), angle)
            out[3:] = _mul(turn, out[3:])
            out[3:] /= np.linalg.norm(out[3:])
        return out
