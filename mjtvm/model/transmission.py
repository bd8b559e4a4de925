r"""Actuators, transmissions and equality constraints of a hand (``docs/state-format.md``).

The paper drives every joint by its own motor: the operation range of eq. (1) bounds the
pair (torque, speed) of a joint. A real hand drives its joints through a transmission: one
tendon actuator moves two distal joints, a linkage closes a kinematic loop. A
[`Transmission`][mjtvm.model.transmission.Transmission] states it linearly at the state, as MuJoCo does:

* actuator speeds ``s = P qd`` and joint torques ``P^T u`` from the actuator forces ``u``,
  with ``P`` the ``(A, M)`` moment matrix (MuJoCo's ``actuator_moment``); the operation
  ranges bound each actuator's pair ``(u_a, s_a)`` instead of a joint's;
* equality constraints ``J_eq qd = 0`` (a joint coupling, a ``connect`` closing a linkage),
  whose forces ``J_eq^T lambda`` (``lambda`` free) join the torque balance;
* passive joint damping ``b`` (N m s/rad): a joint moving at ``qd`` needs ``b qd`` more.

The torque balance of eq. (19) becomes ``P^T u - J^T f + J_eq^T lambda - b qd = g_f`` (the
passive springs at the state belong in ``g_f``). With ``P = I``, no constraint and no
damping it is eq. (19) itself, and a state without a transmission is assembled exactly as
the paper's.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import StateError
from mjtvm.model.bounds import MAX_JOINTS, MAX_NAME, describe, float_array
from mjtvm.model.operation_range import OperationRange

__all__ = ["Transmission", "joint_speed_limits", "transmission_from_dict", "transmission_to_dict"]

MAX_CONSTRAINTS = 3 * MAX_JOINTS  # a weld is 6 rows; a hand closes few loops


def _names(value: Any, field: str, limit: int) -> tuple[str, ...]:
    names = tuple(value)
    if len(names) > limit:
        raise StateError(field, f"expected at most {limit} entries, got {len(names)}")
    for i, name in enumerate(names):
        if not isinstance(name, str) or not name or len(name) > MAX_NAME:
            raise StateError(
                f"{field}[{i}]", f"expected a name of 1 to {MAX_NAME} characters, got {describe(name)}"
            )
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise StateError(field, f"names must be unique; repeated: {dup}")
    return names


@dataclass(frozen=True, eq=False)
class Transmission:
    r"""How the actuators and the equality constraints act on the M joints of a state.

    Parameters
    ----------
    actuator_names
        The A actuators, in the order of `GraspState.operation_ranges`.
    moment
        ``(A, M)`` the moment matrix ``P``: actuator speeds ``s = P qd`` (m/s or rad/s),
        joint torques ``P^T u`` (N m) from actuator forces ``u`` (N or N m). Every row is
        non-zero (an actuator that moves no joint of the state has no place in it).
    constraint_names
        The C equality-constraint rows (a ``connect`` gives three).
    constraint_jacobian
        ``(C, M)`` ``J_eq``: the joint speeds keep ``J_eq qd = 0``; the constraint forces
        ``J_eq^T lambda`` (N m, ``lambda`` free) join the torque balance. ``None`` when C = 0.
    joint_damping
        ``(M,)`` passive damping ``b >= 0`` (N m s/rad) of each joint, in the balance as
        ``b qd``; ``None`` for none.
    """

    actuator_names: tuple[str, ...]
    moment: NDArray[np.float64]
    constraint_names: tuple[str, ...] = ()
    constraint_jacobian: NDArray[np.float64] | None = None
    joint_damping: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        names = _names(self.actuator_names, "transmission.actuators", MAX_JOINTS)
        if not names:
            raise StateError("transmission.actuators", "expected at least one actuator")
        object.__setattr__(self, "actuator_names", names)
        p = float_array(self.moment, "transmission.moment", ndim=2, what="one row of M numbers per actuator")
        if p.shape[0] != len(names):
            raise StateError(
                "transmission.moment", f"expected {len(names)} rows (one per actuator), got {p.shape[0]}"
            )
        for a in np.flatnonzero(~np.any(p != 0.0, axis=1)):
            raise StateError(
                f"transmission.actuators[{a}].moment", "expected a non-zero row: the actuator moves no joint"
            )
        object.__setattr__(self, "moment", p)
        cnames = _names(self.constraint_names, "transmission.constraints", MAX_CONSTRAINTS)
        object.__setattr__(self, "constraint_names", cnames)
        if self.constraint_jacobian is None:
            if cnames:
                raise StateError("transmission.constraints", "expected a Jacobian row per constraint")
        else:
            jeq = float_array(self.constraint_jacobian, "transmission.constraint_jacobian", ndim=2)
            if jeq.shape != (len(cnames), p.shape[1]):
                raise StateError(
                    "transmission.constraint_jacobian",
                    f"expected {len(cnames)} x {p.shape[1]} (one column per joint), got {jeq.shape}",
                )
            for c in np.flatnonzero(~np.any(jeq != 0.0, axis=1)):
                raise StateError(f"transmission.constraints[{c}].jacobian", "expected a non-zero row")
            object.__setattr__(self, "constraint_jacobian", jeq if cnames else None)
        if self.joint_damping is not None:
            b = float_array(self.joint_damping, "transmission.joint_damping", ndim=1)
            if b.shape != (p.shape[1],):
                raise StateError(
                    "transmission.joint_damping",
                    f"expected {p.shape[1]} numbers (one per joint), got {b.shape[0]}",
                )
            if np.any(b < 0.0):
                raise StateError(
                    "transmission.joint_damping", f"expected numbers >= 0, got {float(b.min()):g}"
                )
            object.__setattr__(self, "joint_damping", b if np.any(b > 0.0) else None)

    @property
    def num_joints(self) -> int:
        """M, the columns of `moment`."""
        return int(self.moment.shape[1])

    @property
    def num_constraints(self) -> int:
        """C."""
        return len(self.constraint_names)


def joint_speed_limits(moment: NDArray[np.float64], speeds: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(M,)`` a speed scale per joint: ``s_a / |P_aj|`` of the actuator with the largest
    moment on joint j (``speeds`` the actuators' largest speeds), so that a round-off or a
    minor moment arm on another actuator does not blow the scale up; a passive joint (no
    actuator moves it) the fastest of the others. A size for measuring and normalising, not a
    bound of the LP."""
    p = np.abs(moment)
    strongest = np.argmax(p, axis=0)
    arm = p[strongest, np.arange(p.shape[1])]
    out = np.where(arm > 0.0, np.asarray(speeds, dtype=float)[strongest] / np.where(arm > 0.0, arm, 1.0), 0.0)
    return np.where(out > 0.0, out, float(out.max(initial=0.0)))


def transmission_to_dict(t: Transmission, ranges: Sequence[OperationRange]) -> dict[str, Any]:
    """The ``transmission`` object of a ``mjtvm.state/2`` document."""
    out: dict[str, Any] = {
        "actuators": [
            {"name": n, "moment": row.tolist(), "operation_range": r.to_list()}
            for n, row, r in zip(t.actuator_names, t.moment, ranges, strict=True)
        ]
    }
    if t.constraint_jacobian is not None:
        out["constraints"] = [
            {"name": n, "jacobian": row.tolist()}
            for n, row in zip(t.constraint_names, t.constraint_jacobian, strict=True)
        ]
    if t.joint_damping is not None:
        out["joint_damping"] = t.joint_damping.tolist()
    return out


def transmission_from_dict(data: Any) -> tuple[Transmission, tuple[OperationRange, ...]]:
    """The transmission and the actuators' operation ranges of a ``transmission`` object
    (field names as in the document; the caller checks the sizes against the joints)."""
    if not isinstance(data, Mapping):
        raise StateError("transmission", f"expected a JSON object, got {describe(data)}")
    unknown = sorted(set(data) - {"actuators", "constraints", "joint_damping"})
    if unknown:
        raise StateError(
            f"transmission.{unknown[0]}", "unknown key (allowed: actuators, constraints, joint_damping)"
        )
    acts = data.get("actuators")
    if not isinstance(acts, list) or not acts:
        raise StateError(
            "transmission.actuators", f"expected a non-empty list of actuators, got {describe(acts)}"
        )
    names, rows, ranges = [], [], []
    for i, a in enumerate(acts):
        field = f"transmission.actuators[{i}]"
        if not isinstance(a, Mapping) or set(a) != {"name", "moment", "operation_range"}:
            raise StateError(field, "expected an object with exactly name, moment and operation_range")
        names.append(a["name"])
        rows.append(float_array(a["moment"], f"{field}.moment", ndim=1, what="M numbers (one per joint)"))
        try:
            ranges.append(OperationRange(a["operation_range"]))
        except StateError as e:
            raise e.under(f"{field}.operation_range") from None
    _equal_lengths(rows, "moment", "transmission.actuators")
    cons = data.get("constraints", [])
    if not isinstance(cons, list):
        raise StateError("transmission.constraints", f"expected a list of constraints, got {describe(cons)}")
    cnames, crows = [], []
    for i, c in enumerate(cons):
        field = f"transmission.constraints[{i}]"
        if not isinstance(c, Mapping) or set(c) != {"name", "jacobian"}:
            raise StateError(field, "expected an object with exactly name and jacobian")
        cnames.append(c["name"])
        crows.append(
            float_array(c["jacobian"], f"{field}.jacobian", ndim=1, what="M numbers (one per joint)")
        )
    _equal_lengths(rows + crows, "jacobian", "transmission.constraints", start=len(rows))
    t = Transmission(
        actuator_names=tuple(names),
        moment=np.vstack(rows),
        constraint_names=tuple(cnames),
        constraint_jacobian=np.vstack(crows) if crows else None,
        joint_damping=data.get("joint_damping"),
    )
    return t, tuple(ranges)


def _equal_lengths(rows: list[NDArray[np.float64]], key: str, field: str, start: int = 0) -> None:
    for i in range(max(start, 1), len(rows)):
        if rows[i].shape != rows[0].shape:
            raise StateError(
                f"{field}[{i - start}].{key}",
                f"expected {rows[0].shape[0]} numbers (one per joint), got {rows[i].shape[0]}",
            )
