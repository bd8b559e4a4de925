r"""How a MuJoCo model drives and constrains a grasp state's joints: actuator moments,
equality-constraint rows, joint damping (the extended eq. 19).

At a configuration after ``mj_forward`` MuJoCo holds everything the extended torque balance
needs, over the state's joints (their dofs, in the state's order, ``M`` of them):

* ``actuator_moment`` (``A x nv``, sparse in MuJoCo >= 3.2: ``moment_rownnz``,
  ``moment_rowadr``, ``moment_colind``): actuator ``a``'s speed is ``s_a = moment[a] @ qd``
  (MuJoCo's ``actuator_velocity``) and its force ``u_a`` (``actuator_force``) gives the joint
  torques ``moment.T @ u``. The moment includes the actuator's ``gear`` and, for a tendon
  transmission, the tendon's coefficients (fixed tendon) or moment arms (spatial tendon), so
  ``u`` and ``s`` are in the actuator's own units (N m and rad/s for a hinge or a fixed tendon
  of hinges with coefficient 1; N and m/s for a slide).
* the equality constraints' rows of MuJoCo's constraint Jacobian ``efc_J`` (the rows with
  ``efc_type == mjCNSTR_EQUALITY``): a ``<joint>`` coupling gives one row ``e1 - p'(q2) e2``
  (``p`` its polynomial, linearised at the state), a ``<connect>`` three rows (the difference
  of the two bodies' point Jacobians at the anchor), a ``<weld>`` six, a ``<tendon>`` one.
  The kinematic constraint is ``J_eq qd = 0``; its forces ``J_eq^T lambda`` (``lambda`` free)
  enter the balance. Rows that are zero over the state's dofs are dropped (a connect whose
  linkage moves in a plane has one), as are equalities that touch none of them.
* ``dof_damping``: the passive torque ``-b qd`` of each joint (N m s/rad).

An actuator drives the hand when its moment is nonzero on a state joint. The joint springs
(``qfrc_spring``) are not part of the transmission: they are in the state's bias torque
(gravity plus passive springs at the state, `grasp_state()`).

[`is_independent()`][mjtvm.grasp.actuation.transmission.is_independent] says when none of this is needed: every driving actuator a joint
transmission on its own state joint, no equality, as in the paper (eq. 19 unchanged).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError
from mjtvm.grasp.contacts.touch import ROUND_OFF_REL, without_round_off

__all__ = [
    "CONSTRAINT_TOLERANCE",
    "ModelTransmission",
    "actuator_moments",
    "check_closed",
    "coupled_joints",
    "dense_efc_jacobian",
    "dense_moment",
    "equality_residual",
    "equality_rows",
    "is_independent",
    "model_transmission",
]

_OBJ = mujoco.mjtObj
_ROW_AXES = {
    int(mujoco.mjtEq.mjEQ_CONNECT): ("x", "y", "z"),
    int(mujoco.mjtEq.mjEQ_WELD): ("x", "y", "z", "rx", "ry", "rz"),
}


@dataclass(frozen=True, eq=False)
class ModelTransmission:
    r"""The transmission of a model over a state's joints (module docstring).

    Attributes
    ----------
    joint_names
        The state's joints, ``M`` of them, in order (the columns below).
    actuator_names, actuator_ids
        The ``A`` actuators with a nonzero moment on a state joint, in model order (an
        unnamed actuator is ``"actuator#<id>"``).
    moment
        ``(A, M)``: actuator speed ``s = moment @ qd``; joint torques ``moment.T @ u``.
    constraint_names
        One per row of ``constraint_jacobian``: the equality's name (``"equality#<id>"``
        when unnamed), with ``"/x"`` ... ``"/rz"`` for the rows of a connect or weld.
    constraint_jacobian
        ``(C, M)``: ``J_eq qd = 0``, ``C`` may be 0.
    constraint_residual
        ``(C,)`` MuJoCo's ``efc_pos`` of each row at the configuration (m or rad): how far the
        configuration is from satisfying the constraint (0 for a closed linkage).
    joint_damping
        ``(M,)`` N m s/rad (N s/m for a slide): MuJoCo's ``dof_damping``.
    """

    joint_names: tuple[str, ...]
    actuator_names: tuple[str, ...]
    actuator_ids: tuple[int, ...]
    moment: NDArray[np.float64]
    constraint_names: tuple[str, ...]
    constraint_jacobian: NDArray[np.float64]
    constraint_residual: NDArray[np.float64]
    joint_damping: NDArray[np.float64]

    def __post_init__(self) -> None:
        m = len(self.joint_names)
        a, c = len(self.actuator_names), len(self.constraint_names)
        if self.moment.shape != (a, m) or len(self.actuator_ids) != a:
            raise ModelError("moment", f"expected shape ({a}, {m}), got {self.moment.shape}")
        if self.constraint_jacobian.shape != (c, m):
            raise ModelError(
                "constraint_jacobian", f"expected shape ({c}, {m}), got {self.constraint_jacobian.shape}"
            )
        if self.constraint_residual.shape != (c,):
            raise ModelError(
                "constraint_residual", f"expected shape ({c},), got {self.constraint_residual.shape}"
            )
        if self.joint_damping.shape != (m,):
            raise ModelError("joint_damping", f"expected shape ({m},), got {self.joint_damping.shape}")
        for x in (self.moment, self.constraint_jacobian, self.constraint_residual, self.joint_damping):
            x.setflags(write=False)


def _name(model: mujoco.MjModel, kind: mujoco.mjtObj, i: int, what: str) -> str:
    return mujoco.mj_id2name(model, kind, i) or f"{what}#{i}"


def _outside(row: NDArray[np.float64], dofs: Sequence[int] | NDArray[np.int64]) -> list[int]:
    """Dofs outside ``dofs`` where ``row`` is not (relatively) zero."""
    scale = float(np.max(np.abs(row), initial=0.0))
    inside = set(int(d) for d in dofs)
    return [int(d) for d in np.flatnonzero(np.abs(row) > 1e-12 * scale) if int(d) not in inside]


def _dof_names(model: mujoco.MjModel, dofs: Sequence[int]) -> str:
    joints = sorted({int(model.dof_jntid[d]) for d in dofs})
    return ", ".join(repr(_name(model, _OBJ.mjOBJ_JOINT, j, "joint")) for j in joints)


def dense_moment(model: mujoco.MjModel, data: mujoco.MjData) -> NDArray[np.float64]:
    """``(nactuator, nv)`` MuJoCo's sparse ``actuator_moment`` as a dense matrix (``mju_sparse2dense``)."""
    dense = np.zeros((model.nactuator, model.nv))
    if model.nactuator:
        mujoco.mju_sparse2dense(
            dense, data.actuator_moment, data.moment_rownnz, data.moment_rowadr, data.moment_colind
        )
    return dense


def dense_efc_jacobian(model: mujoco.MjModel, data: mujoco.MjData) -> NDArray[np.float64]:
    """``(nefc, nv)`` the constraint Jacobian ``efc_J``, dense or sparse as ``mj_isSparse`` says."""
    nefc = int(data.nefc)
    if mujoco.mj_isSparse(model):
        efc = np.zeros((nefc, model.nv))
        if nefc:
            mujoco.mju_sparse2dense(efc, data.efc_J, data.efc_J_rownnz, data.efc_J_rowadr, data.efc_J_colind)
        return efc
    return np.array(data.efc_J[: nefc * model.nv]).reshape(nefc, model.nv)


def actuator_moments(
    model: mujoco.MjModel, data: mujoco.MjData, dofs: Sequence[int]
) -> tuple[list[int], NDArray[np.float64]]:
    r"""The actuators with a nonzero moment on ``dofs`` and their moment rows ``(A, len(dofs))``.

    ``data`` after ``mj_forward`` (or ``mj_transmission``). Dense ``(nactuator, nv)`` from MuJoCo's
    sparse ``actuator_moment`` with ``mju_sparse2dense``.

    Raises
    ------
    ModelError
        An actuator that drives a state joint and also a joint outside ``dofs`` (its force
        would move a joint the state holds still): the message names both.
    """
    # Round-off (a shared ancestor's ~1e-17 arm) is no moment: it must not pull joints in.
    dense = _rows_without_round_off(dense_moment(model, data))
    cols = np.asarray(dofs, dtype=int)
    ids = [int(a) for a in np.flatnonzero(np.any(dense[:, cols] != 0.0, axis=1))]
    outside = np.ones(model.nv, dtype=bool)
    outside[cols] = False
    # Every row's entries above 1e-12 of its largest, at once: a row per actuator in Python
    # was most of the transmission's time on the 22-joint Shadow hand.
    beyond = np.any(_significant(dense)[:, outside], axis=1)
    for a in ids:
        if beyond[a]:
            extra = _outside(dense[a], cols)
            raise ModelError(
                f"actuator {_name(model, _OBJ.mjOBJ_ACTUATOR, a, 'actuator')!r}",
                f"drives state joints and also {_dof_names(model, extra)}: add them to the state's joints",
            )
    return ids, _rows_without_round_off(
        dense[np.asarray(ids, dtype=int)][:, cols].reshape(len(ids), len(cols))
    )


def _significant(m: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Where each row of ``m`` exceeds 1e-12 of its largest magnitude (`_outside()`'s test, per row)."""
    magnitude = np.abs(m)
    return magnitude > 1e-12 * np.max(magnitude, axis=1, initial=0.0, keepdims=True)


def _rows_without_round_off(m: NDArray[np.float64]) -> NDArray[np.float64]:
    """[`without_round_off()`][mjtvm.grasp.contacts.touch.without_round_off] of each row of ``m`` (a copy)."""
    out = np.array(m, dtype=float)
    out[np.abs(out) <= ROUND_OFF_REL * np.max(np.abs(out), axis=1, initial=0.0, keepdims=True)] = 0.0
    return out


def equality_rows(
    model: mujoco.MjModel, data: mujoco.MjData, dofs: Sequence[int]
) -> tuple[list[str], NDArray[np.float64], NDArray[np.float64]]:
    r"""Names, rows ``(C, len(dofs))`` and residuals ``(C,)`` (``efc_pos``) of the active
    equality constraints on ``dofs``.

    The rows of ``efc_J`` with ``efc_type == mjCNSTR_EQUALITY`` (dense or sparse, as
    ``mj_isSparse`` says), restricted to ``dofs``; rows zero there are dropped.

    Raises
    ------
    ModelError
        An equality that constrains a state joint together with a dof outside ``dofs`` (e.g. a
        linkage joint missing from the joints list): the message names the constraint and the
        joints to add.
    """
    cols = np.asarray(dofs, dtype=int)
    nefc = int(data.nefc)
    if nefc == 0:
        return [], np.zeros((0, len(cols))), np.zeros(0)
    efc = dense_efc_jacobian(model, data)
    eq = np.flatnonzero(data.efc_type[:nefc] == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY))
    full = _rows_without_round_off(efc[eq])  # a shared ancestor's ~1e-17 column is no coupling
    touched = np.any(full[:, cols] != 0.0, axis=1)
    outside = np.ones(model.nv, dtype=bool)
    outside[cols] = False
    beyond = np.any(_significant(full)[:, outside], axis=1)
    names, rows, residuals = [], [], []
    seen: dict[int, int] = {}
    for i, r in enumerate(eq):
        e = int(data.efc_id[r])
        k = seen.get(e, 0)
        seen[e] = k + 1
        if not touched[i]:
            continue
        label = _name(model, _OBJ.mjOBJ_EQUALITY, e, "equality")
        if beyond[i]:
            raise ModelError(
                f"equality {label!r}",
                f"constrains state joints together with {_dof_names(model, _outside(full[i], cols))}: "
                "add them to the state's joints",
            )
        axes = _ROW_AXES.get(int(model.eq_type[e]))
        names.append(f"{label}/{axes[k]}" if axes else label)
        rows.append(i)
        residuals.append(float(data.efc_pos[r]))
    restricted = _rows_without_round_off(full[rows][:, cols].reshape(len(rows), len(cols)))
    kept = [int(i) for i in np.flatnonzero(np.any(restricted != 0.0, axis=1))]
    return [names[i] for i in kept], restricted[kept], np.array([residuals[i] for i in kept])


def model_transmission(
    model: mujoco.MjModel, data: mujoco.MjData, joint_ids: Sequence[int]
) -> ModelTransmission:
    r"""The transmission over the joints ``joint_ids`` (hinge or slide) at ``data``.

    ``data`` after ``mj_forward`` at the configuration (velocities do not matter: the moment
    and the constraint rows depend on positions only).

    Raises
    ------
    ModelError
        As [`actuator_moments()`][mjtvm.grasp.actuation.transmission.actuator_moments] and [`equality_rows()`][mjtvm.grasp.actuation.transmission.equality_rows].
    """
    dofs = [int(model.jnt_dofadr[j]) for j in joint_ids]
    ids, moment = actuator_moments(model, data, dofs)
    names, jac, residual = equality_rows(model, data, dofs)
    return ModelTransmission(
        joint_names=tuple(_name(model, _OBJ.mjOBJ_JOINT, j, "joint") for j in joint_ids),
        actuator_names=tuple(_name(model, _OBJ.mjOBJ_ACTUATOR, a, "actuator") for a in ids),
        actuator_ids=tuple(ids),
        moment=moment,
        constraint_names=tuple(names),
        constraint_jacobian=jac,
        constraint_residual=residual,
        joint_damping=np.array([float(model.dof_damping[d]) for d in dofs]),
    )


def is_independent(model: mujoco.MjModel, transmission: ModelTransmission, joint_ids: Sequence[int]) -> bool:
    r"""True when the paper's independent joints apply (eq. 19 as written): no equality row, and
    the driving actuators are joint transmissions on distinct state joints, one per joint at most.

    Then the state keeps one operation range per joint (``transmission=None``), read as today.
    """
    if transmission.constraint_names:
        return False
    driven: set[int] = set()
    for a in transmission.actuator_ids:
        if int(model.actuator_trntype[a]) != int(mujoco.mjtTrn.mjTRN_JOINT):
            return False
        j = int(model.actuator_trnid[a, 0])
        if j in driven or j not in set(joint_ids):
            return False
        driven.add(j)
    return True


def coupled_joints(model: mujoco.MjModel, data: mujoco.MjData, joint_ids: Sequence[int]) -> list[int]:
    r"""``joint_ids`` and, repeatedly, every hinge or slide joint an equality or a driving actuator
    ties to them (a linkage's other joints, the other joints of a tendon), in model order.

    A grasp file without a ``joints`` list starts from the joints that move its contacts; a
    linkage's driver and coupler move no contact but carry the motion. ``data`` after
    ``mj_forward``.
    """
    scalar = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    equality = int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    efc = dense_efc_jacobian(model, data)
    rows = _rows_without_round_off(
        np.vstack([dense_moment(model, data), efc[np.flatnonzero(data.efc_type[: len(efc)] == equality)]])
    )
    # Each row's dofs, once: the growth below revisits every row on each pass.
    touched = [{int(d) for d in np.flatnonzero(row)} for row in rows]
    chosen = {int(j) for j in joint_ids}
    grown = True
    while grown:
        grown = False
        dofs = {int(model.jnt_dofadr[j]) for j in chosen}
        for nz in touched:
            if not nz & dofs:
                continue
            for d in nz - dofs:
                j = int(model.dof_jntid[d])
                if int(model.jnt_type[j]) in scalar and j not in chosen:
                    chosen.add(j)
                    grown = True
    return sorted(chosen)


#: m or rad: an equality constraint's residual (``efc_pos``) allowed in a grasp state.
CONSTRAINT_TOLERANCE = 1e-6


def check_closed(transmission: ModelTransmission, tolerance: float = CONSTRAINT_TOLERANCE) -> None:
    """Every equality row of ``transmission`` holds at its configuration within ``tolerance``.

    Raises
    ------
    ModelError
        Naming the first violated equality and its residual: the state's constraint rows are
        linearised about a configuration that must satisfy them.
    """
    for name, residual in zip(transmission.constraint_names, transmission.constraint_residual, strict=True):
        if abs(residual) > tolerance:
            raise ModelError(
                f"equality {name.split('/')[0]!r}",
                f"is violated by {abs(residual):.3g} (m or rad) at the configuration (tolerance "
                f"{tolerance:g}): give joint values that close it",
            )


def equality_residual(
    model: mujoco.MjModel, data: mujoco.MjData, dofs: Sequence[int] | NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""``(R,)`` residuals (``efc_pos``) and ``(R, len(dofs))`` Jacobian rows of the active
    equality constraints that involve ``dofs``, for an IK that keeps them closed.

    Runs ``mj_fwdPosition`` on ``data`` (the constraint rows need it).
    """
    mujoco.mj_fwdPosition(model, data)
    cols = np.asarray(dofs, dtype=int)
    efc = dense_efc_jacobian(model, data)
    equality = int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    rows = [
        r
        for r in range(int(data.nefc))
        if int(data.efc_type[r]) == equality and np.any(without_round_off(efc[r])[cols] != 0.0)
    ]
    return np.array([float(data.efc_pos[r]) for r in rows]), efc[rows][:, cols].reshape(len(rows), len(cols))
