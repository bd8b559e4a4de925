r"""The kinematics alone of Problem 2: the kinematic alpha of a twist and the contacts that lock it.

[`diagnose()`][mjtvm.problem2.diagnosis.diagnose] asks first whether an alpha of 0 comes from the
kinematics (eq. 11-13) whatever the forces: [`kinematic_alpha()`][mjtvm.problem2.kinematic.kinematic_alpha]
maximises alpha with every joint at most its no-load speed and no statics, and
[`locking_contacts()`][mjtvm.problem2.kinematic.locking_contacts] names a minimal set of contacts
that lock the motion when it is 0.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog

from mjtvm.errors import ParamError, SolverError
from mjtvm.model.contacts import Contact, slide_unit, tangent_basis
from mjtvm.model.state import GraspState
from mjtvm.model.transmission import joint_speed_limits
from mjtvm.problem2.assembly import grasp_map_transpose

__all__ = ["kinematic_alpha", "locking_contacts"]

_KIN_ZERO = 1e-9  # kinematic alpha at most this (rows and speeds normalised to 1) is 0


def _kinematic_rows(
    state: GraspState, contacts: Sequence[Contact], r: NDArray[np.float64]
) -> tuple[list[NDArray[np.float64]], list[NDArray[np.float64]], int]:
    """Equality and inequality rows over ``[u (M), rho (S), alpha]`` (``qd = speed * u``, as
    eq. 11-13 write them in [`assembly`][mjtvm.problem2.assembly]) and the number of rho variables."""
    speed = np.array([op.max_speed for op in state.operation_ranges])
    tr = state.transmission
    if tr is not None:
        speed = joint_speed_limits(tr.moment, speed)
    s_contacts = [c for c in contacts if c.type == "S"]
    n_rho = (1 if s_contacts else 0) if state.slip == "shared" else len(s_contacts)
    m = state.num_joints
    eq: list[NDArray[np.float64]] = []
    ub: list[NDArray[np.float64]] = []
    for c in contacts:
        gt_r = grasp_map_transpose(c.position, state.object_position) @ r
        j = c.jacobian * speed
        sel = np.eye(state.dim) if c.type == "F" else c.normal.reshape(1, -1)
        for row_j, row_g in zip(sel @ j, sel @ gt_r, strict=True):
            row = np.concatenate([row_j, np.zeros(n_rho), [-row_g]])
            (ub if c.type == "D" else eq).append(row)
        if c.type == "S":
            k = s_contacts.index(c)
            slide = slide_unit(c)
            if state.slip == "shared":
                slide = c.slide_direction - (c.slide_direction @ c.normal) * c.normal  # type: ignore[operator]
            for t in tangent_basis(c.normal):
                row = np.concatenate([t @ j, np.zeros(n_rho), [-(t @ gt_r)]])
                row[m + (0 if state.slip == "shared" else k)] = t @ slide
                eq.append(row)
    if tr is not None and tr.constraint_jacobian is not None:  # J_eq qd = 0 (a coupling, a linkage)
        eq += [np.concatenate([row * speed, np.zeros(n_rho + 1)]) for row in tr.constraint_jacobian]
    return eq, ub, n_rho


def kinematic_alpha(
    state: GraspState, r: NDArray[np.float64], contacts: Sequence[Contact] | None = None
) -> float:
    r"""The largest alpha in [0, 1] of the kinematics alone (eq. 11-13) for the twist ``r``.

    Every joint speed at most its no-load speed (the operation range's largest), the object
    twist ``alpha r / max|r|``, each row normalised to a largest coefficient of 1; no statics
    and no torque. 0 means the ``contacts`` (default: the state's) lock the motion ``r``.

    Raises
    ------
    ParamError
        When ``r`` is not a non-zero twist of the state's dimension.
    SolverError
        When HiGHS (scipy's ``linprog``) does not settle the LP.
    """
    contacts = state.contacts if contacts is None else contacts
    r = np.asarray(r, dtype=float)
    if r.shape != (state.twist_dim,) or not np.all(np.isfinite(r)) or not np.any(r):
        raise ParamError("r", f"expected a non-zero finite twist of {state.twist_dim} numbers", r)
    r = r / float(np.max(np.abs(r)))
    eq, ub, n_rho = _kinematic_rows(state, contacts, r)
    if not eq and not ub:
        return 1.0

    def normalised(rows: list[NDArray[np.float64]]) -> NDArray[np.float64] | None:
        if not rows:
            return None
        a = np.array(rows)
        big = np.max(np.abs(a), axis=1, keepdims=True)
        return a / np.where(big > 0.0, big, 1.0)

    a_eq, a_ub = normalised(eq), normalised(ub)
    m = state.num_joints
    bounds = [(-1.0, 1.0)] * m + [(0.0, None)] * n_rho + [(0.0, 1.0)]
    cost = np.zeros(m + n_rho + 1)
    cost[-1] = -1.0
    res = linprog(
        cost,
        A_ub=a_ub,
        b_ub=None if a_ub is None else np.zeros(len(a_ub)),
        A_eq=a_eq,
        b_eq=None if a_eq is None else np.zeros(len(a_eq)),
        bounds=bounds,
        method="highs",
    )
    if res.status != 0:  # alpha = 0, u = 0, rho = 0 is always feasible: only a failure lands here
        raise SolverError("highs", res.message, None)
    alpha = float(res.x[-1])
    return 0.0 if alpha <= _KIN_ZERO else alpha


def locking_contacts(state: GraspState, r: NDArray[np.float64]) -> tuple[Contact, ...]:
    """A minimal set of the state's contacts whose kinematics alone give alpha 0.

    A deletion filter in the state's contact order: each contact is left out while the
    others still lock the motion ([`kinematic_alpha()`][mjtvm.problem2.kinematic.kinematic_alpha] 0).

    Parameters
    ----------
    state
        The grasp state.
    r
        ``(D,)`` the twist (an RVDS vertex) that the state's contacts lock.

    Returns
    -------
    tuple[Contact, ...]
        The locking contacts, one minimal set of possibly several.
    """
    kept = list(state.contacts)
    for c in list(kept):
        rest = [x for x in kept if x is not c]
        if kinematic_alpha(state, r, rest) == 0.0:
            kept = rest
    return tuple(kept)
