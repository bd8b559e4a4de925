r"""What the physics check simulates: the hand with DC motors, its contact types, the rollouts of a pair.

[`motor_model()`][mjtvm.physics.check.motor_model] gives a grasp's model a ``<dcmotor>`` on every
state joint (or actuator); [`contact_types()`][mjtvm.physics.check.contact_types] are the types the
simulated model gets ([`sim_model()`][mjtvm.physics.simulate.sim_model]);
[`pair_check()`][mjtvm.physics.check.pair_check] runs one pair (0, l): the bisection of
[`alpha_sim()`][mjtvm.physics.bisection.alpha_sim], the rollouts past it and at the check's scale,
the inertial torque the quasi-static LP leaves out and, on request, the launch and the dynamic
alpha ([`dynamic_row()`][mjtvm.physics.check.dynamic_row]). [`mjtvm.jobs.verify`][mjtvm.jobs.verify]
runs them over a lift's states and writes the rows.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from functools import partial
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError, SolverError
from mjtvm.model.state import GraspState
from mjtvm.physics.bisection import alpha_sim, monotone_flips
from mjtvm.physics.dynamic import dynamic_pair
from mjtvm.physics.feedforward import alpha_sim_ff
from mjtvm.physics.hold_drive import squeezed_drive
from mjtvm.physics.launch import launch_row
from mjtvm.physics.motors import actuator_model, attach_dcmotors, grasp_source, require_motors, same_model
from mjtvm.physics.simulate import SimSettings, inertial_demand, rollout
from mjtvm.physics.squeeze import SERVO_GAIN
from mjtvm.physics.verdict import ratio_cause, verdict
from mjtvm.physics.witness import witness_drive
from mjtvm.problem2.tvmmp import TvmmpResult

_F64 = NDArray[np.float64]

__all__ = ["contact_types", "dynamic_row", "motor_model", "pair_check"]

_MODELS: dict[int, tuple[Any, mujoco.MjModel]] = {}


def motor_model(grasp: Any) -> mujoco.MjModel:
    r"""The grasp's model with a ``<dcmotor>`` on every state joint, built once per grasp.

    With a transmission: a ``<dcmotor>`` per actuator instead, on the actuator's own
    transmission ([`actuator_motors()`][mjtvm.physics.motors.actuator_motors],
    [`attach_actuator_dcmotors()`][mjtvm.physics.motors.attach_actuator_dcmotors]).

    The model as is when each state joint already has one (``input="vel ff"``); otherwise
    the grasp's ``MjSpec`` (its MJCF file with the object and supports it adds) with the motors
    of ``grasp.motors`` attached
    ([`attach_dcmotors()`][mjtvm.physics.motors.attach_dcmotors]; [`require_motors()`][mjtvm.physics.motors.require_motors]
    refuses joints without motor data, naming them).

    Parameters
    ----------
    grasp
        A [`Grasp`][mjtvm.grasp.resolve.loaded.Grasp] (``model``, ``model_path``, ``joints``, ``motors``).

    Raises
    ------
    ModelError
        A joint or actuator without motor data.
    """
    if id(grasp) in _MODELS:
        return _MODELS[id(grasp)][1]
    _refuse_floating_base(grasp.model, grasp.joints)
    if getattr(grasp, "transmission", None) is not None:
        model = actuator_model(grasp)
        _MODELS[id(grasp)] = (grasp, model)
        return model
    model = grasp.model
    motors = require_motors(model, grasp.joints, getattr(grasp, "motors", {}))
    if motors:
        model = same_model(grasp, attach_dcmotors(grasp_source(grasp), motors))
    _MODELS[id(grasp)] = (grasp, model)  # the grasp is kept so that its id is not reused
    return model


def _refuse_floating_base(model: mujoco.MjModel, joints: Sequence[str]) -> None:
    """A hand on a free joint or a mocap body is refused: the rollouts rebuild the model from
    its file (a mocap pose is lost) and hold no base (a free base falls), so alpha_sim would
    measure another hand."""
    for name in joints:
        body = int(model.jnt_bodyid[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)])
        while body > 0:
            free = any(
                model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE
                for j in range(model.body_jntadr[body], model.body_jntadr[body] + model.body_jntnum[body])
            )
            if free or model.body_mocapid[body] >= 0:
                what = "on a free joint" if free else "a mocap body"
                label = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body)
                raise ModelError(
                    f"body {label!r}",
                    f"the hand's base is {what}: the physics check is for fixed-base hands "
                    "(export-state, solve, tvms and replay support it)",
                )
            body = int(model.body_parentid[body])


def contact_types(state: Any) -> dict[str, str]:
    """The contact type of every geom of the state, for [`sim_model()`][mjtvm.physics.simulate.sim_model].

    Parameters
    ----------
    state
        A [`GraspState`][mjtvm.model.state.GraspState] (its contacts' names may carry a ``#i``
        suffix: one geom's several contacts).

    Returns
    -------
    dict
        Geom name -> ``"F"``, ``"S"``, ``"L"`` or ``"D"``.
    """
    return {c.name.split("#")[0]: c.type for c in state.contacts}


def pair_check(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    res: TvmmpResult,
    l: int,
    *,
    settings: SimSettings | None,
    witness: str,
    object_body: str,
    check_s: float,
    dynamics: bool,
    launch_distance: float | None,
    squeeze: bool = False,
) -> dict[str, Any]:
    """The rollouts of pair (0, l), an optimal pair of ``res``: the columns of its check row.

    Parameters
    ----------
    model, qpos
        The simulated model ([`sim_model()`][mjtvm.physics.simulate.sim_model]) and the state's
        configuration.
    state, res
        The grasp state and its Problem 2 result (with witnesses).
    l
        The RVDS vertex.
    settings, witness, object_body
        As in [`alpha_sim()`][mjtvm.physics.bisection.alpha_sim].
    check_s
        The speed factor of the check's rollout (s times alpha_kl).
    dynamics
        Also the dynamic alpha and its check ([`dynamic_row()`][mjtvm.physics.check.dynamic_row]).
    launch_distance
        m: also the launch from rest ([`launch_row()`][mjtvm.physics.launch.launch_row]); ``None``: none.
    squeeze
        Every rollout drives the witness with the squeeze
        ([`squeezed_drive()`][mjtvm.physics.hold_drive.squeezed_drive]) and settles with the
        position loop (``SimSettings.servo`` = `SERVO_GAIN`): the hold drive ``squeeze``
        ([`mjtvm.physics.hold_drive`][mjtvm.physics.hold_drive]).

    Returns
    -------
    dict
        ``alpha_lp``, ``alpha_sim``, ``ratio``, ``verdict``, ``censored`` (s* at the
        bracket's end: ``below``, ``above``, else empty), ``monotone`` and ``flips``
        ([`monotone_flips()`][mjtvm.physics.bisection.monotone_flips]), ``evaluations``, the failing
        rollout's ``fail_reason`` and ``fail_clamp``, the check's ``pass_check``,
        ``check_reason``, the inertial demand's ``inertia_max`` and ``inertia_joint``, the
        check's ``settle_drift`` and limits, then the launch's and the dynamic columns, and
        the ratio's ``cause`` ([`ratio_cause()`][mjtvm.physics.verdict.ratio_cause]).
    """
    ob = object_body
    alpha = float(res.alpha[0, l])
    # The witness drive of pair (0, l) at a scale of alpha: in the bisection, past it, at the
    # check's scale, and at alpha itself for the inertial demand.
    make = squeezed_drive if squeeze else witness_drive
    drive = partial(make, state, 0, l, alpha, witness=witness, vertex=res.witnesses[0][l])  # type: ignore[arg-type]
    if squeeze:
        settings = replace(settings or SimSettings(), servo=SERVO_GAIN)
    a_sim, alpha, b = alpha_sim(
        model,
        qpos,
        state,
        0,
        l,
        result=res,
        settings=settings,
        witness=witness,  # type: ignore[arg-type]
        object_body=ob,
        drive=drive if squeeze else None,
    )
    top = min(b.value + 0.01, 2.0)
    fail = rollout(model, qpos, drive(top), settings=settings, object_body=ob)
    chk = rollout(model, qpos, drive(check_s), settings=settings, object_body=ob)
    flips = monotone_flips(
        b, lambda s: rollout(model, qpos, drive(s), settings=settings, object_body=ob).passed
    )
    one = drive(1.0)
    demand = inertial_demand(model, qpos, one, object_body=ob)
    j = int(np.argmax(demand))
    row: dict[str, Any] = {
        "alpha_lp": alpha,
        "alpha_sim": a_sim,
        "ratio": a_sim / alpha if alpha > 0 else math.nan,
        "verdict": verdict(b, fail, actuators=state.transmission is not None),
        "censored": "below" if b.below_bracket else "above" if b.above_bracket else "",
        "monotone": None if flips is None else not flips,
        "flips": "; ".join(flips or ()),
        "evaluations": b.evaluations,
        "fail_reason": fail.reason,
        "fail_clamp": fail.clamp_fraction,
        "pass_check": chk.passed,
        "check_reason": chk.reason,
        "inertia_max": float(demand[j]),
        "inertia_joint": state.joint_names[j],
        "settle_drift": chk.settle_drift,
        "limit_margin": chk.limit_margin,
        "limit_joint": chk.limit_joint,
        "limit_reached": chk.limit_reached,
    }
    if launch_distance is not None:
        row.update(launch_row(model, qpos, one, launch_distance, settings, ob))
    if dynamics:
        row.update(
            dynamic_row(
                model, qpos, state, l, res, alpha, a_sim, witness, settings, ob, check_s, squeeze=squeeze
            )
        )
    row["cause"] = ratio_cause(
        row["ratio"],
        row["verdict"],
        censored=row["censored"],
        limit_reached=bool(chk.limit_reached),
        inertia_max=row["inertia_max"],
        inertia_joint=row["inertia_joint"],
        ratio_dyn=row.get("ratio_dyn"),
    )
    return row


def dynamic_row(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    l: int,
    res: Any,
    alpha: float,
    a_sim: float,
    witness: str,
    settings: SimSettings | None,
    ob: str,
    check_s: float,
    *,
    squeeze: bool = False,
) -> dict[str, Any]:
    """The dynamic alpha of pair (0, l), its limit, alpha_sim / alpha_dyn and the check at
    ``check_s`` alpha_dyn (a rollout of the same drive at speed factor check_s alpha_dyn / alpha_kl;
    ``squeeze``: the squeeze's, as in [`pair_check()`][mjtvm.physics.check.pair_check], whose
    ``settings`` then have the loop).

    Parameters
    ----------
    model, qpos, state, l, res
        As in [`pair_check()`][mjtvm.physics.check.pair_check].
    alpha, a_sim
        The pair's alpha_kl and alpha_sim.
    witness, settings, ob, check_s
        The witness, the rollouts' settings, the object body and the check's speed factor.

    Returns
    -------
    dict
        ``alpha_dyn``, ``ratio_dyn``, ``dyn_joint``, ``dyn_term``, ``dyn_demand``, ``dyn_lps``,
        when alpha_dyn > 0 ``pass_check_dyn`` and ``check_dyn_reason``, and the second drive's
        ``alpha_sim_ff``, ``ratio_dyn_ff`` and ``ff_verdict`` (`_feedforward_columns()`).
    """
    st = settings or SimSettings()  # the demand along the span the rollout checks
    dyn = dynamic_pair(
        model,
        qpos,
        state,
        0,
        l,
        result=res,
        witness=witness,  # type: ignore[arg-type]
        object_body=ob,
        window=st.startup + st.window,
    )
    a = dyn.alpha
    out: dict[str, Any] = {
        "alpha_dyn": a,
        "ratio_dyn": a_sim / a if a > 0 else math.nan,
        "dyn_joint": _limit_names(state)[dyn.joint] if dyn.joint is not None else "",
        "dyn_term": dyn.term,
        "dyn_demand": float(np.max(np.abs(dyn.demand))),
        "dyn_lps": dyn.lps,
    }
    if a > 0:
        s = check_s * a / alpha
        chk = rollout(
            model,
            qpos,
            (squeezed_drive if squeeze else witness_drive)(
                state,
                0,
                l,
                alpha,
                s,
                witness=witness,  # type: ignore[arg-type]
                vertex=res.witnesses[0][l],
            ),
            settings=settings,
            object_body=ob,
        )
        out.update(pass_check_dyn=chk.passed, check_dyn_reason=chk.reason)
    if (
        squeeze and state.transmission is None
    ):  # the second drive has no squeeze: its least forces do not hold
        why = "not with the squeeze hold drive (its least forces do not hold the state)"
        out.update(alpha_sim_ff=math.nan, ratio_dyn_ff=math.nan, ff_verdict=why)
    else:
        out.update(_feedforward_columns(model, qpos, state, l, alpha, a, settings, ob))
    return out


def _feedforward_columns(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    l: int,
    alpha: float,
    a_dyn: float,
    settings: SimSettings | None,
    ob: str,
) -> dict[str, Any]:
    """``alpha_sim_ff``, ``ratio_dyn_ff`` and ``ff_verdict``: alpha_sim under the second drive
    ([`alpha_sim_ff()`][mjtvm.physics.feedforward.alpha_sim_ff]), nan with the reason where it
    has none (alpha_dyn = 0, a transmission, or a loaded witness the solvers did not solve)."""
    if a_dyn <= 0.0 or state.transmission is not None:
        why = "alpha_dyn = 0" if a_dyn <= 0.0 else "not available with a transmission (actuator forces)"
        return {"alpha_sim_ff": math.nan, "ratio_dyn_ff": math.nan, "ff_verdict": why}
    try:
        a_ff, b, fail = alpha_sim_ff(
            model, qpos, state, 0, l, alpha, a_dyn, settings=settings, object_body=ob
        )
    except SolverError as e:  # the loaded state's witness not solved: the row says so, the check goes on
        return {"alpha_sim_ff": math.nan, "ratio_dyn_ff": math.nan, "ff_verdict": f"no witness: {e}"}
    return {"alpha_sim_ff": a_ff, "ratio_dyn_ff": a_ff / a_dyn, "ff_verdict": verdict(b, fail)}


def _limit_names(state: GraspState) -> tuple[str, ...]:
    """What the operation ranges bound: the actuators with a transmission, else the joints."""
    t = state.transmission
    return state.joint_names if t is None else t.actuator_names
