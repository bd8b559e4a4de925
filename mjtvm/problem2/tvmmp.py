r"""Problem 2: the TVMMP and the distribution of achievable velocities (eq. 31-35).

For each REFS vertex $w_k$ and each non-zero RVDS vertex $\hat r_l$,

$$
\alpha_{kl} = \max \alpha \ \text{s.t.}\ \dot r = \alpha \hat r_l \in S_1\ (S_2
\text{ with S-points}),
$$

and TVMMP $= \min_{kl} \alpha_{kl}$ (eq. 32, 35). The LPs of one state, solved and
certified, are [`StateLPs`][mjtvm.problem2.lps.StateLPs]'s; here they are run pair by pair and
reported (the limiting pair, the distribution of Supplement 4, the witnesses).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError, SolverError, StateError
from mjtvm.lp.certificate import clip
from mjtvm.lp.solvers import (
    SOLVERS,
    Settled,
)
from mjtvm.model.friction import FrictionReport, interval_corners, nominal_state
from mjtvm.model.state import GraspState
from mjtvm.problem2.assembly import Assembly, BoxForm
from mjtvm.problem2.lps import StateLPs
from mjtvm.problem2.result import Diagnosis
from mjtvm.problem2.result import (  # re-exported: the result types lived here
    PairStatus as PairStatus,
)
from mjtvm.problem2.result import (
    Timings as Timings,
)
from mjtvm.problem2.result import (
    TvmmpResult as TvmmpResult,
)
from mjtvm.problem2.result import (
    Witness as Witness,
)
from mjtvm.problem2.result import (
    finite_floats as finite_floats,
)
from mjtvm.problem2.result import (
    finite_or_none as finite_or_none,
)
from mjtvm.problem2.verdict import Verdict

__all__ = ["tvmmp"]

#: Alphas within this relative distance of the smallest one tie for the limiting pair (the
#: first of them in (k, l) order is reported). Symmetric grasps tie exactly in exact
#: arithmetic (Case 1: alpha 0.48885298708278810 and ...824 for two RVDS vertices), and which
#: of two tied alphas comes out smaller is round-off (HiGHS' options alone move alphas by up to
#: 6e-10 relative), far below this tolerance.
LIMITING_TIE_REL = 1e-8


def _witness(
    asm: Assembly, state: GraspState, x: NDArray[np.float64], alpha: float, r: NDArray[np.float64]
) -> Witness:
    tau = x[asm.blocks["tau[0]"]]
    qd = x[asm.blocks["qd"]]
    s = state.actuator_speeds(qd)  # qd itself without a transmission
    if asm.box == "literal":
        box = np.column_stack([x[asm.blocks[n]] for n in ("tau_min", "tau_max", "qd_min", "qd_max")])
    else:  # the motor gives |tau| + loss under joint damping (assembly's module docstring)
        loss = x[asm.blocks["loss"]] if "loss" in asm.blocks else 0.0
        box = np.column_stack(
            [np.minimum(tau - loss, 0), np.maximum(tau + loss, 0), np.minimum(s, 0), np.maximum(s, 0)]
        )
    forces = asm.forces(x) if state.contacts else np.zeros((0, state.dim))
    act = None if state.transmission is None else s
    return Witness(alpha, alpha * r, forces, tau.copy(), qd.copy(), x[asm.blocks["rho"]].copy(), box, act)


@dataclass
class _Pairs:
    """The verdicts of the (k, l) pairs as they are solved ([`TvmmpResult`][mjtvm.problem2.result.TvmmpResult]'s fields)."""

    alpha: NDArray[np.float64]
    status: list[list[PairStatus]]
    witnesses: list[list[Witness | None]]
    settled_by: list[list[str | None]]
    certified: list[list[bool | None]]
    notes: list[tuple[tuple[int, int], str]] = field(default_factory=list)
    held: list[bool] = field(default_factory=list)
    feasible: bool = True
    num_lps: int = 0

    @classmethod
    def empty(cls, n_k: int, n_l: int) -> _Pairs:
        return cls(
            np.full((n_k, n_l), np.nan),
            [["skipped"] * n_l for _ in range(n_k)],
            [[None] * n_l for _ in range(n_k)],
            [[None] * n_l for _ in range(n_k)],
            [[None] * n_l for _ in range(n_k)],
        )


def _settle(
    problem: StateLPs, w: NDArray[np.float64], r: NDArray[np.float64], alpha_max: float, pair: tuple[int, int]
) -> Settled:
    """The LP of one pair of eq. (31-35) settled across the backends (not yet certified);
    a SolverError names the pair."""
    try:
        return problem.solve(w, r, alpha_max=alpha_max)
    except SolverError as e:
        raise SolverError(e.solver, e.status, pair) from e


def _unheld_at_rest(problem: StateLPs, w: NDArray[np.float64]) -> Verdict | None:
    """The certified verdict "infeasible" of ``w``'s hold test at rest when the first LP of
    its k fails in every backend, else None.

    At ``qd = 0, alpha = 0`` every kinematic, range and joint-limit row holds, the travel
    horizon's too (they bound joint speeds), so the first LP of a k is feasible exactly when
    ``w`` is held at rest (`_solve_pairs()`). Without the horizon rows, alpha held at 0, the
    same test is an LP both backends decide where the full one can leave a nearly balanced
    ``w`` undecided (HiGHS "Unknown", Clarabel out of iterations)."""
    state = problem.state
    if state.joint_limits is None or state.joint_limits.horizon == 0.0:
        return None
    rest = StateLPs(
        state.with_(joint_limits=state.joint_limits.with_options(horizon=0.0)), problem.box, problem.solver
    )
    zero = np.zeros(state.twist_dim)
    try:
        settled = rest.solve(w, zero, alpha_max=0.0)
    except SolverError:
        return None
    if settled.solution.status != "infeasible":
        return None
    verdict = rest.conclude(w, zero, 0.0, settled, rest.check(w, zero, 0.0, settled.solution))
    if verdict.settled.solution.status != "infeasible" or not verdict.certified:
        return None
    return verdict


def _solve_pairs(problem: StateLPs, state: GraspState, witnesses: bool) -> _Pairs:
    """Every (k, l) pair's LP, the origin of the RVDS skipped (Supplement 3).

    For REFS vertex ``w_k`` and RVDS vertex ``r_l`` the LP is that of alpha r_l with w_k;
    ``r = 0`` (a state whose RVDS is the origin only, ``l = -1``) asks only whether w_k can
    be balanced, alpha held at 0. With qd = 0, alpha = 0, rho = 0 (and no damping loss) every
    kinematic and range row holds, since damping is not in the balance (a loss,
    [`assembly`][mjtvm.problem2.assembly]), so a pair is infeasible exactly when w_k cannot be held at
    rest ([`holding`][mjtvm.problem2.holding]): the first LP of each k is its hold test, reported as
    ``held``, and every l of an unheld k is infeasible (no more LPs).

    The pairs are solved RVDS vertex by RVDS vertex (l outer, k inner): from one k to the
    next only the balance rows' bounds change, which leaves the last basis dual feasible,
    so the dual simplex goes on from it; a new l changes the alpha column, which is in the
    basis whenever alpha > 0. With six test wrenches and six RVDS vertices on the 22-joint
    dataset hand this halves the time inside HiGHS (k outer: a new column every LP).

    An infeasible (or unbounded) answer is certified at once, since it decides which LPs
    follow; the optimal ones are certified together once every LP is solved
    ([`certify_many()`][mjtvm.problem2.certifying.StateCertificates.certify_many]), and an answer whose certificate
    fails is then solved again other ways ([`conclude()`][mjtvm.problem2.lps.StateLPs.conclude]).
    Should that find a pair infeasible, its k is infeasible as above and its later LPs,
    solved already, are dropped."""
    refs, rvds = state.refs, state.rvds
    if rvds is None:  # checked by tvmmp() already; kept for callers of this step
        raise StateError("rvds", "Problem 2 needs RVDS vertices (a non-empty list of twists)")
    n_k, n_l = refs.shape[0], rvds.shape[0]
    out = _Pairs.empty(n_k, n_l)
    nonzero = [l for l in range(n_l) if np.any(rvds[l] != 0.0)]
    unbalanced: set[int] = set()  # the k whose w_k no contact forces balance
    # In solving order: (pair, r, alpha_max, settled, verdict); verdict None until certified.
    solved: list[tuple[tuple[int, int], NDArray[np.float64], float, Settled, Verdict | None]] = []
    for l in nonzero if nonzero else [None]:
        r = rvds[l] if l is not None else np.zeros(state.twist_dim)
        for k in range(n_k):
            if k in unbalanced:
                continue
            pair = (k, -1 if l is None else l)
            alpha_max = np.inf if l is not None else 0.0
            try:
                settled = _settle(problem, refs[k], r, alpha_max, pair)
            except SolverError as e:
                if any(p[0] == k for p, *_ in solved):  # w_k is held: this pair's failure stands
                    raise
                rest = _unheld_at_rest(problem, refs[k])
                if rest is None:
                    raise
                note = f"{e.solver}: {e.status}; decided by the hold test at rest without the travel horizon"
                rest = replace(rest, settled=replace(rest.settled, note=note))
                out.num_lps += 2
                solved.append((pair, r, alpha_max, rest.settled, rest))
                unbalanced.add(k)
                continue
            out.num_lps += 1
            sol = settled.solution
            verdict = None
            if not (sol.status == "optimal" and sol.x is not None and sol.row_dual is not None):
                check = problem.check(refs[k], r, alpha_max, sol)
                verdict = problem.conclude(refs[k], r, alpha_max, settled, check)
                if verdict.settled.solution.status == "infeasible":
                    unbalanced.add(k)
            solved.append((pair, r, alpha_max, settled, verdict))
    pending = [(refs[p[0]], r, am, st.solution) for p, r, am, st, v in solved if v is None]
    certs = iter(problem.certify_many(pending))
    unbalanced.clear()
    for pair, r, alpha_max, settled, verdict in solved:
        k = pair[0]
        if verdict is None:
            cert = next(certs)
            verdict = problem.conclude(refs[k], r, alpha_max, settled, (cert.ok, cert))
        if k in unbalanced:
            continue
        _record(out, problem, state, pair, r, verdict, nonzero, witnesses)
        if verdict.settled.solution.status == "infeasible":
            unbalanced.add(k)
    out.notes.sort(key=lambda note: note[0])  # in (k, l) order, whatever the solving order
    out.held = [k not in unbalanced for k in range(n_k)]
    return out


def _record(
    out: _Pairs,
    problem: StateLPs,
    state: GraspState,
    pair: tuple[int, int],
    r: NDArray[np.float64],
    verdict: Verdict,
    nonzero: list[int],
    witnesses: bool,
) -> None:
    """Pair ``(k, l)``'s verdict (RVDS vertex ``r``) into ``out``: an infeasible one for every l of its k."""
    k, l = pair
    settled = verdict.settled
    sol = settled.solution
    if settled.note is not None:
        out.notes.append((pair, settled.note))
    if sol.status == "infeasible":
        out.feasible = False
        for ll in nonzero:
            out.status[k][ll] = "infeasible"
            out.settled_by[k][ll] = settled.solver
            out.certified[k][ll] = verdict.certified
            out.alpha[k, ll] = np.nan
            out.witnesses[k][ll] = None
        return
    if l < 0:
        return
    out.status[k][l] = sol.status
    out.settled_by[k][l] = settled.solver
    out.certified[k][l] = verdict.certified
    if sol.status == "optimal" and sol.x is not None:
        # The witness within its bounds (the certificate checked the rows with it):
        # alpha >= 0, lam >= 0 exactly, never a negative alpha (alpha's entry alone unless
        # the witness is asked for: the same clip, one entry).
        j = problem.alpha_col
        a = float(np.minimum(np.maximum(sol.x[j], problem.col_lower[j]), problem.col_upper[j]))
        # ZERO_ALPHA applies in the equilibrated rows (the solver's tolerance is
        # there), so that the rounding to 0 does not depend on the unit system.
        a = 0.0 if abs(a) <= problem.zero_alpha(r) else a
        out.alpha[k, l] = a
        if witnesses:
            x = clip(sol.x, problem.col_lower, problem.col_upper)
            out.witnesses[k][l] = _witness(problem.asm, state, x, a, r)


def _limiting(pairs: _Pairs) -> tuple[tuple[int, int] | None, float | None]:
    r"""The pair attaining $\min \alpha_{kl}$ over the optimal pairs (eq. 32, 35) and
    that minimum; ``None`` when a pair is infeasible or none is optimal.

    The pair is the first in (k, l) order whose alpha is within ``LIMITING_TIE_REL`` of the
    minimum: alphas tied in exact arithmetic (symmetric grasps) differ by round-off, which
    must not decide the pair (its alpha exceeds the reported minimum by that round-off)."""
    alpha, status = pairs.alpha, pairs.status
    n_k, n_l = alpha.shape
    optimal = [(k, l) for k in range(n_k) for l in range(n_l) if status[k][l] == "optimal"]
    if not (pairs.feasible and optimal):
        return None, None
    least = min(float(alpha[kl]) for kl in optimal)
    limiting = next(kl for kl in optimal if alpha[kl] <= least + LIMITING_TIE_REL * abs(least))
    return limiting, least


def _distribution(
    pairs: _Pairs, rvds: NDArray[np.float64], twist_dim: int
) -> list[NDArray[np.float64] | None]:
    r"""Per RVDS vertex, $\min_k \alpha_{kl} \hat r_l$ (Supplement 4): the origin
    where skipped, ``None`` where a pair is infeasible or none is optimal."""
    alpha, status = pairs.alpha, pairs.status
    n_k, n_l = alpha.shape
    distribution: list[NDArray[np.float64] | None] = []
    for l in range(n_l):
        col = [status[k][l] for k in range(n_k)]
        if all(s == "skipped" for s in col):
            distribution.append(np.zeros(twist_dim))
        elif "infeasible" in col or "optimal" not in col:
            distribution.append(None)
        else:
            distribution.append(np.nanmin(alpha[:, l]) * rvds[l])
    return distribution


def tvmmp(
    state: GraspState,
    *,
    solver: str = "highs",
    box: BoxForm = "eliminated",
    witnesses: bool = True,
    diagnose: bool = False,
    compiled: bool = False,
) -> TvmmpResult:
    r"""Solve Problem 2 (eq. 31-35) for one grasp state.

    Parameters
    ----------
    state
        A grasp state with ``rvds`` (the RVDS vertices $\hat r_l$).
    solver
        ``"highs"`` (default) or ``"clarabel"``.
    box
        ``"eliminated"`` (exact reduction of eq. 2, default) or ``"literal"``.
    witnesses
        Whether to keep the forces, torques, speeds and box of each optimal pair.
    diagnose
        Whether to say why an alpha is 0 or a pair infeasible ([`diagnosis`][mjtvm.problem2.diagnosis],
        a few LPs per such pair; nothing when every alpha is > 0): the result's ``diagnosis``.
    compiled
        Whether the LPs that differ from HiGHS' last only in the balance rows' bounds (a new
        REFS vertex, the same RVDS vertex) are re-solved by the compiled dual simplex of
        [`warm`][mjtvm.lp.warm] (numba, imported on first use: for batches; where numba does
        not import, HiGHS solves them). Every answer is certified the same way either way.

    Returns
    -------
    TvmmpResult

    Raises
    ------
    ParamError
        When the state has no RVDS, or ``solver`` or ``box`` is unknown.
    SolverError
        When a solver fails (the failing pair is named).
    """
    if state.rvds is None:
        raise StateError("rvds", "Problem 2 needs RVDS vertices (a non-empty list of twists)")
    if solver not in SOLVERS:
        raise ParamError("solver", f"expected one of {SOLVERS}, got {solver!r}", solver)
    t0 = time.perf_counter()
    problem = StateLPs(state, box, solver, compiled=compiled)
    t1 = time.perf_counter()
    pairs = _solve_pairs(problem, state, witnesses)
    if problem.session is not None:  # the pairs are settled: its HiGHS instance serves the next state
        problem.session.release()
        problem.session = None
    t2 = time.perf_counter()
    limiting, value = _limiting(pairs)
    found: tuple[Diagnosis, ...] = ()
    if diagnose and (not pairs.feasible or np.any(pairs.alpha == 0.0)):
        from mjtvm.problem2.diagnosis import diagnose as diagnose_pairs  # it solves Problem 2's LPs itself

        found = diagnose_pairs(state, pairs.alpha, pairs.status, box=box, solver=solver)
    report = None
    if state.friction_margin > 0.0 or any(c.mu_range is not None for c in state.contacts):
        report = _friction_report(state, solver, box, compiled)
    return TvmmpResult(
        alpha=pairs.alpha,
        status=tuple(tuple(s) for s in pairs.status),
        tvmmp=value,
        feasible=pairs.feasible,
        distribution=tuple(_distribution(pairs, state.rvds, state.twist_dim)),
        limiting=limiting,
        witnesses=tuple(tuple(w) for w in pairs.witnesses),
        timings=Timings(t1 - t0, t2 - t1, t2 - t0, pairs.num_lps),
        solver=solver,
        box=box,
        settled_by=tuple(tuple(b) for b in pairs.settled_by),
        certified=tuple(tuple(c) for c in pairs.certified),
        notes=tuple(pairs.notes),
        held=tuple(pairs.held),
        diagnosis=found,
        friction=report,
    )


def _friction_report(state: GraspState, solver: str, box: BoxForm, compiled: bool) -> FrictionReport:
    """The TVMMP at margin 0 (when the margin is not) and the worst TVMMP over the friction
    intervals, the least over the corners of [`interval_corners()`][mjtvm.model.friction.interval_corners]
    (exact by its quasi-concavity argument; each corner's LPs certified as any state's)."""
    certified = True
    nominal = None
    if state.friction_margin > 0.0:
        res = tvmmp(nominal_state(state), solver=solver, box=box, witnesses=False, compiled=compiled)
        nominal, certified = res.tvmmp, not res.uncertified()
    corners = interval_corners(state)
    worst: float | None = None
    worst_mu: tuple[tuple[str, float], ...] = ()
    feasible = True
    for corner in corners:
        res = tvmmp(corner, solver=solver, box=box, witnesses=False, compiled=compiled)
        certified = certified and not res.uncertified()
        if not res.feasible:
            feasible, worst = False, None
            worst_mu = tuple((c.name, float(c.mu)) for c in corner.contacts if c.mu is not None)
            break
        if res.tvmmp is not None and (worst is None or res.tvmmp < worst):
            worst = res.tvmmp
            worst_mu = tuple((c.name, float(c.mu)) for c in corner.contacts if c.mu is not None)
    return FrictionReport(
        margin=state.friction_margin,
        nominal_tvmmp=nominal,
        worst_tvmmp=worst,
        worst_feasible=feasible,
        worst_mu=worst_mu,
        corners=len(corners),
        certified=certified,
    )
