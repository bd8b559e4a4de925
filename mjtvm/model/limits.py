r"""Joint position limits in Problems 1 and 2 (``docs/joint-limits.md``).

The paper's LPs bound each joint's torque and speed (eq. 1-3) but not its position: a joint
sitting on its limit is free, in the LP, to move further into it. `JointLimits` carries
each joint's position ``q_j`` and range ``[lo_j, hi_j]`` (MuJoCo's ``jnt_range`` and the
state's ``qpos``), and `assemble()` turns them into rows on the
joint speeds ``qd`` (the module docstring's choice, documented in ``docs/joint-limits.md``):

* **instantaneous** (Problems 1 and 2): a joint within `JointLimits.tolerance` of its
  upper limit (``hi_j - q_j <= tol``) gets ``qd_j <= 0``; of its lower limit, ``qd_j >= 0``.
  The paper's instantaneous measure, made physically true: the joint can still leave its
  limit, never push past it;
* **travel horizon** (Problem 2 only): while the object moves along ``alpha r_l`` by
  `JointLimits.horizon` metres of travel ([`travel_speed()`][mjtvm.model.limits.travel_speed]: the fastest of the
  object's point ``p_O`` and its contact points), no joint may cross its limit:
  ``H qd_j <= (hi_j - q_j) s_l alpha`` and ``-H qd_j <= (q_j - lo_j) s_l alpha`` with
  ``s_l`` the travel speed of ``r_l``, linear in ``(qd, alpha)``. Problem 1's twist is free
  (no ``alpha``), and ``s(rdot)`` is a norm, convex: ``H qd_j <= slack s(rdot)`` is not a
  convex constraint, so Problem 1 takes the instantaneous rows only.

A state without limits (``GraspState.joint_limits is None``) has no such row: the paper's
LP entry for entry.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import StateError
from mjtvm.model.bounds import MAX_ABS, describe, number

__all__ = ["DEFAULT_HORIZON", "DEFAULT_TOLERANCE", "JointLimits", "travel_speed", "with_limit_horizon"]

#: A joint within this of its limit (rad for a hinge, m for a slide) is on it. Five times the
#: largest gap a lift's IK leaves at a clamped joint (the Allegro thumb's thj1 at states 25-29
#: of allegro-ik: 0, 2.1e-4, 0, 6.3e-5, 2.1e-4 rad), and 1e-3 of the smallest shipped range.
DEFAULT_TOLERANCE = 1e-3
#: Metres of object travel within which no joint may reach its limit (Problem 2). 1 mm: the
#: physics check drives a witness for 7 ms (``docs/physics-check.md``), i.e. 1 mm of travel
#: at 0.14 m/s, above every alpha of the shipped grasps' lifts (allegro-ik: at most 0.064 m/s,
#: 0.45 mm in 7 ms); a longer horizon is no longer a property of the state (the Jacobians
#: change over a centimetre of travel, and the horizon row uses the state's).
DEFAULT_HORIZON = 1e-3


def _scalar(value: Any, field: str) -> float:
    x = number(value, field)
    if x < 0.0:
        raise StateError(field, f"expected a number >= 0, got {describe(value)}", value)
    return x


class _Point(Protocol):
    """What `travel_speed()` reads of a contact: its position."""

    @property
    def position(self) -> NDArray[np.float64]: ...


class _Travel(Protocol):
    """What `travel_speed()` reads of a state (a `GraspState`; limits stays below state)."""

    @property
    def dim(self) -> int: ...

    @property
    def object_position(self) -> NDArray[np.float64]: ...

    @property
    def contacts(self) -> Sequence[_Point]: ...


_Limited = TypeVar("_Limited", bound="_Horizon")


class _Horizon(Protocol):
    """What `with_limit_horizon()` reads and calls of a state (a `GraspState`)."""

    @property
    def joint_limits(self) -> JointLimits | None: ...

    def with_(self: _Limited, **changes: Any) -> _Limited: ...


@dataclass(frozen=True, eq=False)
class JointLimits:
    r"""The joints' positions and position ranges of one state.

    Parameters
    ----------
    position
        ``(M,)`` $q_j$ (rad or m), the configuration of the state; may lie a little
        beyond a limit (MuJoCo's limits are soft): such a joint is on its limit.
    lower, upper
        ``(M,)`` $[lo_j, hi_j]$ (rad or m); ``-inf``, ``+inf`` for a joint without
        limits (both or neither), ``lo_j <= hi_j``.
    tolerance
        A joint with ``hi_j - q_j <= tolerance`` is on its upper limit (``q_j - lo_j`` the
        lower), in the joints' units ([`DEFAULT_TOLERANCE`][mjtvm.model.limits.DEFAULT_TOLERANCE]).
    horizon
        ``H`` (m of object travel, [`DEFAULT_HORIZON`][mjtvm.model.limits.DEFAULT_HORIZON]; 0: the instantaneous rows only).
    """

    position: NDArray[np.float64]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    tolerance: float = DEFAULT_TOLERANCE
    horizon: float = DEFAULT_HORIZON

    def __post_init__(self) -> None:
        pos = np.array(self.position, dtype=float).reshape(-1)
        lo = np.array(self.lower, dtype=float).reshape(-1)
        hi = np.array(self.upper, dtype=float).reshape(-1)
        if not (pos.shape == lo.shape == hi.shape):
            raise StateError(
                "joints",
                f"expected one position and range per joint, got {pos.shape[0]}, {lo.shape[0]}, {hi.shape[0]}",
            )
        for name, a in (("position", pos), ("range", np.concatenate([lo, hi]))):
            bad = np.flatnonzero(np.isnan(a) | (np.isfinite(a) & (np.abs(a) > MAX_ABS)))
            if len(bad):
                raise StateError(
                    f"joints[{bad[0] % len(pos)}].{name}", f"expected a number, got {a[bad[0]]!r}"
                )
        if not np.all(np.isfinite(pos)):
            raise StateError(
                f"joints[{np.flatnonzero(~np.isfinite(pos))[0]}].position", "expected a finite number"
            )
        limited = np.isfinite(lo)
        if (
            np.any(limited != np.isfinite(hi))
            or np.any(lo[~limited] != -np.inf)
            or np.any(hi[~limited] != np.inf)
        ):
            j = int(
                np.flatnonzero(
                    (limited != np.isfinite(hi)) | (~limited & ((lo != -np.inf) | (hi != np.inf)))
                )[0]
            )
            raise StateError(f"joints[{j}].range", "expected two finite limits, or none (-inf, +inf)")
        if np.any(lo[limited] > hi[limited]):
            j = int(np.flatnonzero(limited & (lo > hi))[0])
            raise StateError(
                f"joints[{j}].range",
                f"expected [lower, upper] with lower <= upper, got [{float(lo[j]):g}, {float(hi[j]):g}]",
            )
        for a in (pos, lo, hi):
            a.setflags(write=False)
        object.__setattr__(self, "position", pos)
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        object.__setattr__(self, "tolerance", _scalar(self.tolerance, "joint_limits.tolerance"))
        object.__setattr__(self, "horizon", _scalar(self.horizon, "joint_limits.horizon"))

    @property
    def num_joints(self) -> int:
        """M."""
        return int(self.position.shape[0])

    @property
    def limited(self) -> NDArray[np.bool_]:
        """``(M,)`` whether each joint has a range."""
        return np.isfinite(self.lower)

    @property
    def upper_slack(self) -> NDArray[np.float64]:
        """``(M,)`` ``hi_j - q_j`` (``inf`` without a range; negative beyond the limit)."""
        with np.errstate(invalid="ignore"):
            return self.upper - self.position

    @property
    def lower_slack(self) -> NDArray[np.float64]:
        """``(M,)`` ``q_j - lo_j``."""
        with np.errstate(invalid="ignore"):
            return self.position - self.lower

    @property
    def at_upper(self) -> NDArray[np.bool_]:
        """``(M,)`` on the upper limit: ``hi_j - q_j <= tolerance`` (then ``qd_j <= 0``)."""
        return self.upper_slack <= self.tolerance

    @property
    def at_lower(self) -> NDArray[np.bool_]:
        """``(M,)`` on the lower limit: ``q_j - lo_j <= tolerance`` (then ``qd_j >= 0``)."""
        return self.lower_slack <= self.tolerance

    def horizon_sides(self) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
        r"""The horizon rows (Problem 2): ``(joint, sign, rate)`` per limited side not on its
        limit, ``sign * qd_j <= rate * s_l * alpha`` with ``rate = slack / H`` (rad per m of
        travel); empty with ``horizon == 0``. Upper sides first (sign +1), then lower (-1),
        each in joint order."""
        if self.horizon == 0.0:
            empty = np.zeros(0)
            return np.zeros(0, dtype=np.int64), empty, empty
        up = np.flatnonzero(self.limited & ~self.at_upper)
        dn = np.flatnonzero(self.limited & ~self.at_lower)
        joints = np.concatenate([up, dn]).astype(np.int64)
        sign = np.concatenate([np.ones(len(up)), -np.ones(len(dn))])
        rate = np.concatenate([self.upper_slack[up], self.lower_slack[dn]]) / self.horizon
        return joints, sign, rate

    def with_options(self, *, tolerance: float | None = None, horizon: float | None = None) -> JointLimits:
        """A copy with another tolerance or horizon (``None``: kept)."""
        return JointLimits(
            self.position,
            self.lower,
            self.upper,
            self.tolerance if tolerance is None else tolerance,
            self.horizon if horizon is None else horizon,
        )


def with_limit_horizon(state: _Limited, horizon: float | None) -> _Limited:
    """``state`` with Problem 2's travel horizon ``horizon`` (m) in its joint limits.

    Parameters
    ----------
    state
        A grasp state.
    horizon
        Metres of object travel (0: the on-limit rows only); ``None`` keeps the state's.

    Returns
    -------
    GraspState
        ``state`` itself when ``horizon`` is ``None`` or the state has no joint limits (a
        horizon without limits bounds nothing), else a copy with the new horizon.
    """
    lim = state.joint_limits
    if horizon is None or lim is None:
        return state
    return state.with_(joint_limits=lim.with_options(horizon=horizon))


def travel_speed(state: _Travel, r: NDArray[np.float64]) -> float:
    r"""``s(r)``: how fast the object travels along twist ``r`` (m/s per unit of ``r``).

    The largest speed of the object's point ``p_O`` (``|v|``) and of its contact points
    (``|v + omega x (p_c - p_O)|``, eq. 6): ``|v|`` for a translation, and for a rotation
    (``v = 0``) the speed of the contact point farthest from the axis, so that a pure
    rotation also has a travel (0 only when no point among them moves, e.g. ``r = 0``).
    The horizon rows measure the object's travel with it (module docstring).
    """
    d = state.dim
    r = np.asarray(r, dtype=float)
    v, w = r[:d], r[d:]
    best = math.sqrt(float(v @ v))
    if not state.contacts:
        return best
    arms = np.array([c.position for c in state.contacts], dtype=float) - state.object_position
    if d == 2:
        u = v + w[0] * np.column_stack([-arms[:, 1], arms[:, 0]])
    else:  # w x arms, as np.cross forms it (a1 b2 - a2 b1, ...), without its overhead
        u = np.empty_like(arms)
        u[:, 0] = w[1] * arms[:, 2] - w[2] * arms[:, 1]
        u[:, 1] = w[2] * arms[:, 0] - w[0] * arms[:, 2]
        u[:, 2] = w[0] * arms[:, 1] - w[1] * arms[:, 0]
        u += v
    return max(best, math.sqrt(float(np.max(np.einsum("ij,ij->i", u, u)))))
