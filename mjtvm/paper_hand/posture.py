r"""Postures of a two-link [yaw, pitch] + [pitch, yaw] finger touching a sphere, in closed form.

The paper prints Case 1's contact points (section 5, Fig. 5) but not the joint angles, and
finger 1 (four joints, one point contact: three equations) is redundant: its posture is a
choice, and the TVMM depends on it strongly (``docs/paper-results.md``). This module states
the choice as a rule instead of IK start angles, and enumerates the alternatives:

* [`planar_fingertip()`][mjtvm.paper_hand.posture.planar_fingertip] (the rule): the fingertip (the end of link 2) on the point, the
  finger planar (distal yaw 0, so both links lie in the vertical plane through the base and
  the point, as finger 3 in the same case), elbow up.
* [`fingertip_family()`][mjtvm.paper_hand.posture.fingertip_family]: every posture with the fingertip on the point (the elbow on the
  circle of points 1 link from both the base and the point), by the elbow's angle on that circle.
* [`side_postures()`][mjtvm.paper_hand.posture.side_postures]: link 2 touching the point at a distance ``along`` from its joint,
  tangent to the sphere (a contact on the link, like finger 3's two contacts).

Geometry (the model of [`hand_mjcf()`][mjtvm.paper_hand.hand.hand_mjcf]): finger ``i`` starts at the origin of
body ``f<i>_link1``, its frame turned by the heading ``H`` about +z; link 1 points along
``Rz(H) Rz(y0) Ry(-p0) e_x`` = ``Rz(H) (cos y0 cos p0, sin y0 cos p0, sin p0)``, link 2 along
``R1 Ry(-p1) Rz(y1) e_x`` = ``R1 (cos p1 cos y1, sin y1, sin p1 cos y1)``; every link has the
length of the offset of body ``f<i>_link2``. Each direction has at most one joint solution
inside the model's ranges (yaw within +-90 deg): [`finger_angles()`][mjtvm.paper_hand.posture.finger_angles].

World frame, SI units (m, rad).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import ModelError

__all__ = [
    "FingerGeometry",
    "FingerPosture",
    "finger_angles",
    "finger_geometry",
    "fingertip_family",
    "planar_fingertip",
    "side_postures",
]

JOINTS = ("yaw0", "pitch0", "pitch1", "yaw1")


def _rz(a: float) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _ry(a: float) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


@dataclass(frozen=True)
class FingerGeometry:
    """Base (m), heading (rad about +z), link length (m), joint names and ranges (rad) of a finger."""

    finger: int
    base: NDArray[np.float64]
    heading: float
    link: float
    joints: tuple[str, ...]
    ranges: tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class FingerPosture:
    r"""One posture: joint name -> angle (rad), the elbow (m) and how the finger touches.

    ``contact`` is ``"tip"`` or ``"side"``; ``along`` the contact's distance from the second
    pitch joint along link 2 (m; the link length for the tip); ``parameter`` the family's
    coordinate (rad: the elbow angle psi for the tip, link 2's angle phi in the tangent
    plane for the side).
    """

    angles: dict[str, float]
    elbow: NDArray[np.float64]
    contact: str
    along: float
    parameter: float


def finger_geometry(model: mujoco.MjModel, finger: int) -> FingerGeometry:
    """The finger's geometry read from the compiled model (raises if it is not [yaw, pitch] + [pitch, yaw])."""
    names = tuple(f"f{finger}_{j}" for j in JOINTS)
    ranges = []
    for name in names:
        if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name) < 0:
            raise ModelError(
                f"finger {finger}", f"has no joint {name!r}: expected [yaw, pitch] + [pitch, yaw]"
            )
        lo, hi = model.joint(name).range
        ranges.append((float(lo), float(hi)))
    body = model.body(f"f{finger}_link1")
    q = np.array(body.quat, dtype=float)
    heading = float(2.0 * np.arctan2(q[3], q[0]))
    link = float(model.body(f"f{finger}_link2").pos[0])
    return FingerGeometry(finger, np.array(body.pos, dtype=float), heading, link, names, tuple(ranges))


def _inside(angles: Sequence[float], geo: FingerGeometry, tol: float = 1e-12) -> bool:
    return all(lo - tol <= a <= hi + tol for a, (lo, hi) in zip(angles, geo.ranges, strict=True))


def finger_angles(geo: FingerGeometry, elbow: ArrayLike, direction: ArrayLike) -> dict[str, float] | None:
    r"""Joint angles putting link 1 from the base to ``elbow`` and link 2 along ``direction``.

    Link 1: ``(a, b, c) = Rz(-H) (elbow - base) / l``; ``p0 = asin c, y0 = atan2(b, a)`` or
    ``p0 = pi - asin c, y0 = atan2(-b, -a)``. Link 2: ``(x, y, z) = R1^T d``,
    ``y1 = asin y``, ``p1 = atan2(z, x)``. Returns the solution inside the joint ranges
    (the first of the two link-1 branches), ``None`` if neither is.
    """
    a, b, c = _rz(-geo.heading) @ ((np.asarray(elbow, dtype=float) - geo.base) / geo.link)
    c = float(np.clip(c, -1.0, 1.0))
    d = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    for p0, y0 in ((np.arcsin(c), np.arctan2(b, a)), (np.pi - np.arcsin(c), np.arctan2(-b, -a))):
        r1 = _rz(geo.heading) @ _rz(y0) @ _ry(-p0)
        x, y, z = r1.T @ d
        q = (float(y0), float(p0), float(np.arctan2(z, x)), float(np.arcsin(np.clip(y, -1.0, 1.0))))
        if _inside(q, geo):
            return dict(zip(geo.joints, q, strict=True))
    return None


def planar_fingertip(geo: FingerGeometry, point: ArrayLike) -> FingerPosture:
    r"""The rule: fingertip on ``point``, both links in the vertical plane through the base, elbow up.

    In that plane (horizontal coordinate ``r`` from the base towards the point, height
    ``z``) the two-link IK is ``D = |(r, z)|``, ``gamma = acos(D / 2l)``, link 1 at the
    elevation ``atan2(z, r) + gamma`` (elbow up; ``- gamma`` is elbow down).

    Raises
    ------
    ModelError
        The point is out of reach or the planar posture leaves the joint ranges.
    """
    p = np.asarray(point, dtype=float)
    h = p[:2] - geo.base[:2]
    r, z = float(np.linalg.norm(h)), float(p[2] - geo.base[2])
    dist = float(np.hypot(r, z))
    if not 0.0 < dist <= 2.0 * geo.link:
        raise ModelError(
            f"finger {geo.finger}", f"point {p.tolist()} out of reach ({dist:.4g} m from the base)"
        )
    up = np.arctan2(z, r) + np.arccos(dist / (2.0 * geo.link))
    horizontal = np.r_[h / r, 0.0]
    elbow = geo.base + geo.link * (np.cos(up) * horizontal + np.sin(up) * np.array([0.0, 0.0, 1.0]))
    angles = finger_angles(geo, elbow, p - elbow)
    if angles is None:
        raise ModelError(f"finger {geo.finger}", "the planar elbow-up posture leaves the joint ranges")
    angles[geo.joints[3]] = 0.0  # exactly planar (atan of a round-off)
    return FingerPosture(angles, elbow, "tip", geo.link, 0.0)


def _outward(elbow: NDArray[np.float64], point: NDArray[np.float64], centre: NDArray[np.float64]) -> bool:
    """Link 2 from ``elbow`` ending at ``point`` on the sphere stays outside it."""
    return float((elbow - point) @ (centre - point)) < 0.0


def fingertip_family(
    geo: FingerGeometry, point: ArrayLike, centre: ArrayLike, angles: ArrayLike
) -> list[FingerPosture]:
    r"""Every posture with the fingertip on ``point``, at the elbow angles ``angles`` (rad).

    The elbow lies on the circle of the points one link from the base and from ``point``:
    centre ``m = (base + point) / 2``, radius ``sqrt(l^2 - |point - base|^2 / 4)``; psi = 0
    is its highest point (the planar elbow-up posture), psi > 0 turns it towards
    ``(point - base) x e_z``. Postures outside the joint ranges, or whose link 2 would
    enter the sphere, are left out.
    """
    p, c = np.asarray(point, dtype=float), np.asarray(centre, dtype=float)
    axis = p - geo.base
    dist = float(np.linalg.norm(axis))
    axis /= dist
    mid, radius = geo.base + 0.5 * dist * axis, float(np.sqrt(geo.link**2 - 0.25 * dist**2))
    side = np.cross(axis, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    up = np.cross(side, axis)
    out = []
    for psi in np.asarray(angles, dtype=float):
        elbow = mid + radius * (np.cos(psi) * up + np.sin(psi) * side)
        q = finger_angles(geo, elbow, p - elbow)
        if q is not None and _outward(elbow, p, c):
            out.append(FingerPosture(q, elbow, "tip", geo.link, float(psi)))
    return out


def side_postures(
    geo: FingerGeometry, point: ArrayLike, centre: ArrayLike, along: float
) -> list[FingerPosture]:
    r"""Postures with link 2 tangent to the sphere at ``point``, ``along`` (m) from its joint.

    Link 2's direction ``d`` lies in the tangent plane (``d = cos phi u + sin phi w``); the
    elbow ``point - along d`` must be one link from the base: the roots in phi of
    ``|point - along d - base| - l`` (found on a 1/2-degree grid, refined by bisection to
    1e-15 rad). One posture per root inside the joint ranges; ``parameter`` is phi.
    """
    from scipy.optimize import brentq

    p, c = np.asarray(point, dtype=float), np.asarray(centre, dtype=float)
    n = (c - p) / np.linalg.norm(c - p)
    u = np.cross(n, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    w = np.cross(n, u)

    def gap(phi: float) -> float:
        d = np.cos(phi) * u + np.sin(phi) * w
        return float(np.linalg.norm(p - along * d - geo.base)) - geo.link

    grid = np.linspace(0.0, 2.0 * np.pi, 721)
    values = [gap(x) for x in grid]
    out = []
    for k in range(len(grid) - 1):
        if values[k] * values[k + 1] < 0.0:
            phi = brentq(gap, grid[k], grid[k + 1], xtol=1e-15)
            d = np.cos(phi) * u + np.sin(phi) * w
            elbow = p - along * d
            q = finger_angles(geo, elbow, d)
            if q is not None:
                out.append(FingerPosture(q, elbow, "side", float(along), float(phi)))
    return out
