r"""The bound rows of the assembly: operation ranges, damping losses, preloads, joint limits.

[`assemble()`][mjtvm.problem2.assembly.assemble] lays out the variables and writes the statics and
kinematic rows (``mjtvm.problem2.assembly``); the rows here bound them, in the order the
assembly's module docstring lists: the operation ranges (eq. 1-3, in the exact reduction or
the paper's literal box), the preloads, the damping losses and, last, the joint position
limits (``mjtvm.model.limits``). Each function appends its rows to a
[`Rows`][mjtvm.lp.rows.Rows] builder; ``blocks`` maps the assembly's variable blocks to
their column slices.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.roundoff import cancelling_product
from mjtvm.lp.rows import Rows
from mjtvm.model.state import GraspState

__all__ = [
    "damping_loss",
    "joint_limit_rows",
    "loss_rows",
    "preload_rows",
    "range_rows_eliminated",
    "range_rows_literal",
]


def range_rows_eliminated(out: Rows, state: GraspState, blocks: dict[str, slice], copies: int) -> None:
    """The operation ranges (eq. 1-3) by the exact reduction: per copy i, row h of joint j
    is ``c_tau tau_ij + c_qd qd_j <= b`` (`OperationRange.mirrored_halfplanes`), with
    ``|c_tau| loss_j`` on the left under joint damping (module docstring)."""
    qd0 = blocks["qd"].start
    hps = [op.mirrored_halfplanes for op in state.operation_ranges]
    joint_of_row = np.repeat(np.arange(len(hps)), [len(hp) for hp in hps])
    hp_all = np.vstack(hps)
    t = state.transmission
    for i in range(copies):
        r0 = out.add(-np.inf, hp_all[:, 2], len(hp_all))
        row_idx = r0 + np.arange(len(hp_all))
        out.coo.add_entries(row_idx, blocks[f"tau[{i}]"].start + joint_of_row, hp_all[:, 0])
        if t is None:
            out.coo.add_entries(row_idx, qd0 + joint_of_row, hp_all[:, 1])
        else:  # the actuator's speed P_a qd
            out.coo.add(r0, qd0, hp_all[:, 1:2] * t.moment[joint_of_row])
        if "loss" in blocks:  # a_tau (|u| + loss) + a_qd |s| <= b
            out.coo.add_entries(row_idx, blocks["loss"].start + joint_of_row, np.abs(hp_all[:, 0]))


def range_rows_literal(out: Rows, state: GraspState, blocks: dict[str, slice], copies: int) -> None:
    """The paper's literal box (eq. 2) with four variables per joint:
    ``tau_min <= tau_i <= tau_max``, ``qd_min <= qd <= qd_max``, and the operation range's
    half-planes (eq. 3) at the box's four corners, in their mirrored copies. Under joint
    damping the torque's box holds ``tau_i +- loss`` (module docstring)."""
    qd0 = blocks["qd"].start
    for j, op in enumerate(state.operation_ranges):
        tmax, tmin = blocks["tau_max"].start + j, blocks["tau_min"].start + j
        qmax, qmin = blocks["qd_max"].start + j, blocks["qd_min"].start + j
        for i in range(copies):
            tau = blocks[f"tau[{i}]"].start + j
            r0 = out.add(-np.inf, 0.0, 2)
            out.coo.add(r0, tau, np.array([[1.0], [-1.0]]))
            out.coo.add(r0, tmax, np.array([[-1.0], [0.0]]))
            out.coo.add(r0, tmin, np.array([[0.0], [1.0]]))
            if "loss" in blocks:
                out.coo.add(r0, blocks["loss"].start + j, np.array([[1.0], [1.0]]))
        r0 = out.add(-np.inf, 0.0, 2)
        if state.transmission is None:
            out.coo.add(r0, qd0 + j, np.array([[1.0], [-1.0]]))
        else:  # the actuator's speed P_a qd
            out.coo.add(r0, qd0, np.outer([1.0, -1.0], state.transmission.moment[j]))
        out.coo.add(r0, qmax, np.array([[-1.0], [0.0]]))
        out.coo.add(r0, qmin, np.array([[0.0], [1.0]]))
        for a_t, a_q, b in op.halfplanes:
            for t_col, st in ((tmax, 1.0), (tmin, -1.0)):
                for q_col, sq in ((qmax, 1.0), (qmin, -1.0)):
                    r0 = out.add(-np.inf, b, 1)
                    out.coo.add(r0, t_col, np.array([[st * a_t]]))
                    out.coo.add(r0, q_col, np.array([[sq * a_q]]))


def damping_loss(state: GraspState) -> NDArray[np.float64] | None:
    r"""``(A, M)`` the loss coefficients ``b_j / |P_aj|`` of joint damping (0 where actuator a
    does not move joint j), or ``None`` without damping: actuator a pays
    ``loss_a >= max_j (b_j / |P_aj|) |qd_j|`` (module docstring). Its force ``P_aj loss_a`` on
    joint j then overcomes that joint's damping torque ``b_j |qd_j|``; exact for an actuator
    on one joint, an upper bound for a tendon over several (each joint charged in full). A
    joint no actuator moves has no motor to pay its damping: not modelled
    (``docs/state-format.md``)."""
    t = state.transmission
    if t is None or t.joint_damping is None:
        return None
    arm = np.abs(t.moment)
    with np.errstate(divide="ignore"):
        return np.where(arm > 0.0, t.joint_damping / np.where(arm > 0.0, arm, 1.0), 0.0)


def loss_rows(out: Rows, state: GraspState, blocks: dict[str, slice]) -> None:
    """``+- (b_j / |P_aj|) qd_j - loss_a <= 0`` for every actuator a and damped joint j it
    moves ([`damping_loss()`][mjtvm.problem2.range_rows.damping_loss])."""
    coef = damping_loss(state)
    if coef is None:
        return
    a_idx, j_idx = np.nonzero(coef)
    values = coef[a_idx, j_idx]
    for sign in (1.0, -1.0):
        r0 = out.add(-np.inf, 0.0, len(values))
        rows = r0 + np.arange(len(values))
        out.coo.add_entries(rows, blocks["qd"].start + j_idx, sign * values)
        out.coo.add_entries(rows, blocks["loss"].start + a_idx, -np.ones(len(values)))


def preload_rows(
    out: Rows,
    state: GraspState,
    gens: tuple[NDArray[np.float64], ...],
    gen_slices: tuple[slice, ...],
    blocks: dict[str, slice],
    copies: int,
) -> None:
    """Per copy i and per contact c with a preload: ``n_c^T E_c lam_ic >= preload_c`` (the
    normal force of eq. 22 bounded below by the contact's preload, N)."""
    for ci, c in enumerate(state.contacts):
        if c.preload <= 0.0 or gens[ci].shape[1] == 0:
            continue
        row = cancelling_product(c.normal.reshape(1, -1), gens[ci])
        for i in range(copies):
            r0 = out.add(c.preload, np.inf, 1)
            out.coo.add(r0, blocks[f"lam[{i}]"].start + gen_slices[ci].start, row)


def joint_limit_rows(
    out: Rows, state: GraspState, blocks: dict[str, slice], horizon: bool
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """The position-limit rows (`limits`): ``qd_j <= 0`` per joint on its
    upper limit, then ``qd_j >= 0`` per joint on its lower; with ``horizon`` the horizon
    rows ``sign qd_j <= rate_j s alpha`` (bounds ``(-inf, 0]``, their ``alpha`` coefficient
    the caller's). Returns the limit rows, the horizon rows and their rates."""
    empty = np.zeros(0, dtype=np.int64)
    lim = state.joint_limits
    if lim is None:
        return empty, empty, np.zeros(0)
    qd0 = blocks["qd"].start
    start = out.count
    for joints, lo, hi in (
        (np.flatnonzero(lim.at_upper), -np.inf, 0.0),
        (np.flatnonzero(lim.at_lower), 0.0, np.inf),
    ):
        if len(joints):
            r0 = out.add(lo, hi, len(joints))
            out.coo.add_entries(r0 + np.arange(len(joints)), qd0 + joints, np.ones(len(joints)))
    limit_rows = np.arange(start, out.count)
    joints, sign, rate = lim.horizon_sides() if horizon else (empty, np.zeros(0), np.zeros(0))
    if not len(joints):
        return limit_rows, empty, np.zeros(0)
    r0 = out.add(-np.inf, 0.0, len(joints))
    out.coo.add_entries(r0 + np.arange(len(joints)), qd0 + joints, sign)
    return limit_rows, r0 + np.arange(len(joints)), rate
