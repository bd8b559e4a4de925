r"""Why an alpha of Problem 2 is 0 or a pair infeasible, in words ([`diagnose()`][mjtvm.problem2.diagnosis.diagnose]).

An enveloping grasp with every touching link a sticking F-point is typically locked: two
F-points on one finger, or one on the palm, admit no object motion, and TVMMP is exactly 0.
A pair can also be infeasible: some joint cannot produce the torque that balances the REFS
vertex. Each question is answered with small LPs on the state alone, only for the pairs that
need it (every alpha > 0: nothing is computed).

* $\alpha_{kl} = 0$. First the kinematics alone (eq. 11-13): the contact rows
  $H(J\dot q - G^T \alpha \hat r_l)\ (=, \le)\ 0$ (with the S-points' slip) and every
  joint at most its no-load speed (the operation range's largest speed, eq. 1), maximising
  alpha ([`kinematic_alpha()`][mjtvm.problem2.kinematic.kinematic_alpha]). If that is 0, the contacts lock the motion, whatever the
  forces: a deletion filter (drop one contact at a time, leave it out while the others still
  lock) gives a minimal set of contacts whose rows alone admit no joint speed along
  $\hat r_l$. Otherwise the operation ranges bind: at the torques that balance
  $w_k$ (eq. 19-20) they leave the joints no speed for the motion; the same filter on
  the joints (every range enlarged 100 times in torque and speed, then each restored while
  alpha stays > 0) gives a minimal set of joints.
* an infeasible pair ($w_k$ cannot be balanced within the ranges, eq. 19-20, 22-24;
  then every $l$ of this $k$ is): with every range enlarged, still infeasible
  means no contact forces balance $w_k$ at all (the friction cones and normals);
  otherwise the filter names the joints whose torque limits bind, each with the torque it
  needs (the witness of the LP with those joints enlarged) and the most its range gives.
  Either way the diagnosis says which way the REFS vertex is unbalanced: the certified Farkas
  multipliers ``y`` of the LP ([`farkas()`][mjtvm.lp.certificate.farkas]) bound every
  admissible contact wrench ``f`` by ``y_w^T f < -y_w^T w_k`` on the balance rows
  ``G E lam = -w_k`` (eq. 20), so the net wrench ``w_k + f`` has a negative component
  along ``y_w`` whatever the forces: it pushes the object along the twist ``-y_w``
  ([`escape_direction()`][mjtvm.problem2.diagnosis.escape_direction]; e.g. along the weight for a finger whose cone cannot hold it
  up). For the balance cause each contact is then changed alone ([`relieving_contacts()`][mjtvm.problem2.diagnosis.relieving_contacts]):
  its friction coefficient raised (an F-point: the least that balances, by bisection), or
  the contact made a sticking F-point (an L, S or D point); those that balance the vertex
  are named, with the change.

The pair LPs are Problem 2's own ([`StateLPs`][mjtvm.problem2.lps.StateLPs], certified), on the
state with the contacts or ranges changed, so that what is diagnosed is what was solved.
A minimal set is one of possibly several (the filter's order is the state's). The kinematics
alone (kinematic alpha, the locking contacts) are ``mjtvm.problem2.kinematic``'s.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from mjtvm.model.contacts import Contact
from mjtvm.model.state import GraspState
from mjtvm.problem2.assembly import BoxForm
from mjtvm.problem2.holding import unheld_motions
from mjtvm.problem2.kinematic import kinematic_alpha, locking_contacts
from mjtvm.problem2.lps import StateLPs
from mjtvm.problem2.relaxed import RELAX, binding_balance, binding_joints, solve_pair, with_relaxed
from mjtvm.problem2.result import Diagnosis, PairStatus

__all__ = ["RELAX", "diagnose", "escape_direction", "kinematic_alpha", "relieving_contacts"]

_MU_STEPS = 12  # bisection steps on log(mu) between a contact's mu and RELAX times it: 0.15 % on tan(60 deg)
_PURE = 1e-6  # a direction's force (moment x length) part below this fraction of the other is left out


# ------------------------------------------------------------------ which way, and what relieves it
def _dual_bound(
    a: NDArray[np.float64],
    lower: NDArray[np.float64],
    upper: NDArray[np.float64],
    col_lower: NDArray[np.float64],
    col_upper: NDArray[np.float64],
    y: NDArray[np.float64],
) -> float:
    """The finite part of the dual bound of ``min 0`` s.t. ``lower <= a x <= upper``,
    ``col_lower <= x <= col_upper`` for the row multipliers ``y``: each row and column
    term at its finite bound, the terms at an infinite one left out (those are the
    multipliers of the wrong sign, within round-off of 0, that
    [`farkas()`][mjtvm.lp.certificate.farkas] measures and bounds). Positive for the sign of
    ``y`` that proves the LP infeasible: here only to tell that sign."""

    def finite(coef: NDArray[np.float64], lo: NDArray[np.float64], hi: NDArray[np.float64]) -> float:
        at = np.where(coef > 0.0, lo, np.where(coef < 0.0, hi, 0.0))
        ok = np.isfinite(at)
        return float(np.sum(coef[ok] * at[ok]))

    return finite(y, lower, upper) + finite(-(a.T @ y), col_lower, col_upper)


def escape_direction(
    state: GraspState, w: NDArray[np.float64], *, box: BoxForm = "eliminated", solver: str = "highs"
) -> NDArray[np.float64] | None:
    r"""``(D,)`` the unit twist along which the REFS vertex ``w`` stays unbalanced, or ``None``.

    The LP of ``w`` at rest (Problem 2's pair with ``r = 0``, [`StateLPs`][mjtvm.problem2.lps.StateLPs])
    solved and certified infeasible by its Farkas multipliers ``y``
    ([`farkas()`][mjtvm.lp.certificate.farkas], HiGHS' dual ray); ``-y`` on its balance rows
    ``G E lam = -w`` (eq. 20), normalised: the net wrench on the object has a negative
    component along ``y_w`` for every admissible contact force (module docstring), so it
    pushes the object along ``-y_w`` (``[v; omega]`` about the object's origin, world frame).
    ``None`` when the LP is feasible or not certified infeasible, or when the certificate
    lies in the torque rows alone (a joint that cannot hold its own link).
    """
    problem = StateLPs(state, box, solver)
    r = np.zeros(state.twist_dim)
    verdict = problem.certified(w, r, alpha_max=0.0)
    if problem.session is not None:
        problem.session.release()
        problem.session = None
    sol = verdict.settled.solution
    if sol.status != "infeasible" or not verdict.certified or sol.row_dual is None:
        return None
    y = np.asarray(sol.row_dual, dtype=float)
    if not problem.proves_infeasible(w, r, 0.0, sol):
        return None
    a = problem.pair_matrix(r)[0]
    lower, upper = problem.asm.statics_bounds(w)
    col_upper = problem.col_upper.copy()
    col_upper[-1] = 0.0  # alpha held at 0: the holding at rest
    sign = max((1.0, -1.0), key=lambda s: _dual_bound(a, lower, upper, problem.col_lower, col_upper, s * y))
    y_w = sign * y[problem.asm.wrench_rows[0]]
    norm = float(np.linalg.norm(y_w))
    if norm == 0.0 or _dual_bound(a, lower, upper, problem.col_lower, col_upper, sign * y) <= 0.0:
        return None
    out: NDArray[np.float64] = -y_w / norm
    return out


def _feasible(state: GraspState, w: NDArray[np.float64], box: BoxForm, solver: str) -> bool:
    return solve_pair(state, w, np.zeros(state.twist_dim), box, solver)[0] == "optimal"


def relieving_contacts(
    state: GraspState, w: NDArray[np.float64], *, box: BoxForm = "eliminated", solver: str = "highs"
) -> tuple[tuple[str, str], ...]:
    r"""The changes of one contact alone that balance ``w`` at rest: ``(contact, change)`` pairs.

    An F-point: its friction coefficient raised (eq. 24's cone), up to `RELAX` times
    its own; where that balances ``w``, the least coefficient that does, by bisection on
    its logarithm (``"mu >= X"``, X rounded up). An L, S or D point: made a sticking F-point
    (``"type F, mu X"``) with the largest coefficient of the state's F and S points (1
    without any). ``state`` is solved as given: pass it with its ranges enlarged to ask
    about the contacts alone.
    """
    mus = [float(c.mu) for c in state.contacts if c.type in ("F", "S") and c.mu is not None]
    mu0 = max(mus, default=1.0)

    def with_contact(i: int, c: Contact) -> GraspState:
        return state.with_(contacts=tuple(c if j == i else x for j, x in enumerate(state.contacts)))

    out: list[tuple[str, str]] = []
    for i, c in enumerate(state.contacts):
        if c.type == "F" and c.mu is not None:
            lo = float(c.mu)
            hi = RELAX * max(lo, 1.0)
            if not _feasible(with_contact(i, replace(c, mu=hi)), w, box, solver):
                continue
            for _ in range(_MU_STEPS):
                mid = float(np.sqrt(lo * hi)) if lo > 0.0 else hi / 2.0
                if _feasible(with_contact(i, replace(c, mu=mid)), w, box, solver):
                    hi = mid
                else:
                    lo = mid
            out.append((c.name, f"mu >= {_round_up(hi)}"))
        elif c.type != "F":
            stuck = replace(c, type="F", mu=mu0, slide_direction=None)
            if _feasible(with_contact(i, stuck), w, box, solver):
                out.append((c.name, f"type F, mu {mu0:g}"))
    return tuple(out)


def _round_up(x: float) -> str:
    """``x`` to 3 significant digits, rounded up (a bisection's feasible end stays feasible)."""
    if x <= 0.0:
        return "0"
    e = int(np.floor(np.log10(x))) - 2
    return f"{np.ceil(x / 10.0**e - 1e-9) * 10.0**e:.3g}"


def _vector(v: NDArray[np.float64]) -> str:
    return "(" + ", ".join(f"{x:.3g}" if abs(x) >= 5e-4 else "0" for x in v / np.linalg.norm(v)) + ")"


def _direction_words(state: GraspState, w: NDArray[np.float64], t: NDArray[np.float64]) -> str:
    """The escape twist ``t`` in words: the force along its ``v``, the moment about its ``omega``."""
    d = state.dim
    v, om = t[:d], t[d:]
    length = max(
        (float(np.linalg.norm(c.position - state.object_position)) for c in state.contacts), default=1.0
    )
    length = length if length > 0.0 else 1.0
    fv, fm = float(np.linalg.norm(v)), float(np.linalg.norm(om)) * length
    parts = []
    if fv > _PURE * fm:
        words = f"a net force along {_vector(v)}"
        wf = w[:d]
        if np.linalg.norm(wf) > 0.0 and float(v @ wf) / (fv * float(np.linalg.norm(wf))) > 0.999:
            words += " (the REFS vertex's own direction)"
        parts.append(words)
    if fm > _PURE * fv:
        if d == 2:
            parts.append(f"a net moment {'counter-clockwise' if om[0] > 0 else 'clockwise'}")
        else:
            parts.append(f"a net moment about {_vector(om)}")
    return " and ".join(parts) + " that no admissible contact force opposes"


def _relief_words(relief: Sequence[tuple[str, str]]) -> str:
    if not relief:
        return (
            "no single contact's friction or type balances it: no contact's normal opposes that "
            "direction (move a finger, or add a contact, whose normal pushes against it)"
        )
    return "balanced with " + " or ".join(f"{name!r} {change}" for name, change in relief)


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
        locks[l] = locking_contacts(state, r) if kinematic_alpha(state, r) == 0.0 else ()
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
    if lim is not None and solve_pair(state.with_(joint_limits=None), w, r, box, solver)[1] > 0.0:
        held = _binding_limits(state, lambda s: solve_pair(s, w, r, box, solver)[1] > 0.0)
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
    joints = binding_joints(state, lambda s: solve_pair(s, w, r, box, solver)[1] > 0.0)
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
    unheld = unheld_motions(state, k)  # a cause no contact or range can fix: said first
    if unheld is not None:
        moved = tuple(dict.fromkeys(j for group in unheld.joints for j in group))
        return Diagnosis((k, -1), "unheld", (), moved, unheld.describe(state.joint_names))
    w, r = state.refs[k], np.zeros(state.twist_dim)
    joints = binding_balance(state, w, box, solver)
    if joints is None:
        relaxed = with_relaxed(state, set(range(len(state.operation_ranges))))
        t = escape_direction(relaxed, w, box=box, solver=solver)
        relief = relieving_contacts(relaxed, w, box=box, solver=solver)
        which = "" if t is None else f": {_direction_words(state, w, t)}"
        return Diagnosis(
            (k, -1),
            "balance",
            tuple(c.name for c in state.contacts),
            (),
            f"REFS vertex {k} cannot be balanced by any forces of the contacts (their normals and friction "
            f"cones, eq. 20-24), whatever the joint torques{which}; {_relief_words(relief)}",
            () if t is None else tuple(float(x) for x in t),
            relief,
        )
    _, _, tau = solve_pair(with_relaxed(state, set(joints)), w, r, box, solver)
    unit = "N m" if state.transmission is None else "N or N m"  # a tendon's force is in N
    needs = ", ".join(
        f"{state.actuator_names[j]!r} (needs {abs(tau[j]):.4g} {unit}, has {state.operation_ranges[j].max_torque:.4g})"
        if tau is not None
        else repr(state.actuator_names[j])
        for j in joints
    )
    t = escape_direction(state, w, box=box, solver=solver)
    which = "" if t is None else f"; within those limits: {_direction_words(state, w, t)}"
    return Diagnosis(
        (k, -1),
        "ranges",
        (),
        tuple(state.actuator_names[j] for j in joints),
        f"REFS vertex {k} cannot be balanced: the torque limits of {needs} bind (eq. 19-20){which}",
        () if t is None else tuple(float(x) for x in t),
    )


def diagnose(
    state: GraspState,
    alpha: NDArray[np.float64],
    status: Sequence[Sequence[PairStatus]],
    *,
    box: BoxForm = "eliminated",
    solver: str = "highs",
) -> tuple[Diagnosis, ...]:
    r"""One `Diagnosis` per pair with alpha 0 and per REFS vertex
    that cannot be balanced (pair ``(k, -1)``); empty when every alpha is > 0.

    Parameters
    ----------
    state
        The grasp state Problem 2 was solved for (with ``rvds``).
    alpha, status
        ``(K, R)`` alphas and statuses of [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp].
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
