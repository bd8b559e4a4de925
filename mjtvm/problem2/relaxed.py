r"""Problem 2 on a state whose operation ranges are enlarged: the LPs of the diagnosis.

[`binding_joints()`][mjtvm.problem2.relaxed.binding_joints] finds a minimal set of joints (or a
transmission's actuators) whose ranges, enlarged by [`RELAX`][mjtvm.problem2.relaxed.RELAX], make a pair work
(a deletion filter); [`binding_balance()`][mjtvm.problem2.relaxed.binding_balance] does so for "REFS vertex
k is balanced" and skips every LP whose answer a balance point already proves.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from mjtvm.model.state import GraspState
from mjtvm.problem2.assembly import BoxForm
from mjtvm.problem2.lps import StateLPs

__all__ = [
    "RELAX",
    "binding_balance",
    "binding_joints",
    "solve_pair",
    "solve_point",
    "strictly_inside",
    "with_relaxed",
]

RELAX = 100.0  # an enlarged operation range: the range scaled by this in torque and speed


def solve_pair(
    state: GraspState, w: NDArray[np.float64], r: NDArray[np.float64], box: BoxForm, solver: str
) -> tuple[str, float, NDArray[np.float64] | None]:
    """Status, alpha (0 within the solver's tolerance, as tvmmp reports it) and joint torques
    of Problem 2's pair (w, r); ``r = 0`` asks only whether ``w`` is balanced (alpha held at 0)."""
    status, alpha, tau, _ = solve_point(state, w, r, box, solver)
    return status, alpha, tau


def solve_point(
    state: GraspState, w: NDArray[np.float64], r: NDArray[np.float64], box: BoxForm, solver: str
) -> tuple[str, float, NDArray[np.float64] | None, tuple[NDArray[np.float64], dict[str, slice]] | None]:
    """`solve_pair()` and, when optimal, the LP's solution with its column blocks."""
    problem = StateLPs(state, box, solver)
    zero_twist = not np.any(r)
    verdict = problem.certified(w, r, alpha_max=0.0 if zero_twist else np.inf)
    if problem.session is not None:
        problem.session.release()
        problem.session = None
    sol = verdict.settled.solution
    if sol.status != "optimal" or sol.x is None:
        return sol.status, float("nan"), None, None
    alpha = float(sol.x[problem.alpha_col])
    alpha = 0.0 if zero_twist or alpha <= problem.zero_alpha(r) else alpha
    x = np.array(sol.x)
    return "optimal", alpha, x[problem.asm.blocks["tau[0]"]], (x, problem.asm.blocks)


#: How far inside its own range a joint's torque and speed must be (relative to the range's
#: half-plane offsets) for a balance point to prove that the joint's range need not be enlarged.
_INSIDE = 1e-6


def strictly_inside(state: GraspState, j: int, point: tuple[NDArray[np.float64], dict[str, slice]]) -> bool:
    """Whether the solution ``point`` of an eliminated-box LP keeps joint (or actuator) ``j``
    strictly inside its own operation range: every row ``c_tau tau + c_qd s (+ |c_tau| loss) <= b``
    of it (`range_rows_eliminated`) with a slack of more than `_INSIDE` b."""
    x, blocks = point
    tau = float(x[blocks["tau[0]"].start + j])
    qd = x[blocks["qd"]]
    t = state.transmission
    speed = float(qd[j]) if t is None else float(t.moment[j] @ qd)
    loss = float(x[blocks["loss"].start + j]) if "loss" in blocks else 0.0
    hp = state.operation_ranges[j].mirrored_halfplanes
    lhs = hp[:, 0] * tau + hp[:, 1] * speed + np.abs(hp[:, 0]) * loss
    return bool(np.all(lhs < hp[:, 2] * (1.0 - _INSIDE)))


def binding_balance(state: GraspState, w: NDArray[np.float64], box: BoxForm, solver: str) -> list[int] | None:
    """`binding_joints()` for "REFS vertex ``w`` is balanced", with the same answers in
    fewer LPs: a balance point the last feasible LP found that keeps joint j strictly inside
    its own range (`strictly_inside()`) also balances with j's range not enlarged, so that
    LP is not solved (its answer, feasible, is proven by the point). The deletion filter's
    order and every other answer are `solve_pair()`'s."""
    r = np.zeros(state.twist_dim)
    relaxed = set(range(len(state.operation_ranges)))
    status, _, _, point = solve_point(with_relaxed(state, relaxed), w, r, box, solver)
    if status != "optimal":
        return None
    for j in range(len(state.operation_ranges)):
        if box == "eliminated" and point is not None and strictly_inside(state, j, point):
            relaxed.discard(j)
            continue
        status, _, _, found = solve_point(with_relaxed(state, relaxed - {j}), w, r, box, solver)
        if status == "optimal":
            relaxed.discard(j)
            point = found
    return sorted(relaxed)


def with_relaxed(state: GraspState, relaxed: set[int]) -> GraspState:
    """``state`` with the operation ranges of the joints (or actuators) ``relaxed`` scaled by
    `RELAX` in torque and speed."""
    ranges = tuple(
        op.scaled(torque=RELAX, speed=RELAX) if j in relaxed else op
        for j, op in enumerate(state.operation_ranges)
    )
    return state.with_(operation_ranges=ranges)


def binding_joints(state: GraspState, works: Callable[[GraspState], bool]) -> list[int] | None:
    """A minimal set of joints whose enlarged ranges make ``works(state)`` true (deletion
    filter), or ``None`` when enlarging every range does not."""
    relaxed = set(range(len(state.operation_ranges)))  # the joints, or a transmission's actuators
    if not works(with_relaxed(state, relaxed)):
        return None
    for j in range(len(state.operation_ranges)):
        if works(with_relaxed(state, relaxed - {j})):
            relaxed.discard(j)
    return sorted(relaxed)
