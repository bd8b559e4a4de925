r"""Simulation of one dataset grasp (``mjtvm rank --verify``): the hold test and the speed test.

Per grasp ([`grasp_sim()`][mjtvm.physics.grasp_sim.grasp_sim]):

* **The hold test** ([`disturb_test()`][mjtvm.physics.disturb.disturb_test]): DexGraspBench's
  six pushes of 10 m/s^2 x the object's mass for 2 s (implicitfast at 1 ms:
  [`HOLD_SETTINGS`][mjtvm.physics.disturb.HOLD_SETTINGS]), held when the object moves less than
  5 cm and turns less than 15 deg along every direction, the hand held by the squeeze
  ([`squeeze_drive()`][mjtvm.physics.squeeze.squeeze_drive]) and its position loop (the
  protocol, its source and what differs: [`mjtvm.physics.disturb`][mjtvm.physics.disturb]).
* **The speed test**: for every RVDS direction l whose alpha_l = alpha_0l > 0, the witness
  rollout of ``mjtvm verify`` ([`rollout()`][mjtvm.physics.simulate.rollout], the central
  witness, its pass/fail criteria: twist within 10 % and 10 deg, no F-point slip, no contact
  lost, no motor at its saturation or more than 1 % past its speed edge) at s x alpha_l for s
  in [`SPEED_FACTORS`][mjtvm.physics.grasp_sim.SPEED_FACTORS], at the rollouts' settings (0.25 ms, the model's own integrator:
  at implicitfast 1 ms 9-71 % of the grasps change a rollout's verdict). The grasp's **speed success**:
  the prediction holds, i.e. the rollout at s = 0.8 passes along every direction with
  alpha_l > 0 (the predicted feasible speed, less the protocol's 20 % margin, is achieved).

The model ([`dataset_sim_model()`][mjtvm.physics.grasp_sim.dataset_sim_model]) is the grasp's
with the hand's DC motors attached ([`motor_model()`][mjtvm.physics.check.motor_model]'s
motors), the dataset grasp's object scale and the hand's posed base (a mocap body, fixed) put
back in, and the rollouts' settings ([`sim_model()`][mjtvm.physics.settings.sim_model]).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import mujoco
import numpy as np

from mjtvm.errors import ModelError, ParamError
from mjtvm.model.state import GraspState
from mjtvm.physics.check import contact_types
from mjtvm.physics.disturb import DISTURB_DURATION, HOLD_SETTINGS, DisturbResult, disturb_test
from mjtvm.physics.motors import (
    actuator_motors,
    attach_actuator_dcmotors,
    attach_dcmotors,
    grasp_source,
    require_motors,
    same_model,
)
from mjtvm.physics.settings import SimSettings, sim_model
from mjtvm.physics.simulate import SettleCache, rollout
from mjtvm.physics.squeeze import squeeze_drive
from mjtvm.physics.witness import Drive, WitnessProblem, witness_drive
from mjtvm.problem2.assembly import assemble

__all__ = [
    "SIM_COLUMNS",
    "SPEED_FACTORS",
    "dataset_sim_model",
    "faster_drive",
    "grasp_sim",
    "motorized_model",
    "protocol",
    "speed_key",
]

SPEED_FACTORS = (0.8, 1.0, 1.2)
"""The speed factors s of the speed test: the witness driven at s x alpha_l."""


def speed_key(s: float) -> str:
    """The column of the fraction of directions passing at ``s``: ``sim_speed_pass_08`` for 0.8."""
    return f"sim_speed_pass_{round(10 * s):02d}"


SIM_COLUMNS = (
    "sim_hold",
    "sim_hold_dirs",
    "sim_hold_translation",
    "sim_hold_rotation",
    *(speed_key(s) for s in SPEED_FACTORS),
    "sim_speed_dirs",
    "sim_speed_success",
    "sim_failure",
)
"""The columns [`grasp_sim()`][mjtvm.physics.grasp_sim.grasp_sim] fills, in order."""


def protocol() -> str:
    """The simulation protocol of [`grasp_sim()`][mjtvm.physics.grasp_sim.grasp_sim] as text:
    the speed test's and the hold test's settings and the constants that decide a verdict
    (the push, its checks and thresholds, the squeeze's share and loop gain, the speed
    factors). A run's rows hold only for the protocol that made them: ``rank --resume`` keeps a
    verified row only if this text has not changed (``inputs_digest``)."""
    from mjtvm.physics import disturb, squeeze

    constants = {
        "speed": SimSettings(),
        "hold": HOLD_SETTINGS,
        "hold_run": disturb.HOLD_RUN,
        "push": (disturb.DISTURB_ACCEL, DISTURB_DURATION, disturb.DISTURB_CHECK_EVERY),
        "thresholds": (disturb.DISTURB_TRANSLATION, disturb.DISTURB_ANGLE),
        "directions": disturb.DIRECTIONS,
        "squeeze": (squeeze.SQUEEZE_SHARE, squeeze.FRICTION_MARGINS, squeeze.TORSIONAL_FRICTION),
        "servo_gain": squeeze.SERVO_GAIN,
        "speed_factors": SPEED_FACTORS,
    }
    return "\n".join(f"{k} {v!r}" for k, v in constants.items())


def faster_drive(at_one: Drive, state: GraspState, l: int, alpha: float, s: float) -> Drive:
    r"""The central witness drive of direction ``l`` at ``s > 1`` from the one at ``s = 1``.

    Above 1, [`witness_drive()`][mjtvm.physics.witness.witness_drive] solves the same QP as at
    1 (at $\min(s, 1)\alpha$) and scales its joint and slip speeds by ``s``: the same numbers,
    without solving the QP again (``at_one`` is ``witness_drive(state, 0, l, alpha, 1.0)``).
    """
    if s <= 1.0:
        raise ParamError("s", f"expected a speed factor above 1, got {s!r}", s)
    if state.rvds is None:
        raise ParamError("state", "the state has no RVDS (state.rvds is None)")
    slips = {g: (rate * s, hat) for g, (rate, hat) in at_one.slips.items()}
    return replace(
        at_one,
        speeds=at_one.speeds * s,
        twist=s * alpha * np.asarray(state.rvds[l], float),
        slips=slips,
    )


def _refuse_free_base(model: mujoco.MjModel, joints: tuple[str, ...]) -> None:
    """A hand on a free joint falls in a rollout: refused. A mocap base is fixed (kept)."""
    for name in joints:
        body = int(model.jnt_bodyid[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)])
        while body > 0:
            adr, num = int(model.body_jntadr[body]), int(model.body_jntnum[body])
            if any(model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE for j in range(adr, adr + num)):
                raise ModelError(
                    "base", "the hand's base is on a free joint: the physics check holds no base"
                )
            body = int(model.body_parentid[body])


def motorized_model(grasp: Any, source: mujoco.MjSpec | None = None) -> mujoco.MjModel:
    """The grasp's model with the hand's DC motors attached (the first part of
    [`dataset_sim_model()`][mjtvm.physics.grasp_sim.dataset_sim_model]), compiled.

    ``source``: the ``MjSpec`` the grasp's model was compiled from (a dataset grasp's, with its
    object file: [`BatchModels.spec()`][mjtvm.grasp.resolve.batch.BatchModels.spec]); default
    the grasp file's (``grasp.spec()``). It depends only on the hand, the object file and the
    posed root, not on the grasp's joint values: one per (grasp file, object) serves every grasp.

    Raises
    ------
    ModelError
        A joint or actuator without motor data, a hand on a free joint, or a ``source`` that
        compiles to other bodies or geoms than ``grasp.model``'s.
    """
    gm = grasp.model
    _refuse_free_base(gm, tuple(grasp.joints))
    src = grasp_source(grasp) if source is None else source
    if getattr(grasp, "transmission", None) is not None:
        found = actuator_motors(grasp)
        return same_model(grasp, attach_actuator_dcmotors(src, found)) if found else gm
    motors = require_motors(gm, grasp.joints, getattr(grasp, "motors", {}))
    return same_model(grasp, attach_dcmotors(src, motors)) if motors else gm


def scale_free(grasp: Any) -> bool:
    """Whether the grasp's object has no mesh: its scale is all in its bodies' and geoms' poses,
    sizes and inertia, which [`dataset_sim_model()`][mjtvm.physics.grasp_sim.dataset_sim_model]
    copies from the grasp, so a motorized model of the object at another scale serves it."""
    gm = grasp.model
    ob = int(gm.body(grasp.object_body).id)
    inside = [b for b in range(gm.nbody) if b == ob or _inside(gm, b, ob)]
    mesh = int(mujoco.mjtGeom.mjGEOM_MESH)
    return not any(int(gm.geom_type[g]) == mesh for g in range(gm.ngeom) if int(gm.geom_bodyid[g]) in inside)


def dataset_sim_model(
    grasp: Any,
    state: GraspState,
    *,
    mu: float,
    mg: float,
    settings: SimSettings | None = None,
    motorized: mujoco.MjModel | None = None,
) -> mujoco.MjModel:
    """The model a dataset grasp's rollouts run on (module docstring).

    The motors are attached ([`motorized_model()`][mjtvm.physics.grasp_sim.motorized_model], or
    ``motorized`` when already built for the grasp's hand and object), and the grasp's own
    object (its bodies' and geoms' poses, sizes and inertia: the dataset's ``obj_scale``) and
    its mocap bodies' poses (the posed base) are copied from ``grasp.model`` and ``grasp.data``.

    Raises
    ------
    ModelError
        As `motorized_model()`, or an object whose meshes differ from the motorized model's
        (a dataset ``obj_path`` with the grasp file's spec as the source).
    """
    model = motorized_model(grasp) if motorized is None else motorized
    model = _with_grasp_geometry(model, grasp)
    return sim_model(
        model, contact_types(state), mu=mu, mg=mg, settings=settings, object_body=grasp.object_body
    )


def _with_grasp_geometry(model: mujoco.MjModel, grasp: Any) -> mujoco.MjModel:
    """A copy of ``model`` with the object subtree's geometry and the mocap poses of ``grasp``."""
    import copy

    gm, m = grasp.model, copy.deepcopy(model)
    if (gm.nmesh, gm.nmeshvert) != (m.nmesh, m.nmeshvert) or not np.array_equal(gm.mesh_vert, m.mesh_vert):
        raise ModelError(
            "obj_path",
            "the grasp's object mesh differs from the motorized model's: attach the motors to the "
            "grasp's own MjSpec (motorized_model(source=))",
        )
    ob = int(gm.body(grasp.object_body).id)
    bodies = [b for b in range(gm.nbody) if b == ob or _inside(gm, b, ob)]
    for name in ("body_pos", "body_quat", "body_ipos", "body_iquat", "body_mass", "body_inertia"):
        getattr(m, name)[bodies] = getattr(gm, name)[bodies]
    geoms = [g for g in range(gm.ngeom) if int(gm.geom_bodyid[g]) in bodies]
    for name in ("geom_size", "geom_pos", "geom_quat", "geom_rbound", "geom_aabb"):
        getattr(m, name)[geoms] = getattr(gm, name)[geoms]
    for b in range(gm.nbody):
        mid = int(gm.body_mocapid[b])
        if mid >= 0:
            m.body_pos[b] = grasp.data.mocap_pos[mid]
            m.body_quat[b] = grasp.data.mocap_quat[mid]
    d = mujoco.MjData(m)  # the subtree masses of the copied inertia
    mujoco.mj_setConst(m, d)
    return m


def _inside(model: mujoco.MjModel, body: int, top: int) -> bool:
    while body > 0:
        body = int(model.body_parentid[body])
        if body == top:
            return True
    return False


def grasp_sim(
    model: mujoco.MjModel,
    qpos: np.ndarray,
    state: GraspState,
    result: Any,
    *,
    object_body: str,
    settings: SimSettings | None = None,
    hold_settings: SimSettings = HOLD_SETTINGS,
    hold_duration: float | None = None,
) -> dict[str, Any]:
    """The hold test and the speed test of one grasp state (module docstring).

    Parameters
    ----------
    model, qpos
        From [`dataset_sim_model()`][mjtvm.physics.grasp_sim.dataset_sim_model], and the grasp's
        configuration.
    state, result
        The grasp state and its [`TvmmpResult`][mjtvm.problem2.tvmmp.TvmmpResult] with witnesses.
    settings
        The speed test's rollouts (default ``SimSettings()``: ``model``'s time step).
    hold_settings
        The hold test's simulation (default
        [`HOLD_SETTINGS`][mjtvm.physics.disturb.HOLD_SETTINGS]: implicitfast at 1 ms).
    hold_duration
        s each push acts (default the protocol's 2 s).

    Returns
    -------
    dict
        [`SIM_COLUMNS`][mjtvm.physics.grasp_sim.SIM_COLUMNS]: ``sim_hold`` (bool),
        ``sim_hold_dirs`` (directions held of 6), ``sim_hold_translation`` (m) and
        ``sim_hold_rotation`` (deg, the largest over the directions), per s the fraction of
        directions passing, ``sim_speed_dirs`` (directions with alpha_l > 0),
        ``sim_speed_success`` (bool, ``None`` without such a direction) and ``sim_failure``
        (what failed first, in words; ``""`` when everything passed).
    """
    st = settings or SimSettings()
    optimal = [l for l, status in enumerate(result.status[0]) if status == "optimal"]
    out: dict[str, Any] = dict.fromkeys(SIM_COLUMNS)
    if not optimal:
        out["sim_failure"] = "no optimal pair: no witness to drive"
        return out
    asm = assemble(state, horizon=True)  # one assembly for every witness of both tests
    qp = WitnessProblem(state, 0, assembly=asm)  # one QP set-up for every direction and speed
    rest = squeeze_drive(state, result, assembly=asm, problem=qp)  # not None: a pair is optimal
    assert rest is not None
    duration = DISTURB_DURATION if hold_duration is None else hold_duration
    hold: DisturbResult = disturb_test(
        model, qpos, rest, settings=hold_settings, object_body=object_body, duration=duration
    )
    out.update(
        sim_hold=hold.held,
        sim_hold_dirs=hold.held_count,
        sim_hold_translation=float(np.nanmax(hold.translation)),
        sim_hold_rotation=float(np.nanmax(hold.rotation)),
    )
    why = [] if hold.held else [f"hold: the object leaves the thresholds pushed along {hold.first_failure}"]
    moving = [l for l in optimal if float(result.alpha[0, l]) > 0.0]
    out["sim_speed_dirs"] = len(moving)
    passes = {s: 0 for s in SPEED_FACTORS}
    settled = SettleCache()  # the settles by drive, and one rig for all
    for l in moving:
        alpha = float(result.alpha[0, l])
        at_one: Drive | None = None  # the central witness solved at alpha_l (s = 1)
        for s in SPEED_FACTORS:
            if s > 1.0 and at_one is not None:
                drive = faster_drive(at_one, state, l, alpha, s)
            else:
                drive = witness_drive(state, 0, l, alpha, s, witness="central", problem=qp)
            if s == 1.0:
                at_one = drive
            # Only passed and reason are kept: the first violation decides both (exact stop).
            r = rollout(
                model, qpos, drive, settings=st, object_body=object_body, stop_early=True, settled=settled
            )
            passes[s] += bool(r.passed)
            if not r.passed and s == SPEED_FACTORS[0]:
                why.append(f"speed at {s:g} alpha, l = {l}: {r.reason}")
    for s in SPEED_FACTORS:
        out[speed_key(s)] = passes[s] / len(moving) if moving else None
    out["sim_speed_success"] = passes[SPEED_FACTORS[0]] == len(moving) if moving else None
    if not moving:
        why.append("no direction with alpha > 0: no speed to test")
    out["sim_failure"] = "; ".join(" ".join(w.split()) for w in why)
    return out
