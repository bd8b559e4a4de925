r"""Kinematic measures of a grasp state: the hand-object manipulability (Yoshikawa's measure)
and the kinematic velocity polytope (``docs/measures.md``).

Twists are scaled like the wrenches of [`wrenches`][mjtvm.measures.wrenches]:
``[v; rho omega]`` (m/s), with ``v`` the velocity of the object position and ``rho`` the torque
scale, so that a scaled wrench times a scaled twist is the power (W) and volumes and
ellipsoids of twists have one unit.

The contact kinematics used by the manipulability are the equality constraints of the
paper's eq. (9)-(13) and of a transmission: ``J_i qd = G_i^T rdot`` for an F contact (d rows),
``n^T J_i qd = n^T G_i^T rdot`` for L and S (the normal; an S-point's tangential slip is
free), and ``J_eq qd = 0``. A D-point's ``<=`` (eq. 12) is no linear constraint and is left
out there; the velocity polytope keeps it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from mjtvm.measures.wrenches import RANK_REL_TOL
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.model.transmission import Transmission
from mjtvm.polytopes.lifted import lifted_polytope
from mjtvm.polytopes.projection import project_lp
from mjtvm.polytopes.volume import hull_volume
from mjtvm.problem2.assembly import grasp_map_transpose

__all__ = ["contact_kinematics", "kinematic_polytope", "manipulability", "speed_only_state"]


def _twist_scale(state: GraspState, rho: float) -> NDArray[np.float64]:
    """``(D,)`` the factors of the scaled twist ``[v; rho omega]``."""
    d = state.dim
    return np.concatenate([np.ones(d), np.full(state.twist_dim - d, rho)])


def contact_kinematics(
    state: GraspState, torque_scale: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(A, B)``: the equality constraints ``A qd = B t`` of the module docstring on the joint
    speeds ``qd`` (``(c, M)``) and the scaled twist ``t`` (``(c, D)``), the transmission's
    ``J_eq qd = 0`` last (``B`` rows 0)."""
    m, big_d = state.num_joints, state.twist_dim
    inv = 1.0 / _twist_scale(state, torque_scale)
    a_rows, b_rows = [np.zeros((0, m))], [np.zeros((0, big_d))]
    for c in state.contacts:
        if c.type == "D":
            continue
        sel = np.eye(state.dim) if c.type == "F" else c.normal.reshape(1, -1)
        a_rows.append(sel @ c.jacobian)
        b_rows.append((sel @ grasp_map_transpose(c.position, state.object_position)) * inv)
    t = state.transmission
    if t is not None and t.constraint_jacobian is not None:
        a_rows.append(t.constraint_jacobian)
        b_rows.append(np.zeros((t.num_constraints, big_d)))
    return np.vstack(a_rows), np.vstack(b_rows)


def _null_space(m: NDArray[np.float64]) -> NDArray[np.float64]:
    """Orthonormal basis (columns) of the null space of ``m`` (rank by [`RANK_REL_TOL`][mjtvm.measures.kinematics.RANK_REL_TOL])."""
    if m.shape[0] == 0:
        return np.eye(m.shape[1])
    _, s, vt = np.linalg.svd(m)
    rank = int(np.sum(s > RANK_REL_TOL * s[0])) if s.size and s[0] > 0.0 else 0
    return vt[rank:].T


def manipulability(state: GraspState, torque_scale: float) -> tuple[float, bool]:
    r"""Yoshikawa's measure of the hand-object system and whether the kinematics determine
    the twist.

    The consistent motions are the null space of ``[A, -B]`` ([`contact_kinematics()`][mjtvm.measures.kinematics.contact_kinematics]).
    When ``B t = 0`` has only ``t = 0`` the twist is a linear function of the consistent
    joint speeds: ``t = K qd`` on the subspace ``Q`` they span (Li, Hsu & Sastry 1989: the
    hand Jacobian ``G^{+T} J`` restricted to ``Q``; Bicchi & Prattichizzo 2000). With ``K_Q``
    its matrix in an orthonormal basis of ``Q``, the unit ball of joint speeds in ``Q`` maps
    onto the ellipsoid ``{K_Q z : |z| <= 1}`` and the measure is its volume up to the unit
    ball's, $w = \sqrt{\det(K_Q K_Q^T)}$ (Yoshikawa 1985); 0 when ``dim Q < D`` or
    ``K_Q`` is rank deficient (some twist needs no or unbounded joint speed).

    Returns
    -------
    (w, determined)
        ``w`` in (m/s)^D per (rad/s)^D (scaled twists per joint speeds); 0 and ``False``
        when the object can move with the hand at rest (the twist is not determined).
    """
    a, b = contact_kinematics(state, torque_scale)
    m, big_d = state.num_joints, state.twist_dim
    if b.shape[0] == 0 or _null_space(b).shape[1] > 0:
        return 0.0, False
    basis = _null_space(np.hstack([a, -b]))
    nq, nt = basis[:m], basis[m:]
    if basis.shape[1] < big_d:
        return 0.0, True
    # Q = range(nq), nq injective here (nq z = 0 gives B t = 0, so t = 0, so z = 0).
    _, s, vt = np.linalg.svd(nq, full_matrices=False)
    k_q = nt @ vt.T / s  # t = nt z with nq z = u s vt z = qd: z = vt^T s^-1 (u^T qd)
    w = float(np.sqrt(max(0.0, np.linalg.det(k_q @ k_q.T))))
    return w, True


def speed_only_state(state: GraspState) -> GraspState:
    """``state`` with its statics made void: no REFS wrench, no gravity torque, no preload, no
    damping, and each operation range replaced by the box of its largest torque and speed, so
    that Problem 1's polytope is the set of twists of joint speeds within those speeds
    ([`kinematic_polytope()`][mjtvm.measures.kinematics.kinematic_polytope]). The contact forces may then all be 0, which leaves every
    torque at 0, where the (down-closed) ranges allow their largest speed."""
    boxes = tuple(OperationRange.box(r.max_torque, r.max_speed) for r in state.operation_ranges)
    t = state.transmission
    if t is not None and t.joint_damping is not None:
        t = Transmission(t.actuator_names, t.moment, t.constraint_names, t.constraint_jacobian, None)
    return state.with_(
        refs=np.zeros((1, state.twist_dim)),
        gravity_torque=np.zeros(state.num_joints),
        contacts=tuple(replace(c, preload=0.0) for c in state.contacts),
        operation_ranges=boxes,
        rvds=None,
        transmission=t,
    )


def kinematic_polytope(state: GraspState, torque_scale: float) -> tuple[float, int, NDArray[np.float64]]:
    """The kinematic velocity polytope: the twists reached with joint (actuator) speeds within
    each operation range's largest speed, ``|P qd| <= s_max`` and ``J_eq qd = 0`` with a
    transmission, under the contact kinematics of eq. (9)-(13) (D-points' ``<=`` included),
    forces ignored: Problem 1's TVMS of [`speed_only_state()`][mjtvm.measures.kinematics.speed_only_state] (exact projection by
    support LPs, `project_lp()`).

    Returns
    -------
    (volume, dimension, vertices)
        The volume of the scaled twists' hull ((m/s)^D; 0 below full dimension, ``inf``
        when unbounded: the object moves with the hand at rest, ``nan`` when the projection
        stopped at its memory budget), the dimension of the polytope (-1 when empty) and
        its ``(n, D)`` vertices in scaled twists.
    """
    proj = project_lp(lifted_polytope(speed_only_state(state), rvds_cone=False))
    big_d = state.twist_dim
    if proj.status == "unbounded":
        return float("inf"), big_d, np.zeros((0, big_d))
    if proj.status not in ("bounded", "approximate"):
        return 0.0, -1, np.zeros((0, big_d))
    verts = proj.vertices * _twist_scale(state, torque_scale)
    dim = int(proj.dimension) if proj.dimension is not None else -1
    if proj.status == "approximate":  # the memory budget stopped the exact projection
        return float("nan"), dim, verts
    vol = hull_volume(verts) if dim == big_d else 0.0
    return vol, dim, verts
