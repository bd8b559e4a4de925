r"""Witnesses to drive in a rollout: the motion and forces attaining alpha_kl (Supplement 1).

The simplex witness of [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp] sits at a vertex of the feasible set
(redundant joints at their speed limits, friction on the pyramid's edges); a rollout drives a
more central one: the same constraints (eq. 31, assembled by `assemble()`)
at a given alpha, with the least joint motion and the forces inside the pyramids.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import clarabel
import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from mjtvm.errors import ParamError, SolverError
from mjtvm.model.state import GraspState
from mjtvm.model.transmission import joint_speed_limits
from mjtvm.problem2.assembly import Assembly, assemble

__all__ = ["Drive", "WitnessKind", "WitnessProblem", "alpha_column", "central_witness", "witness_drive"]

WitnessKind = Literal["central", "vertex"]
_F64 = NDArray[np.float64]


def central_witness(
    state: GraspState, k: int, l: int, alpha: float, *, assembly: Assembly | None = None
) -> dict[str, _F64]:
    r"""The least-motion, force-centred solution of eq. (31) at a fixed ``alpha`` (Clarabel QP).

    Minimises $\sum_j (\dot q_j/\omega_{0j})^2 + \sum_e (\lambda_e/|w_k|)^2$ over the
    constraints of Problem 2 (`assemble()` with ``horizon=True``: the
    joint limits' on-limit and travel-horizon rows, `limits`) with
    $\dot r = \alpha \hat r_l$;
    returns ``speeds``, ``torques``, ``forces`` and ``slip_speeds`` (and ``actuator_speeds``
    ``P qd`` with a transmission). With a transmission the ranges bound actuators and
    $\omega_{0j}$ is joint j's fastest speed through them
    ([`joint_speed_limits()`][mjtvm.model.transmission.joint_speed_limits]): the weight stays per joint speed;
    ``torques`` are then the actuator forces ``u``. ``assembly``: ``assemble(state,
    horizon=True)`` when already built (it depends on the state alone; read, not changed).

    Raises
    ------
    SolverError
        The QP is not solved (e.g. ``alpha`` above $\alpha_{kl}$).
    """
    if state.rvds is None:
        raise ParamError("state", "the state has no RVDS (state.rvds is None)")
    return WitnessProblem(state, k, assembly=assembly).solve(l, alpha)


def alpha_column(state: GraspState, asm: Assembly, l: int) -> _F64:
    """``(rows of asm.A,)`` alpha's column of direction ``l``: ``A_twist r_l``, and
    ``-rate_j s(r)`` on the travel-horizon rows, as in Problem 2: at a fixed alpha they bound
    qd, so that the driven witness, like the LP's, reaches no joint limit within the horizon's
    travel.

    Raises
    ------
    ParamError
        The state has no RVDS.
    """
    if state.rvds is None:
        raise ParamError("state", "the state has no RVDS (state.rvds is None)")
    r = np.asarray(state.rvds[l], dtype=np.float64)
    col = np.asarray(asm.A_twist @ r, dtype=float).reshape(-1)
    col[asm.horizon_rows] = asm.horizon_column(state, r)
    return col


class WitnessProblem:
    r"""The QP of [`central_witness()`][mjtvm.physics.witness.central_witness] for one state and
    reference wrench ``k``, assembled once for every direction ``l`` and ``alpha``.

    Only alpha's column (``A_twist r_l`` and the horizon rows' coefficients) and alpha's fixed
    value depend on the direction and the speed: the rows of ``A``, their split into
    equalities and inequalities (from the bounds at ``w_k``), the objective and the cones are
    kept, and `solve()` appends the column to the kept matrix. The data Clarabel gets are
    those of a fresh assembly entry for entry (same CSC arrays, same order), so the witness is
    the same to the bit.

    Parameters
    ----------
    state
        The grasp state (with ``rvds``).
    k
        The reference wrench's index in ``state.refs``.
    assembly
        ``assemble(state, horizon=True)`` when already built (read, not changed).
    """

    def __init__(self, state: GraspState, k: int, *, assembly: Assembly | None = None) -> None:
        if state.rvds is None:
            raise ParamError("state", "the state has no RVDS (state.rvds is None)")
        self.state, self.k = state, k
        asm = self.asm = assemble(state, horizon=True) if assembly is None else assembly
        w = state.refs[k]
        n = self.n = asm.num_variables
        lo, hi = asm.statics_bounds(w)
        eq = np.isfinite(lo) & (lo == hi)
        up, dn = np.isfinite(hi) & ~eq, np.isfinite(lo) & ~eq
        cl, cu = asm.col_lower, asm.col_upper
        ceq = cl == cu
        cup, cdn = np.isfinite(cu) & ~ceq, np.isfinite(cl) & ~ceq
        a = asm.A.tocsr()
        eye = sp.identity(n, format="csr")
        # alpha's own row (fixed to alpha, an equality) follows the variables' equality rows
        last = sp.csr_matrix((1, n))
        self.base = sp.vstack([a[eq], eye[ceq], last, a[up], -a[dn], eye[cup], -eye[cdn]], format="csc")
        self.row_masks = (eq, up, dn)
        self.alpha_row = int(eq.sum() + ceq.sum())  # alpha's row in the stacked system
        self.b_parts = (
            np.concatenate([hi[eq], cu[ceq]]),
            np.concatenate([hi[up], -lo[dn], cu[cup], -cl[cdn]]),
        )
        weight = np.zeros(n + 1)
        w0 = np.array([rng.max_speed for rng in state.operation_ranges])
        t = state.transmission
        if t is not None:  # ranges per actuator, speeds per joint: each joint's fastest speed
            w0 = joint_speed_limits(t.moment, w0)
        weight[asm.blocks["qd"]] = 1.0 / w0**2
        weight[asm.blocks["lam[0]"]] = 1.0 / max(float(np.linalg.norm(w)), 1e-3) ** 2
        self.objective = sp.diags(2 * weight).tocsc()
        n_eq = int(eq.sum() + ceq.sum()) + 1
        self.cone_sizes = (n_eq, int(up.sum() + dn.sum() + cup.sum() + cdn.sum()))
        self._last: tuple[tuple[int, float], dict[str, _F64]] | None = None  # solve()'s last answer

    def matrix(self, l: int) -> sp.csc_matrix:
        """``(rows, n + 1)`` the stacked constraint matrix of direction ``l`` (alpha's column last)."""
        eq, up, dn = self.row_masks
        col = alpha_column(self.state, self.asm, l)
        base, n_eq = self.base, int(eq.sum())
        stacked = np.zeros(base.shape[0])  # the variables' own bound rows hold no alpha
        head = np.concatenate([col[eq], np.zeros(self.alpha_row - n_eq), [1.0], col[up], -col[dn]])
        stacked[: len(head)] = head
        rows = np.flatnonzero(stacked)  # a zero coefficient is no entry (scipy drops it)
        return sp.csc_matrix(
            (
                np.concatenate([base.data, stacked[rows]]),
                np.concatenate([base.indices, rows.astype(base.indices.dtype)]),
                np.append(base.indptr, base.indptr[-1] + len(rows)).astype(base.indptr.dtype),
            ),
            shape=(base.shape[0], self.n + 1),
        )

    def vector(self, alpha: float) -> _F64:
        """The stacked right-hand side with alpha's row at ``alpha``."""
        return np.concatenate([self.b_parts[0], [alpha], self.b_parts[1]])

    def solve(self, l: int, alpha: float) -> dict[str, _F64]:
        """[`central_witness()`][mjtvm.physics.witness.central_witness] of direction ``l`` at ``alpha``.

        The last answer is kept: asked again for the same ``(l, alpha)`` (a drive and its
        squeeze, [`squeezed_drive()`][mjtvm.physics.hold_drive.squeezed_drive]) it is returned
        without a second solve (its arrays are not to be changed in place).

        Raises
        ------
        SolverError
            The QP is not solved (e.g. ``alpha`` above $\alpha_{kl}$).
        """
        if self._last is not None and self._last[0] == (l, alpha):
            return self._last[1]
        asm = self.asm
        cones = [clarabel.ZeroConeT(self.cone_sizes[0]), clarabel.NonnegativeConeT(self.cone_sizes[1])]
        opts = clarabel.DefaultSettings()
        opts.verbose = False
        q = np.zeros(self.n + 1)
        res = clarabel.DefaultSolver(
            self.objective, q, self.matrix(l), self.vector(alpha), cones, opts
        ).solve()
        status = str(res.status).split(".")[-1]
        if status not in ("Solved", "AlmostSolved"):
            raise SolverError("clarabel", status, (self.k, l))
        x = np.array(res.x)
        out = {
            "speeds": x[asm.blocks["qd"]],
            "torques": x[asm.blocks["tau[0]"]],
            "forces": asm.forces(x),
            "slip_speeds": x[asm.blocks["rho"]],
        }
        t = self.state.transmission
        if t is not None:
            out["actuator_speeds"] = t.moment @ out["speeds"]
        self._last = ((l, alpha), out)
        return out


@dataclass(frozen=True, eq=False)
class Drive:
    r"""What one rollout commands: joint speeds and feedforward torques, the object twist.

    Attributes
    ----------
    joints
        The M driven joints, each driven by its ``<dcmotor>`` (found by its transmission).
    speeds, torques
        ``(M,)`` joint speed setpoints (rad/s) and feedforward torques (N m, joint side).
    twist
        ``(6,)`` the object twist to produce, [v of the object origin; omega] (m/s, rad/s).
    contacts
        ``(geom label, type)`` of each finger contact (F, L, S); D-contacts are left out. The
        label is `geom_label()` (a name, or ``"<body>/geom<n>"``).
    slips
        S geom label -> (slip speed rho (m/s), unit slide direction (3,)) of eq. (13).
    actuators
        With a transmission: the A actuators (the state's ``transmission.actuators``), each
        driven by the ``<dcmotor>`` of that name on the model actuator's own transmission;
        ``torques`` are then their ``(A,)`` forces ``u`` (N m or N, actuator units). Empty
        for the paper's independent joints.
    moment
        ``(A, M)`` the state's moment matrix ``P`` (actuator speeds ``P qd``), or ``None``.
    speed_limits
        ``(A,)`` (``(M,)`` without a transmission) each actuator's (joint's) largest speed in
        its operation range (rad/s or m/s: `OperationRange.max_speed`), the speed edge the
        rollout holds it to (``SimSettings.edge_tol``); ``None``: not checked.
    """

    joints: tuple[str, ...]
    speeds: _F64
    torques: _F64
    twist: _F64
    contacts: tuple[tuple[str, str], ...]
    slips: Mapping[str, tuple[float, _F64]] = field(default_factory=dict)
    actuators: tuple[str, ...] = ()
    moment: _F64 | None = None
    speed_limits: _F64 | None = None

    def __post_init__(self) -> None:
        na = len(self.actuators) if self.actuators else len(self.joints)
        if self.speed_limits is not None and np.shape(self.speed_limits) != (na,):
            raise ParamError("drive.speed_limits", f"expected {na} speeds (one per actuator)")
        if np.shape(self.speeds) != (len(self.joints),) or np.shape(self.torques) != (na,):
            raise ParamError(
                "drive", f"expected {len(self.joints)} joint speeds and {na} torques (one per actuator)"
            )
        if self.actuators and (self.moment is None or self.moment.shape != (na, len(self.joints))):
            raise ParamError("drive.moment", f"expected shape ({na}, {len(self.joints)})")

    @property
    def actuator_speeds(self) -> _F64:
        """``(A,)`` ``P qd`` with a transmission, else the joint speeds."""
        return self.speeds if self.moment is None else self.moment @ self.speeds


def witness_drive(
    state: GraspState,
    k: int,
    l: int,
    alpha: float,
    s: float,
    *,
    witness: WitnessKind = "central",
    vertex: Any = None,
    assembly: Assembly | None = None,
    problem: WitnessProblem | None = None,
) -> Drive:
    r"""The drive of pair (k, l) at speed factor ``s`` (module docstring, step 2).

    ``vertex``: the [`Witness`][mjtvm.problem2.tvmmp.Witness] of the pair, required for ``"vertex"``.
    ``assembly``: the state's, for [`central_witness()`][mjtvm.physics.witness.central_witness].
    ``problem``: the state's [`WitnessProblem`][mjtvm.physics.witness.WitnessProblem] of ``k``
    when already built (the drives of several directions and speeds share it).

    Raises
    ------
    ParamError
        A ``problem`` of another state or reference wrench.
    """
    if state.rvds is None:
        raise ParamError("state", "the state has no RVDS (state.rvds is None)")
    if witness == "central":
        frac = min(s, 1.0)
        if problem is not None and (problem.state is not state or problem.k != k):
            raise ParamError("problem", f"expected the WitnessProblem of this state and k = {k}")
        qp = WitnessProblem(state, k, assembly=assembly) if problem is None else problem
        sol = qp.solve(l, alpha * frac * (1.0 - 1e-7))
        gain = s / frac if frac > 0 else 0.0
        speeds, torques, rho = sol["speeds"] * gain, sol["torques"], sol["slip_speeds"] * gain
    elif witness == "vertex":
        if vertex is None:
            raise ParamError("vertex", "the 'vertex' drive needs the pair's Witness")
        speeds, torques, rho = vertex.speeds * s, vertex.torques, vertex.slip_speeds * s
    else:
        raise ParamError("witness", f"expected 'central' or 'vertex', got {witness!r}", witness)
    contacts, slips, i_s = [], {}, 0
    for c in state.contacts:
        if c.type == "D":
            continue
        geom = c.name.split("#")[0]
        contacts.append((geom, c.type))
        if c.type == "S" and c.slide_direction is not None:
            rate = float(rho[min(i_s, len(rho) - 1)]) if len(rho) else 0.0
            slips[geom] = (rate, np.asarray(c.slide_direction, dtype=float))
            i_s += 1
    t = state.transmission
    return Drive(
        state.joint_names,
        np.asarray(speeds, float),
        np.asarray(torques, float),
        s * alpha * np.asarray(state.rvds[l], float),
        tuple(contacts),
        slips,
        actuators=() if t is None else t.actuator_names,
        moment=None if t is None else t.moment,
        speed_limits=np.array([r.max_speed for r in state.operation_ranges], dtype=float),
    )


# ------------------------------------------------------------------- rollouts
