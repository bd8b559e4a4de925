r"""Holding at rest, and the joint motions a transmission leaves unheld.

A grasp is held when its REFS vertex $w_k$ is balanced at zero joint speed: contact
forces in their cones balance it on the object (eq. 20-24) and the actuators, with their
torque at zero speed (eq. 1), balance the finger side (eq. 19, with the transmission of
[`transmission`][mjtvm.model.transmission]: ``P^T u - J^T f + J_eq^T lambda = g_f``). Joint damping is
not in that balance (it is a loss, [`assembly`][mjtvm.problem2.assembly]), so the point
``qd = 0, alpha = 0`` satisfies every kinematic and operation-range row whenever these
statics hold, and every pair ``(k, l)`` of Problem 2 is feasible exactly when ``w_k`` is held:
Problem 2's first LP of each ``k`` is its hold test (`TvmmpResult.held`).

An underactuated hand can fail it for a reason no contact can fix: a joint motion ``v``
that no actuator drives and no equality constraint holds (``P v = 0``, ``J_eq v = 0``: the
Shadow hand's J1 - J2 under its sum tendon) takes no torque from the hand,
``v^T (P^T u + J_eq^T lambda) = 0``, so the contacts and gravity alone must balance along it,
``v^T (J^T f + g_f) = 0``. [`free_motions()`][mjtvm.problem2.holding.free_motions] gives those motions and [`unheld_motions()`][mjtvm.problem2.holding.unheld_motions]
says whether a REFS vertex fails because of them: with a free torque added along each, the
hold LP becomes feasible, and the least such torque is what the hand lacks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.lp import LinearProgram
from mjtvm.lp.solvers import solve_settled
from mjtvm.model.state import GraspState
from mjtvm.problem2.assembly import assemble

__all__ = ["UnheldMotion", "free_motions", "unheld_motions"]

#: A component of a free motion below this (of a unit vector) is not named in a message.
_SHOWN = 1e-3
#: The least free torque, relative to the torques the state's ranges give, below which the
#: REFS vertex is held without it (the solver's tolerance on the equilibrated LP is 1e-9).
_HELD_REL = 1e-7


@dataclass(frozen=True)
class UnheldMotion:
    r"""A REFS vertex that cannot be held because the transmission leaves joint motions free.

    Attributes
    ----------
    k
        The REFS vertex $w_k$.
    joints
        Per free motion, the names of the joints it moves.
    motions
        ``(F, M)`` unit joint motions $v$ with ``P v = 0`` and ``J_eq v = 0``.
    torque
        ``(F,)`` the least torque (N m per unit of motion, $|t_i|$ summed to a minimum)
        that would have to act along each motion for $w_k$ to be held.
    """

    k: int
    joints: tuple[tuple[str, ...], ...]
    motions: NDArray[np.float64]
    torque: NDArray[np.float64]

    def describe(self, joint_names: tuple[str, ...]) -> str:
        """One line: which joints, which motion, the torque it needs, and what to change."""
        parts = []
        for v, t in zip(self.motions, self.torque, strict=True):
            moved = ", ".join(f"{joint_names[j]} {v[j]:+.3g}" for j in np.flatnonzero(np.abs(v) > _SHOWN))
            parts.append(f"({moved}) needs {abs(t):.3g} N m")
        return (
            f"REFS vertex {self.k} cannot be held at rest: the transmission leaves joint motions that "
            "no actuator drives and no equality constraint holds, and the contacts do not balance "
            f"along them: {'; '.join(parts)}; couple those joints (an equality constraint or a "
            "tendon) or place the contacts so that they hold them"
        )


def free_motions(state: GraspState) -> NDArray[np.float64]:
    r"""``(F, M)`` an orthonormal basis of the joint motions no actuator drives and no equality
    constraint holds, the null space of ``[P; J_eq]``; ``(0, M)`` without a transmission
    (each joint its own actuator, eq. 19).

    The basis is taken per group of joints that the transmission's rows connect (a finger's
    tendon and its equalities), so that each motion names one finger's joints; each motion's
    first largest entry is positive.
    """
    m = state.num_joints
    t = state.transmission
    if t is None:
        return np.zeros((0, m))
    rows = t.moment if t.constraint_jacobian is None else np.vstack([t.moment, t.constraint_jacobian])
    out: list[NDArray[np.float64]] = []
    for group in _groups(rows):
        sub = rows[:, group][np.any(rows[:, group] != 0.0, axis=1)]
        if sub.shape[0] == 0:  # joints no row touches: each free on its own
            basis = np.eye(len(group))
        else:
            _, s, vt = np.linalg.svd(sub, full_matrices=True)
            rank = int(np.sum(s > max(sub.shape) * np.finfo(float).eps * float(s[0])))
            basis = vt[rank:]
        for v in basis:
            full = np.zeros(m)
            full[group] = v
            # The sign: the first entry within round-off of the largest is positive, so that
            # equal entries (J1 + J2 of a sum tendon) do not let LAPACK's round-off pick it.
            mag = np.abs(full)
            big = int(np.flatnonzero(mag >= (1.0 - 1e-9) * mag.max())[0])
            out.append(full * np.sign(full[big]))
    return np.array(out).reshape(-1, m)


def _groups(rows: NDArray[np.float64]) -> list[NDArray[np.int64]]:
    """The joints (columns) in groups connected through shared nonzero rows."""
    m = rows.shape[1]
    parent = list(range(m))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for row in rows:
        cols = np.flatnonzero(row)
        for c in cols[1:]:
            parent[find(int(c))] = find(int(cols[0]))
    roots = np.array([find(i) for i in range(m)])
    return [np.flatnonzero(roots == r) for r in dict.fromkeys(roots.tolist())]


def unheld_motions(state: GraspState, k: int) -> UnheldMotion | None:
    r"""Whether REFS vertex ``k`` fails to be held because of the transmission's free motions.

    Solves the hold LP of ``w_k`` (Problem 2's rows at ``qd = 0``, ``alpha = 0``) with a free
    torque ``t_i`` added along each free motion ``v_i`` of [`free_motions()`][mjtvm.problem2.holding.free_motions] in the torque
    balance, minimising $\sum_i |t_i|$.

    Returns
    -------
    UnheldMotion or None
        ``None`` when there is no free motion, when the hold LP is infeasible even with the
        free torques (the cause is elsewhere: the contacts or the ranges), or when it needs
        none of them (the vertex is held, or fails for another reason).
    """
    free = free_motions(state)
    if free.shape[0] == 0:
        return None
    asm = assemble(state)
    n, f = asm.num_variables, free.shape[0]
    lower, upper = asm.statics_bounds(state.refs[k])
    col_lower = np.concatenate([asm.col_lower, np.zeros(2 * f)])
    col_upper = np.concatenate([asm.col_upper, np.full(2 * f, np.inf)])
    for name in ("qd", "rho", "loss"):  # at rest: no joint speed, no slip, no loss
        if name in asm.blocks:
            col_lower[asm.blocks[name]] = 0.0
            col_upper[asm.blocks[name]] = 0.0
    import scipy.sparse as sp  # only on this diagnostic path, as for every scipy use here

    rows = asm.torque_rows[0]
    extra = np.zeros((asm.csc.shape[0], 2 * f))
    extra[rows, :f] = free.T  # + N t_plus - N t_minus in P^T u - J^T f + J_eq^T eq (+ N t) = g_f
    extra[rows, f:] = -free.T
    a = sp.hstack([asm.A, sp.csc_matrix(extra)], format="csc")
    cost = np.concatenate([np.zeros(n), np.ones(2 * f)])
    sol = solve_settled(LinearProgram(cost, a, lower, upper, col_lower, col_upper)).solution
    if sol.status != "optimal" or sol.x is None:
        return None
    t = sol.x[n : n + f] - sol.x[n + f :]
    scale = max(float(np.max([op.max_torque for op in state.operation_ranges])), 1e-300)
    if float(np.sum(np.abs(t))) <= _HELD_REL * scale:
        return None
    names = state.joint_names
    joints = tuple(tuple(names[j] for j in np.flatnonzero(np.abs(v) > _SHOWN)) for v in free)
    needed = np.abs(t) > _HELD_REL * scale
    return UnheldMotion(
        k, tuple(j for j, keep in zip(joints, needed, strict=True) if keep), free[needed], t[needed]
    )
