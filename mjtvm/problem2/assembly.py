r"""Sparse assembly of the TVM constraint system, shared by Problems 1 and 2.

One [`Assembly`][mjtvm.problem2.assembly.Assembly] holds, for one grasp state, every linear constraint of eq. (26)
(eq. 34 with S-points) except the object twist, whose coefficients are kept apart in
``A_twist`` so that Problem 2 can collapse the twist into ``alpha * r_l`` (eq. 31) and
Problem 1 can keep it as D free variables. The rows are

* statics, per REFS copy i (eq. 19-20, 25):
  ``G E lam_i = -w_i`` (D rows) and ``tau_i - J^T E lam_i = g_f`` (M rows), where
  the columns of ``E`` are the force generators of `force_generators()`
  and ``lam_i >= 0`` (eq. 24; D-points carry no force);
* kinematics (eq. 11-13): ``H (J qd - G^T rdot) [+ rho T s] = 0`` for F (d rows), L and
  S normal (1 row), S tangential (d - 1 rows); ``<= 0`` for D (eq. 12);
* operation ranges (eq. 2-3): either the exact reduction
  ``c_tau tau_ij + c_qd qd_j <= b`` (`OperationRange.mirrored_halfplanes`), or
  the paper's literal box with four variables per joint;
* preloads, per copy and per contact with ``preload > 0`` (last, so that a state without
  preloads has exactly the paper's system): ``n^T E_c lam_ic >= preload``, the contact's
  normal force bounded below instead of eq. (22)'s ``n_f >= 0``;
* joint position limits (`limits`; after every other row, so that a state
  without ``joint_limits`` has exactly the paper's system): ``qd_j <= 0`` for a joint on its
  upper limit, ``qd_j >= 0`` on its lower; with ``horizon=True`` (Problem 2) also
  ``sign qd_j - rate s alpha <= 0`` per limited side, whose ``alpha`` coefficient the caller
  puts in with ``alpha`` (`Assembly.horizon_column()`).

This module lays out the variables and writes the statics and kinematic rows; the bound rows
after them (operation ranges, preloads, damping losses, joint limits) are
``mjtvm.problem2.range_rows``'.

Variables, in order: ``lam_1, tau_1, ..., lam_K, tau_K, qd, rho[, loss][, tau_max, tau_min,
qd_max, qd_min]``, then the twist (or ``alpha``) appended by the caller.

With a [`Transmission`][mjtvm.model.transmission.Transmission] ``tau_i`` holds the A actuator
forces ``u_i`` and is followed by the C constraint forces ``eq_i`` (free); the torque rows
read ``P^T u_i - J^T E lam_i + J_eq^T eq_i = g_f``, the operation ranges bound
``(u_ia, P_a qd)``, and the C rows ``J_eq qd = 0`` come last. Without one every block is
built as above (``P = I``), entry for entry.

Joint damping ``b`` is a loss, never a torque source (``docs/state-format.md``, "Damping"):
it is not in the balance, where a finger moving along a motion its actuators do not drive
would "make" torque (``b qd``) to hold the object. Each actuator a instead pays
``loss_a >= b_j |qd_j| / |P_aj|`` for every joint j it moves (a variable per actuator, after
``rho``), and its operation range bounds ``(|u_ia| + loss_a, |P_a qd|)``: the rows
``c_tau u_ia + |c_tau| loss_a + c_qd P_a qd <= b``, which are
``a_tau (|u| + loss) + a_qd |s| <= b`` (`OperationRange.mirrored_halfplanes`). The
motor's torque is its holding torque plus what overcomes the damping, whatever their signs,
so that more damping can only shrink the feasible set; a state without damping has no
``loss`` block and is assembled exactly as before.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from itertools import pairwise
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError
from mjtvm.lp.csc import Csc
from mjtvm.lp.roundoff import cancelling_product, drop_cancellation, drop_data_roundoff, jacobian_scale
from mjtvm.lp.rows import Rows as _Rows
from mjtvm.model.contacts import force_generators, slide_unit, tangent_basis
from mjtvm.model.friction import margin_contacts
from mjtvm.model.limits import travel_speed
from mjtvm.model.state import GraspState
from mjtvm.problem2.range_rows import (
    damping_loss,
    joint_limit_rows,
    loss_rows,
    preload_rows,
    range_rows_eliminated,
    range_rows_literal,
)

if TYPE_CHECKING:
    import scipy.sparse as sp

__all__ = ["Assembly", "BoxForm", "assemble", "damping_loss", "grasp_map_transpose"]

BoxForm = Literal["eliminated", "literal"]


def grasp_map_transpose(
    position: NDArray[np.float64], object_position: NDArray[np.float64]
) -> NDArray[np.float64]:
    r"""``(d, D)`` $G_{ij}^T$: velocity of the object point at ``position`` (eq. 6).

    In space $G^T = [I, -[r\times]]$ with $r = p_C - p_O$, so
    $G^T \dot r = v + \omega \times r$; in the plane
    $G^T \dot r = [v_x - \omega r_y, v_y + \omega r_x]$. The round-off of ``r``
    ([`roundoff`][mjtvm.lp.roundoff]: of the difference, then of the vector) is 0.
    """
    p_c, p_o = np.asarray(position, dtype=float), np.asarray(object_position, dtype=float)
    r = drop_data_roundoff(drop_cancellation(p_c - p_o, np.abs(p_c) + np.abs(p_o)))
    if r.shape[0] == 2:
        return np.array([[1.0, 0.0, -r[1]], [0.0, 1.0, r[0]]])
    skew = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    return np.hstack([np.eye(3), -skew])


@dataclass(frozen=True, eq=False)
class Assembly:
    r"""The constraint system ``row_lower <= A x + A_twist rdot <= row_upper`` of one state.

    Attributes
    ----------
    csc
        ``(m, n)`` the matrix ``A`` over the variables listed in the module docstring
        ([`Csc`][mjtvm.lp.csc.Csc]; `A` is the same as a scipy matrix).
    twist_csc
        ``(m, D)`` the coefficients of the object twist ``rdot`` (`A_twist` as scipy's).
    row_lower, row_upper
        ``(m,)`` row bounds; the statics rows of copy i hold ``-w`` once
        `statics_bounds()` is applied.
    col_lower, col_upper
        ``(n,)`` variable bounds.
    blocks
        Name -> ``slice`` of variables: ``lam[i]``, ``tau[i]`` (and ``eq[i]`` with
        constraints) per copy, ``qd``, ``rho``, ``loss`` (per actuator, with joint damping only) and, in the
        literal form, ``tau_max``, ``tau_min``, ``qd_max``, ``qd_min`` (per actuator).
    wrench_rows
        One ``slice`` of D rows per copy: the force-moment balance (eq. 20).
    torque_rows
        One ``slice`` of M rows per copy: ``tau_i - J^T E lam_i = g_f`` (eq. 19), row j
        the only statics row of ``tau_i[j]``.
    generators
        Per contact, its ``(d, g)`` force generators (``E`` restricted to it).
    generator_slices
        Per contact, the slice of its generators inside ``lam[i]``.
    kinematic_rows
        The rows whose ``A_twist`` coefficients are non-zero (eq. 11-13).
    row_groups
        ``(m,)`` one id per vector whose components the rows are (a copy's force balance,
        its moment balance, a contact's relative velocity); every other row its own id.
        A certificate measures a row's violation against its vector's size, as a rotation
        of the frame mixes the components ([`certificate`][mjtvm.lp.certificate]).
    limit_rows
        The rows ``qd_j <= 0`` / ``qd_j >= 0`` of the joints on a position limit
        (`limits`).
    horizon_rows, horizon_rates
        The travel-horizon rows ``sign qd_j - rate_j s(r) alpha <= 0`` (assembled with
        ``horizon=True``) and their ``rate_j = slack_j / H`` (rad or m per m of travel):
        the ``alpha`` coefficient of the row is ``-rate_j`` times the travel speed of ``r``
        (`horizon_column()`).
    """

    csc: Csc
    twist_csc: Csc
    row_lower: NDArray[np.float64]
    row_upper: NDArray[np.float64]
    col_lower: NDArray[np.float64]
    col_upper: NDArray[np.float64]
    blocks: dict[str, slice]
    wrench_rows: tuple[slice, ...]
    torque_rows: tuple[slice, ...]
    generators: tuple[NDArray[np.float64], ...]
    generator_slices: tuple[slice, ...]
    kinematic_rows: NDArray[np.int64]
    row_groups: NDArray[np.int64]
    copies: int
    box: BoxForm
    limit_rows: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    horizon_rows: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    horizon_rates: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))

    @property
    def num_variables(self) -> int:
        """n, the number of variables before the twist."""
        return int(self.csc.shape[1])

    @cached_property
    def A(self) -> sp.csc_matrix:
        """``(m, n)`` the constraint matrix as a scipy sparse matrix (`csc`'s arrays)."""
        return self.csc.to_scipy()

    @cached_property
    def A_twist(self) -> sp.csc_matrix:
        """``(m, D)`` the twist's coefficients as a scipy sparse matrix (`twist_csc`'s arrays)."""
        return self.twist_csc.to_scipy()

    def statics_bounds(
        self, wrenches: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Row bounds with ``-wrenches[i]`` on the balance rows of copy i (eq. 20)."""
        lower, upper = self.row_lower.copy(), self.row_upper.copy()
        for rows, w in zip(self.wrench_rows, np.atleast_2d(wrenches)):
            lower[rows] = -w
            upper[rows] = -w
        return lower, upper

    def horizon_column(self, state: GraspState, r: NDArray[np.float64]) -> NDArray[np.float64]:
        r"""``(len(horizon_rows),)`` the coefficients of ``alpha`` on the horizon rows when
        ``rdot = alpha r`` (eq. 31): ``-rate_j s(r)`` ([`travel_speed()`][mjtvm.model.limits.travel_speed]);
        on every other row alpha's coefficient is ``A_twist r``."""
        return -self.horizon_rates * travel_speed(state, r)

    def forces(self, x: NDArray[np.float64], copy: int = 0) -> NDArray[np.float64]:
        """``(L, d)`` contact forces on the object, from a solution vector ``x``."""
        lam = x[self.blocks[f"lam[{copy}]"]]
        return np.array([g @ lam[s] for g, s in zip(self.generators, self.generator_slices)])


def _variables(
    state: GraspState, copies: int, box: BoxForm, n_gen: int, n_rho: int
) -> tuple[dict[str, slice], NDArray[np.float64], NDArray[np.float64]]:
    """The variable layout (module docstring) and the sign constraints on it: ``lam >= 0``
    (eq. 22, 24 in generator form), ``rho >= 0`` (eq. 13, 34), ``loss >= 0`` and, in the literal box,
    ``tau_max, qd_max >= 0 >= tau_min, qd_min`` (appendix A)."""
    m, a = state.num_joints, len(state.operation_ranges)
    n_eq = 0 if state.transmission is None else state.transmission.num_constraints
    blocks: dict[str, slice] = {}
    col = 0

    def take(name: str, size: int) -> None:
        nonlocal col
        blocks[name] = slice(col, col + size)
        col += size

    for i in range(copies):
        take(f"lam[{i}]", n_gen)
        take(f"tau[{i}]", a)
        if n_eq:
            take(f"eq[{i}]", n_eq)
    take("qd", m)
    take("rho", n_rho)
    if damping_loss(state) is not None:
        take("loss", a)
    if box == "literal":
        for name in ("tau_max", "tau_min", "qd_max", "qd_min"):
            take(name, a)
    col_lower = np.full(col, -np.inf)
    col_upper = np.full(col, np.inf)
    for i in range(copies):
        col_lower[blocks[f"lam[{i}]"]] = 0.0
    col_lower[blocks["rho"]] = 0.0
    if "loss" in blocks:
        col_lower[blocks["loss"]] = 0.0
    if box == "literal":
        col_lower[blocks["tau_max"]] = 0.0
        col_lower[blocks["qd_max"]] = 0.0
        col_upper[blocks["tau_min"]] = 0.0
        col_upper[blocks["qd_min"]] = 0.0
    return blocks, col_lower, col_upper


def _statics_rows(
    out: _Rows,
    state: GraspState,
    gens: tuple[NDArray[np.float64], ...],
    gt: list[NDArray[np.float64]],
    jacobians: list[NDArray[np.float64]],
    blocks: dict[str, slice],
    copies: int,
) -> tuple[list[slice], list[slice]]:
    """Per copy i, the statics with ``f = E lam_i`` (eq. 19-20): ``G E lam_i = -w_i`` (D
    rows, bounds set later by [`Assembly.statics_bounds()`][mjtvm.problem2.assembly.Assembly.statics_bounds]) and
    ``tau_i - J^T E lam_i = g_f`` (M rows). Returns the slices of the balance rows and of
    the torque rows."""
    contacts, big_d, m = state.contacts, state.twist_dim, state.num_joints
    wrench_map = (
        np.hstack([cancelling_product(gt[i].T, gens[i]) for i in range(len(contacts))])
        if contacts
        else np.zeros((big_d, 0))
    )
    torque_map = (
        np.hstack([cancelling_product(j.T, g) for j, g in zip(jacobians, gens)])
        if contacts
        else np.zeros((m, 0))
    )
    wrench_rows, torque_rows = [], []
    d = state.dim
    for i in range(copies):
        r0 = out.add(0.0, 0.0, d, vector=True)  # the force, then the moment (one vector each)
        out.add(0.0, 0.0, big_d - d, vector=True)
        wrench_rows.append(slice(r0, r0 + big_d))
        out.coo.add(r0, blocks[f"lam[{i}]"].start, wrench_map)
        r0 = out.add(state.gravity_torque, state.gravity_torque, m)
        torque_rows.append(slice(r0, r0 + m))
        t = state.transmission
        out.coo.add(r0, blocks[f"tau[{i}]"].start, np.eye(m) if t is None else t.moment.T)
        out.coo.add(r0, blocks[f"lam[{i}]"].start, -torque_map)
        if t is not None and t.constraint_jacobian is not None:
            out.coo.add(r0, blocks[f"eq[{i}]"].start, t.constraint_jacobian.T)
    return wrench_rows, torque_rows


def _kinematic_rows(
    out: _Rows,
    state: GraspState,
    gt: list[NDArray[np.float64]],
    jacobians: list[NDArray[np.float64]],
    blocks: dict[str, slice],
) -> NDArray[np.int64]:
    """The contact kinematics (eq. 9-13): ``H (J qd - G^T rdot) [+ rho T s] (=, <=) 0`` --
    all d directions for F, the normal for L and S (``<= 0`` for D, eq. 12), and for S the
    tangential slip ``T (J qd - G^T rdot) = -rho T s`` (eq. 13; one shared ``rho`` whose
    slide vectors' lengths set the ratios, or one per S-point). Returns their row indices."""
    d, contacts = state.dim, state.contacts
    s_contacts = [i for i, c in enumerate(contacts) if c.type == "S"]
    kin_start = out.count
    qd0, rho0 = blocks["qd"].start, blocks["rho"].start
    for ci, c in enumerate(contacts):
        if c.type == "F":
            sel = np.eye(d)
        else:
            sel = c.normal.reshape(1, -1)
        r0 = out.add(-np.inf if c.type == "D" else 0.0, 0.0, sel.shape[0], vector=True)
        out.coo.add(r0, qd0, cancelling_product(sel, jacobians[ci]))
        out.twist.add(r0, 0, -cancelling_product(sel, gt[ci]))
        if c.type == "S":
            tb = tangent_basis(c.normal)
            r0 = out.add(0.0, 0.0, d - 1, join=True)  # the same relative velocity
            out.coo.add(r0, qd0, cancelling_product(tb, jacobians[ci]))
            out.twist.add(r0, 0, -cancelling_product(tb, gt[ci]))
            k = s_contacts.index(ci)
            if state.slip == "shared":
                s = c.slide_direction - (c.slide_direction @ c.normal) * c.normal  # type: ignore[operator]
                out.coo.add(r0, rho0, cancelling_product(tb, s).reshape(-1, 1))
            else:
                out.coo.add(r0, rho0 + k, cancelling_product(tb, slide_unit(c)).reshape(-1, 1))
    return np.arange(kin_start, out.count)


def assemble(
    state: GraspState, *, copies: int = 1, box: BoxForm = "eliminated", horizon: bool = False
) -> Assembly:
    r"""Build the sparse constraint system of ``state`` (see the module docstring).

    Parameters
    ----------
    state
        The grasp state.
    copies
        Number of statics copies (one per REFS vertex balanced at once): 1 for
        Problem 2 (eq. 31), K for Problem 1 (eq. 26).
    box
        ``"eliminated"`` (exact reduction, default) or ``"literal"`` (eq. 2's box).
    horizon
        Also the travel-horizon rows of the joint limits (Problem 2, whose ``alpha`` they
        need: `Assembly.horizon_column()`); Problem 1 takes the on-limit rows only
        (`limits`).

    Returns
    -------
    Assembly
    """
    if box not in ("eliminated", "literal"):
        raise ParamError("box", f"expected 'eliminated' or 'literal', got {box!r}", box)
    contacts = state.contacts
    # F pyramids at (1 - friction_margin) mu (mjtvm.model.friction); the contacts as they are at 0.
    gens = tuple(force_generators(c, state.friction_edges) for c in margin_contacts(state))
    offsets = np.cumsum([0] + [g.shape[1] for g in gens])
    gen_slices = tuple(slice(int(a), int(b)) for a, b in pairwise(offsets))
    n_s = sum(c.type == "S" for c in contacts)
    n_rho = (1 if n_s else 0) if state.slip == "shared" else n_s
    blocks, col_lower, col_upper = _variables(state, copies, box, int(offsets[-1]), n_rho)
    gt = [grasp_map_transpose(c.position, state.object_position) for c in contacts]
    # The round-off of the Jacobians is relative to their scale, the largest entry of them
    # all unless it stands alone far above the others (roundoff.jacobian_scale).
    jac_max = jacobian_scale([c.jacobian for c in contacts])
    jacobians = [drop_data_roundoff(c.jacobian, jac_max) for c in contacts]
    out = _Rows()
    wrench_rows, torque_rows = _statics_rows(out, state, gens, gt, jacobians, blocks, copies)
    kinematic_rows = _kinematic_rows(out, state, gt, jacobians, blocks)
    if box == "eliminated":
        range_rows_eliminated(out, state, blocks, copies)
    else:
        range_rows_literal(out, state, blocks, copies)
    preload_rows(out, state, gens, gen_slices, blocks, copies)
    loss_rows(out, state, blocks)
    t = state.transmission
    if t is not None and t.constraint_jacobian is not None:  # J_eq qd = 0
        r0 = out.add(0.0, 0.0, t.num_constraints)
        out.coo.add(r0, blocks["qd"].start, t.constraint_jacobian)
    limit_rows, horizon_rows, horizon_rates = joint_limit_rows(out, state, blocks, horizon)
    return Assembly(
        csc=out.coo.build((out.count, len(col_lower))),
        twist_csc=out.twist.build((out.count, state.twist_dim)),
        row_lower=np.concatenate(out.lower),
        row_upper=np.concatenate(out.upper),
        col_lower=col_lower,
        col_upper=col_upper,
        blocks=blocks,
        wrench_rows=tuple(wrench_rows),
        torque_rows=tuple(torque_rows),
        generators=gens,
        generator_slices=gen_slices,
        kinematic_rows=kinematic_rows,
        row_groups=np.concatenate(out.groups),
        copies=copies,
        box=box,
        limit_rows=limit_rows,
        horizon_rows=horizon_rows,
        horizon_rates=horizon_rates,
    )
