r"""Why an alpha of Problem 2 is 0 or a pair infeasible, in words (:func:`diagnose`).

An enveloping grasp with every touching link a sticking F-point is typically locked: two
F-points on one finger, or one on the palm, admit no object motion, and TVMMP is exactly 0.
A pair can also be infeasible: some joint cannot produce the torque that balances the REFS
vertex. Each question is answered with small LPs on the state alone, only for the pairs that
need it (every alpha > 0: nothing is computed).

* :math:`\alpha_{kl} = 0`. First the kinematics alone (eq. 11-13): the contact rows
  :math:`H(J\dot q - G^T \alpha \hat r_l)\ (=, \le)\ 0` (with the S-points' slip) and every
  joint at most its no-load speed (the operation range's largest speed, eq. 1), maximising
  alpha (:func:`kinematic_alpha`). If that is 0, the contacts lock the motion, whatever the
  forces: a deletion filter (drop one contact at a time, leave it out while the others still
  lock) gives a minimal set of contacts whose rows alone admit no joint speed along
  :math:`\hat r_l`. Otherwise the operation ranges bind: at the torques that balance
  :math:`w_k` (eq. 19-20) they leave the joints no speed for the motion; the same filter on
  the joints (every range enlarged 100 times in torque and speed, then each restored while
  alpha stays > 0) gives a minimal set of joints.
* an infeasible pair (:math:`w_k` cannot be balanced within the ranges, eq. 19-20, 22-24;
  then every :math:`l` of this :math:`k` is): with every range enlarged, still infeasible
  means no contact forces balance :math:`w_k` at all (the friction cones and normals);
  otherwise the filter names the joints whose torque limits bind, each with the torque it
  needs (the witness of the LP with those joints enlarged) and the most its range gives.

The pair LPs are Problem 2's own (:class:`~mjtvm.core.problem2.StateLPs`, certified), on the
state with the contacts or ranges changed, so that what is diagnosed is what was solved.
A minimal set is one of possibly several (the filter's order is the state's).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog

from ..errors import ParamError, SolverError
from .assembly import BoxForm, grasp_map_transpose
from .contacts import Contact, slide_unit, tangent_basis
from .problem2 import StateLPs
from .result import Diagnosis, PairStatus
from .state import GraspState
from .transmission import joint_speed_limits

__all__ = ["RELAX", "diagnose", "kinematic_alpha"]

RELAX = 100.0  # an enlarged operation range: the range scaled by this in torque and speed
_KIN_ZERO = 1e-9  # kinematic alpha at most this (rows and speeds normalised to 1) is 0


# ------------------------------------------------------------------ kinematics alone
def _kinematic_rows(
    state: GraspState, contacts: Sequence[Contact], r: NDArray[np.float64]
) -> tuple[list[NDArray[np.float64]], list[NDArray[np.float64]], int]:
    """Equality and inequality rows over ``[u (M), rho (S), alpha]`` (``qd = speed * u``, as
    eq. 11-13 write them in :mod:`~mjtvm.core.assembly`) and the number of rho variables."""
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


def _locking_contacts(state: GraspState, r: NDArray[np.float64]) -> tuple[Contact, ...]:
    """A minimal set of the state's contacts whose kinematics alone give alpha 0 (deletion filter)."""
    kept = list(state.contacts)
    for c in list(kept):
        rest = [x for x in kept if x is not c]
        if kinematic_alpha(state, r, rest) == 0.0:
            kept = rest
    return tuple(kept)


# ------------------------------------------------------------------ Problem 2 with ranges changed
def _solve(
    state: GraspState, w: NDArray[np.float64], r: NDArray[np.float64], box: BoxForm, solver: str
) -> tuple[str, float, NDArray[np.float64] | None]:
    """Status, alpha (0 within the solver's tolerance, as tvmmp reports it) and joint torques
    of Problem 2's pair (w, r); ``r = 0`` asks only whether ``w`` is balanced (alpha held at 0)."""
    problem = StateLPs(state, box, solver)
    zero_twist = not np.any(r)
    verdict = problem.certified(w, r, alpha_max=0.0 if zero_twist else np.inf)
    if problem.session is not None:
        problem.session.release()
        problem.session = None
    sol = verdict.settled.solution
    if sol.status != "optimal" or sol.x is None:
        return sol.status, float("nan"), None
    alpha = float(sol.x[problem.alpha_col])
    alpha = 0.0 if zero_twist or alpha <= problem.zero_alpha(r) else alpha
    return "optimal", alpha, np.array(sol.x[problem.asm.blocks["tau[0]"]])


def _with_relaxed(state: GraspState, relaxed: set[int]) -> GraspState:
    ranges = tuple(
        op.scaled(torque=RELAX, speed=RELAX) if j in relaxed else op
        for j, op in enumerate(state.operation_ranges)
    )
    return state.with_(operation_ranges=ranges)


def _binding_joints(state: GraspState, works: Callable[[GraspState], bool]) -> list[int] | None:
    """A minimal set of joints whose enlarged ranges make ``works(state)`` true (deletion
    filter), or ``None`` when enlarging every range does not."""
    relaxed = set(range(len(state.operation_ranges)))  # the joints, or a transmission's actuators
    if not works(_with_relaxed(state, relaxed)):
        return None
    for j in range(len(state.operation_ranges)):
        if works(_with_relaxed(state, relaxed - {j})):
            relaxed.discard(j)
    return sorted(relaxed)


# ------------------------------------------------------------------ the words
def _binding_limits(state: GraspState, works: Callable[[GraspState], bool]) -> list[int]:
    """A minimal set of limited joints whose position limits, removed, give ``works``
    (the state without any limits does): removed in joint order until it works, then each
    put back where it still works."""
    lim = state.joint_limits
    assert lim is not None

    def without(removed: set[int]) -> GraspState:
        lo, hi = lim.lower.copy(), lim.upper.copy()
        idx = sorted(removed)
        lo[idx], hi[idx] = -np.inf, np.inf
        return state.with_(joint_limits=replace(lim, lower=lo, upper=hi))

    removed: set[int] = set()
    for joint in np.flatnonzero(lim.limited).tolist():
        removed.add(joint)
        if works(without(removed)):
            break
    for joint in sorted(removed):
        if works(without(removed - {joint})):
            removed.discard(joint)
    return sorted(removed)


def _names(items: Sequence[str]) -> str:
    return ", ".join(repr(x) for x in items)


def _lock_hint(contacts: Sequence[Contact]) -> str:
    """Why such contacts lock: a point no joint moves, or sticking points sharing joints."""
    still = [c.name for c in contacts if not np.any(c.jacobian)]
    if still:
        return f"; {_names(still)} {'is' if len(still) == 1 else 'are'} on a body no joint moves"
    sticking = [c for c in contacts if c.type == "F"]
    for a in sticking:
        for b in sticking:
            if a is not b and np.any(np.any(a.jacobian != 0, axis=0) & np.any(b.jacobian != 0, axis=0)):
                return f"; {a.name!r} and {b.name!r} are sticking points moved by the same joints"
    return ""


def _zero_alpha(
    state: GraspState, k: int, l: int, box: BoxForm, solver: str, locks: dict[int, tuple[Contact, ...]]
) -> Diagnosis:
    assert state.rvds is not None
    r, w = state.rvds[l], state.refs[k]
    if l not in locks:
        locks[l] = _locking_contacts(state, r) if kinematic_alpha(state, r) == 0.0 else ()
    if locks[l]:
        names = tuple(c.name for c in locks[l])
        kinds = ", ".join(f"{c.name!r} ({c.type})" for c in locks[l])
        tr = state.transmission
        if tr is not None and tr.constraint_jacobian is not None:
            free = state.with_(transmission=replace(tr, constraint_names=(), constraint_jacobian=None))
            if kinematic_alpha(free, r, locks[l]) > 0.0:  # the joint couplings take part
                kinds += f" with the equality constraints {_names(tr.constraint_names)}"
        return Diagnosis(
            (k, l),
            "contacts",
            names,
            (),
            f"the contacts {kinds} lock the motion along RVDS vertex {l}: their kinematic rows "
            f"(J qd = G^T rdot, eq. 11-13) admit no joint speed for it{_lock_hint(locks[l])}",
        )
    lim = state.joint_limits
    if lim is not None and _solve(state.with_(joint_limits=None), w, r, box, solver)[1] > 0.0:
        held = _binding_limits(state, lambda s: _solve(s, w, r, box, solver)[1] > 0.0)
        names = tuple(state.joint_names[j] for j in held)
        return Diagnosis(
            (k, l),
            "limits",
            (),
            names,
            f"the position limits of joint{'' if len(names) == 1 else 's'} {_names(names)} bind: "
            f"on a limit, or reaching it within {lim.horizon:g} m of object travel along RVDS vertex {l} "
            "(docs/joint-limits.md)",
        )
    joints = _binding_joints(state, lambda s: _solve(s, w, r, box, solver)[1] > 0.0)
    if not joints:
        why = (
            "an alpha at the solver's tolerance"
            if joints is not None
            else "enlarging every operation range does not lift it: the statics of the passive joints, "
            "the constraint forces or the damping"
        )
        return Diagnosis(
            (k, l), "unknown", (), (), f"no contact locks the motion and no operation range binds ({why})"
        )
    names = tuple(state.actuator_names[j] for j in joints)
    return Diagnosis(
        (k, l),
        "ranges",
        (),
        names,
        f"the operation ranges of {'joint' if state.transmission is None else 'actuator'}"
        f"{'' if len(names) == 1 else 's'} {_names(names)} bind: "
        f"at the torques that balance REFS vertex {k} (eq. 19-20) they leave no speed for RVDS vertex {l}",
    )


def _infeasible(state: GraspState, k: int, box: BoxForm, solver: str) -> Diagnosis:
    w, r = state.refs[k], np.zeros(state.twist_dim)
    joints = _binding_joints(state, lambda s: _solve(s, w, r, box, solver)[0] == "optimal")
    if joints is None:
        return Diagnosis(
            (k, -1),
            "balance",
            tuple(c.name for c in state.contacts),
            (),
            f"REFS vertex {k} cannot be balanced by any forces of the contacts (their normals and friction "
            "cones, eq. 20-24), whatever the joint torques",
        )
    _, _, tau = _solve(_with_relaxed(state, set(joints)), w, r, box, solver)
    unit = "N m" if state.transmission is None else "N or N m"  # a tendon's force is in N
    needs = ", ".join(
        f"{state.actuator_names[j]!r} (needs {abs(tau[j]):.4g} {unit}, has {state.operation_ranges[j].max_torque:.4g})"
        if tau is not None
        else repr(state.actuator_names[j])
        for j in joints
    )
    return Diagnosis(
        (k, -1),
        "ranges",
        (),
        tuple(state.actuator_names[j] for j in joints),
        f"REFS vertex {k} cannot be balanced: the torque limits of {needs} bind (eq. 19-20)",
    )


def diagnose(
    state: GraspState,
    alpha: NDArray[np.float64],
    status: Sequence[Sequence[PairStatus]],
    *,
    box: BoxForm = "eliminated",
    solver: str = "highs",
) -> tuple[Diagnosis, ...]:
    r"""One :class:`~mjtvm.core.result.Diagnosis` per pair with alpha 0 and per REFS vertex
    that cannot be balanced (pair ``(k, -1)``); empty when every alpha is > 0.

    Parameters
    ----------
    state
        The grasp state Problem 2 was solved for (with ``rvds``).
    alpha, status
        ``(K, R)`` alphas and statuses of :func:`~mjtvm.core.tvmmp.tvmmp`.
    box, solver
        As Problem 2 was solved.
    """
    out: list[Diagnosis] = []
    locks: dict[int, tuple[Contact, ...]] = {}  # the kinematics depend on l only
    for k, row in enumerate(status):
        if "infeasible" in row:
            out.append(_infeasible(state, k, box, solver))
            continue
        for l, s in enumerate(row):
            if s == "optimal" and alpha[k, l] == 0.0:
                out.append(_zero_alpha(state, k, l, box, solver, locks))
    return tuple(out)
