r"""The state the physics check solves at a lift state, its Problem 2 and what differs from ``mjtvm solve``'s.

[`verify_lp()`][mjtvm.jobs.verify_lp.verify_lp] gives [`verify_state()`][mjtvm.jobs.verify.verify_state]
its grasp state, the LP's result (alpha_kl, before any rollout) and the row's ``lp_state`` and
``lp_note``; [`pair_reason()`][mjtvm.jobs.verify_lp.pair_reason] says why a pair has no alpha.
No MuJoCo rollout runs here.
"""

from __future__ import annotations

from dataclasses import replace

from mjtvm.errors import MjtvmError
from mjtvm.lift.states import lift_state
from mjtvm.lift.trajectory import Lift
from mjtvm.model.limits import with_limit_horizon
from mjtvm.model.state import GraspState
from mjtvm.problem2.tvmmp import TvmmpResult, tvmmp

__all__ = ["pair_reason", "verify_lp"]


def verify_lp(
    lift: Lift,
    index: int,
    run: str,
    *,
    mu: float,
    mg: float,
    preload: float = 0.0,
    friction_margin: float | None = None,
    limit_horizon: float | None = None,
) -> tuple[GraspState, TvmmpResult | MjtvmError, dict[str, str]]:
    r"""The state [`verify_state()`][mjtvm.jobs.verify.verify_state] checks at lift state ``index`` for ``run``, its Problem 2
    (``alpha_lp``, without a rollout) and the row's ``lp_state`` and ``lp_note``.

    State 0 is the grasp at its own configuration (the lift starts there): with the grasp's
    friction and weight (``mu``, ``mg`` its own), the file's contact types and no
    ``preload``, the state is the one ``mjtvm solve GRASP`` solves and its alphas are solve's
    (``lp_state`` ``grasp``, ``lp_note`` empty). Otherwise ``lp_note`` says what differs from
    solve's state and why: a state further along the lift (``lp_state`` ``lift``), another
    ``mu`` or ``mg`` (``--mu``, ``--mg``), the L contacts' preload (``--preload``), the
    contacts the run retypes, a ``friction_margin`` (the state's, on the rollouts' cone) other
    than the grasp's, a ``limit_horizon`` (``--limit-horizon``) other than the state's. The LP is solved on the initial configuration, never on the
    settled one of the hold test or a rollout (those move the object by at most
    ``hold_reach``).

    Returns
    -------
    state, result, fields
        The grasp state, its [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp] result (with the diagnosis of
        its infeasible pairs and zero alphas), or the error the LP ended in, and
        ``{"lp_state": ..., "lp_note": ...}``.
    """
    variant, _, reading = run.partition("-")
    sc = lift.scenario
    own_mg = getattr(sc, "weight_mg", None)  # the grasp's own weight: its REFS as they are (solve's)
    state = lift_state(
        lift,
        index,
        variant=variant,  # type: ignore[arg-type]
        reading=reading or "physical",  # type: ignore[arg-type]
        mu=mu,
        mg=None if own_mg is not None and mg == own_mg else mg,
    )
    if preload > 0:
        state = state.with_(
            contacts=tuple(replace(c, preload=preload) if c.type == "L" else c for c in state.contacts)
        )
    own_margin = state.friction_margin
    if friction_margin is not None:
        state = state.with_(friction_margin=friction_margin)
    own_limits = state.joint_limits
    state = with_limit_horizon(state, limit_horizon)
    notes = []
    if index > 0 or float(lift.s[index]) != 0.0:
        notes.append(
            f"the lift's state {index} (s = {float(lift.s[index]):.6g} m), not the grasp's configuration"
        )
    if mu != getattr(sc, "default_mu", None):
        notes.append(f"mu {mu:g} (--mu), not the grasp's")
    if mg != own_mg:
        notes.append(f"mg {mg:g} N (--mg), not the grasp's weight")
    if preload > 0:
        notes.append(f"preload {preload:g} N on the L contacts (--preload)")
    if state.friction_margin != own_margin:
        notes.append(
            f"friction margin {state.friction_margin:g} (--friction-margin on the rollouts' cone), "
            f"not the grasp's {own_margin:g}"
        )
    if (
        own_limits is not None
        and state.joint_limits is not None
        and state.joint_limits.horizon != own_limits.horizon
    ):
        notes.append(
            f"joint-limit horizon {state.joint_limits.horizon:g} m (--limit-horizon), "
            f"not the grasp's {own_limits.horizon:g}"
        )
    own = getattr(sc, "contact_types", {})
    retyped = sorted(
        {c.name.split("#")[0] for c in state.contacts if own.get(c.name.split("#")[0], c.type) != c.type}
    )
    if retyped:
        notes.append(f"run {run} types {', '.join(retyped)} {variant}, the grasp file otherwise")
    fields = {"lp_state": "grasp" if index == 0 else "lift", "lp_note": "; ".join(notes)}
    try:
        return state, tvmmp(state, diagnose=True), fields
    except MjtvmError as e:
        return state, e, fields


def pair_reason(res: TvmmpResult, l: int) -> str:
    """Why pair (0, l) is infeasible or its alpha 0 (the diagnosis ``mjtvm solve`` prints)."""
    for d in res.diagnosis:
        if d.pair[0] == 0 and d.pair[1] in (l, -1):
            return d.message
    return ""
