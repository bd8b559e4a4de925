r"""The polygon geometry of an operation range (eq. 1-3), as pure functions on vertices.

[`validated_vertices()`][mjtvm.model.polygon.validated_vertices] checks a polygon in the quadrant of absolute torque and speed
(shape, quadrant, origin, convexity, down-closure); [`halfplanes()`][mjtvm.model.polygon.halfplanes] lists its edges off
the axes; [`mirrored_halfplanes()`][mjtvm.model.polygon.mirrored_halfplanes] the sign combinations of those edges that eliminate
the box of eq. (2) exactly (the claim and proof are on
[`mirrored_halfplanes`][mjtvm.model.operation_range.OperationRange.mirrored_halfplanes]).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import StateError
from mjtvm.model.bounds import MAX_RANGE_VERTICES, float_array

__all__ = ["halfplanes", "mirrored_halfplanes", "validated_vertices"]

_TOL = 1e-9  # tolerance of the geometric checks, relative to each axis's largest value


def _cross(o: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def validated_vertices(raw: object) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The vertices ``v`` as floats, checked, with ``u = v / scale`` and ``scale = (max
    torque, max speed)``; [`StateError`][mjtvm.errors.StateError] (field ``""``) naming the problem.

    Torque and speed have unrelated units (1.5 N m beside 1.5e9 rad/s is a valid range), so
    every geometric check runs on ``u``, where both axes span [0, 1] and one absolute
    tolerance is scale-invariant per axis."""
    v = _quadrant_vertices(raw)
    scale = v.max(axis=0)
    u = v / scale
    if not np.any(np.all(u <= _TOL, axis=1)):
        raise StateError("", "the origin [0, 0] must be a vertex", v.tolist())
    check_convex(u, v)
    check_down_closed(u, v)
    return v, u, scale


def _quadrant_vertices(raw: object) -> NDArray[np.float64]:
    """At least 3 finite ``[torque, speed]`` pairs, none negative, with a positive torque
    and a positive speed."""
    v = float_array(raw, "", ndim=2, max_len=MAX_RANGE_VERTICES, what="a list of [torque, speed] pairs")
    if v.shape[1:] != (2,) or v.shape[0] < 3:
        raise StateError(
            "",
            f"expected at least 3 and at most {MAX_RANGE_VERTICES} [torque, speed] pairs, got shape {v.shape}",
            raw,
        )
    if np.any(v < 0.0):
        raise StateError(
            "",
            "vertices must lie in the quadrant of absolute torque and absolute speed (no negative coordinate)",
            v.tolist(),
        )
    t_max, s_max = v.max(axis=0)
    if t_max <= 0.0 or s_max <= 0.0:
        raise StateError("", "needs a vertex with positive torque and one with positive speed", v.tolist())
    return v


def check_convex(u: NDArray[np.float64], v: NDArray[np.float64]) -> None:
    """The scaled vertices ``u`` (``v`` as given, for messages) bound a convex polygon in
    the order given: no repeated vertex, the same turn everywhere, winding once."""
    n = len(u)
    turns = np.array([_cross(u[i - 1], u[i], u[(i + 1) % n]) for i in range(n)])
    if np.any(np.linalg.norm(u - np.roll(u, 1, axis=0), axis=1) <= _TOL):
        raise StateError("", "repeated vertex", v.tolist())
    if np.all(turns >= -_TOL) or np.all(turns <= _TOL):
        # Same turn everywhere; rule out a polygon that winds twice around.
        angles = np.arctan2(*(np.roll(u, -1, axis=0) - u).T[::-1])
        total = np.sum(np.mod(np.diff(np.append(angles, angles[0])) + np.pi, 2 * np.pi) - np.pi)
        if abs(abs(total) - 2 * np.pi) < 1e-6:
            return
    raise StateError(
        "", "not convex: the vertices, in the order given, must bound a convex polygon", v.tolist()
    )


def check_down_closed(u: NDArray[np.float64], v: NDArray[np.float64]) -> None:
    """Down-closure, given convexity and the origin: the largest torque is reached at zero
    speed and the largest speed at zero torque (``u``: scaled vertices, ``v``: as given)."""
    t_max, s_max = v.max(axis=0)
    if not np.any((u[:, 0] >= 1.0 - _TOL) & (u[:, 1] <= _TOL)):
        raise StateError(
            "",
            f"not down-closed: the largest torque {t_max:g} must be reached at zero speed "
            "(expected a vertex [max torque, 0] on the torque axis)",
            v.tolist(),
        )
    if not np.any((u[:, 1] >= 1.0 - _TOL) & (u[:, 0] <= _TOL)):
        raise StateError(
            "",
            f"not down-closed: the largest speed {s_max:g} must be reached at zero torque "
            "(expected a vertex [0, max speed] on the speed axis)",
            v.tolist(),
        )


def halfplanes(u: NDArray[np.float64], scale: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(h, 3)`` read-only rows ``[a_tau, a_qd, b]`` (eq. 3), one per edge off the axes.

    Outward edge normals of the scaled polygon ``u = v / scale``; for a down-closed polygon
    each is non-negative. A row ``a . u <= b`` is ``(a / scale) . v <= b`` in the given
    units, normalised so that ``[a_tau, a_qd]`` has unit length."""
    ccw = sum(_cross(u[0], u[i], u[i + 1]) for i in range(1, len(u) - 1)) > 0
    rows = []
    for i in range(len(u)):
        a, b = u[i], u[(i + 1) % len(u)]
        edge = b - a
        normal = np.array([edge[1], -edge[0]]) if ccw else np.array([-edge[1], edge[0]])
        length = float(np.linalg.norm(normal))
        if length <= _TOL:
            continue
        normal /= length
        offset = float(normal @ a)
        if offset <= _TOL:  # an axis edge through the origin: x >= 0 or y >= 0
            continue
        # (normal / scale) . v <= offset, multiplied by min(scale) first so that a
        # scale of 1e-300 cannot overflow the row before it is normalised.
        c = float(np.min(scale))
        given = normal * (c / scale)
        size = float(np.linalg.norm(given))
        rows.append([given[0] / size, given[1] / size, offset * (c / size)])
    hp = np.array(rows, dtype=float)
    hp[:, :2][np.abs(hp[:, :2]) < 1e-15] = 0.0
    hp.setflags(write=False)
    return hp


def mirrored_halfplanes(hp: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(h', 3)`` read-only rows ``[c_tau, c_qd, b]``: every edge ``[a_tau, a_qd, b]`` of
    ``hp`` in its sign combinations ``[s1 a_tau, s2 a_qd, b]`` (one sign where a
    coefficient is 0): eq. (2)'s box eliminated exactly."""
    rows: list[list[float]] = []
    for a_t, a_q, b in hp:
        for s1 in (1.0, -1.0) if a_t != 0.0 else (1.0,):
            for s2 in (1.0, -1.0) if a_q != 0.0 else (1.0,):
                rows.append([s1 * a_t, s2 * a_q, b])
    out = np.array(rows, dtype=float)
    out.setflags(write=False)
    return out
