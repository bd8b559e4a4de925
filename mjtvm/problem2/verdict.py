r"""The verdict of one Problem 2 LP: its settled answer, certified on the unscaled LP, or
solved again other ways until an answer is ([`other_ways()`][mjtvm.problem2.verdict.other_ways]).

[`StateLPs.conclude()`][mjtvm.problem2.lps.StateLPs.conclude] gives the LP as assembled and
its check ([`StateCertificates.check()`][mjtvm.problem2.certifying.StateCertificates.check]: the certificate of an
optimal answer, the Farkas multipliers of an infeasible one); what is tried and in what
order is decided here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np

from mjtvm.errors import SolverError
from mjtvm.lp.certificate import Certificate
from mjtvm.lp.lp import LPSolution
from mjtvm.lp.solvers import HighsSession, LinearProgram, Scaling, Settled, solve_clarabel

__all__ = ["Check", "Verdict", "other_ways"]

Check: TypeAlias = tuple[bool, Certificate | None] | None
"""``(certified, certificate)`` of an optimal or infeasible answer; ``None`` for an unbounded
one (no certificate)."""


@dataclass(frozen=True, eq=False)
class Verdict:
    """A settled LP, the certificate of its optimal answer (``None`` otherwise), and whether
    the answer is certified (optimal: its certificate holds; infeasible: Farkas multipliers
    prove it; unbounded: a second solve agrees)."""

    settled: Settled
    certificate: Certificate | None
    certified: bool


def other_ways(
    settled: Settled, cert: Check, lp: LinearProgram, check: Callable[[LPSolution], Check]
) -> Verdict:
    """The verdict of an LP whose settled answer ``settled`` failed its check ``cert``.

    The LP as assembled, ``lp``, is solved again other ways, in turn: HiGHS from a cold start
    on its own equilibration, Clarabel, and HiGHS on ``lp`` unequilibrated; each answer is
    checked by ``check``, and the first certified one is reported, with a note. If none is,
    the first answer is reported with a note naming what failed, and ``certified`` False. An
    unbounded verdict (no certificate) is confirmed by a second solve's.
    """
    first = settled.solution
    tried = [f"{settled.solver}: {_describe(first, cert)}"]
    ones = Scaling(np.ones(lp.A.shape[0]), np.ones(lp.A.shape[1]), 1.0)
    ways = (
        ("highs (cold)", "highs", lambda: HighsSession(lp).solve(duals=True)),
        ("clarabel", "clarabel", lambda: solve_clarabel(lp)),
        ("highs (own scaling)", "highs", lambda: HighsSession(lp, scaling=ones).solve(duals=True)),
    )
    for name, solver, run in ways:
        try:
            other = run()
        except SolverError as e:
            tried.append(f"{name}: {e.status}")
            continue
        c2 = check(other)
        if first.status == "unbounded" and other.status == "unbounded":
            return Verdict(settled, None, True)  # confirmed by a second solve
        if c2 is not None and c2[0]:
            note = f"{settled.solver}'s answer ({first.status}) not certified ({_describe(first, cert)}); certified by {name}: {other.status}"
            return Verdict(Settled(other, solver, _join(settled.note, note)), c2[1], True)
        tried.append(f"{name}: {_describe(other, c2)}")
    note = "not certified: " + "; ".join(tried)
    return Verdict(
        Settled(first, settled.solver, _join(settled.note, note)),
        None if cert is None else cert[1],
        False,
    )


def _describe(sol: LPSolution, check: Check) -> str:
    """What a failed check of ``sol`` found, in a few words."""
    if sol.status == "optimal" and check is not None and check[1] is not None:
        return check[1].describe()
    if sol.status == "infeasible":
        return "infeasible without Farkas multipliers that prove it"
    return f"{sol.status} (not certified by itself)"


def _join(a: str | None, b: str) -> str:
    return b if a is None else f"{a}; {b}"
