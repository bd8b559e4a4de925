r"""MuJoCo rollouts of TVMMP witnesses: is $s\,\alpha_{kl}\hat r_l$ physically achievable?

A rollout drives the hand with MuJoCo's own ``<dcmotor>`` actuators (``input="vel ff"``:
velocity setpoint in actuator-length units, i.e. joint speed x gear, plus a torque
feedforward; drive voltage clamped at Vmax; motor torque clamped at the continuous torque),
so the speed-torque line, the torque saturation and the rotor inertia are MuJoCo's motor
physics. The object is free under gravity. Protocol (``docs/physics-check.md``):

1. *Model* ([`sim_model()`][mjtvm.physics.simulate.sim_model]): a copy of the lift's model with elliptic friction cones,
   contact ``solref = (2 ms, 1)``, ``impratio = 10``, a 0.25 ms step; finger geoms take
   priority in contact mixing: F- and S-geoms get friction ``mu`` (condim 3), L-geoms and the
   base D-geom are frictionless (condim 1), other finger geoms keep ``mu``.
2. *Drive* (`witness_drive()`): the witness of pair (k, l) at speed factor ``s``: joint
   speeds $s\,\dot q^*$, feedforward torques $\tau^*$ (eq. 19) plus the joints'
   own damping and friction loss at the commanded speeds (zero on the paper's hand), object twist
   $s\alpha_{kl}\hat r_l$. The ``"central"`` witness (default) re-solves the
   constraints of eq. (31) at $\alpha = \min(s, 1)\alpha_{kl}$ minimising
   $\sum_j (\dot q_j/\omega_{0j})^2 + \sum_e (\lambda_e/|w_k|)^2$ (least joint motion,
   forces inside the pyramids); above 1 its speeds are scaled. ``"vertex"`` scales the
   simplex witness of [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp] (Supplement 1).
3. *Settle* (``settle`` s): setpoints 0, feedforward $\tau^*$, from the lift state's
   ``qpos`` at rest: the fingers hold the object with the witness forces.
4. *Start* (impulsive): joint and object velocities are set to the drive's (they satisfy
   eq. 7-13), since accelerating the reflected rotor inertia (gear^2 x rotor) to TVMMP
   speeds takes about 0.1 s and several cm of travel with the torque left over.
5. *Run* (``startup + window`` s): with ``track`` the speed setpoints are corrected every
   step by the least-norm change that keeps each finger's contact velocity consistent with
   the drive's twist at the current configuration (eq. 7 rows for F, the normal row of eq. 8
   for L, eq. 7 minus the witness slip for S), so that the kinematic drift of constant joint
   speeds in a moving configuration is not mistaken for a motor limit.

Failure ([`RolloutResult`][mjtvm.physics.simulate.RolloutResult]), at any step of the window: the twist $[v; R\omega]$
(R the object's bounding radius, [`Rig`][mjtvm.physics.rig.Rig]) off $s\alpha\hat r_l$
by more than ``speed_tol`` in magnitude or ``angle_tol`` degrees in direction; an F-point's accumulated
tangential slip above ``slip_tol`` x the object's travel (+ ``slip_floor``); a finger geom
more than ``lost_gap`` from the object; a motor torque at its saturation.

Any hand: the model needs one ``<dcmotor>`` per state joint (found by its transmission;
[`mjtvm.physics.motors`][mjtvm.physics.motors] attaches them to a hand with servos), or, for a state with a
transmission, one per actuator on the actuator's own joint or tendon (found by name; the
drive's actuator forces fed forward, its actuator speeds the setpoints, ``docs/physics-check.md``), finger geoms are keyed by
label (`geom_label()`), and contact points come from
``mj_geomDistance``, so fingertips and objects need not be spheres.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError, ParamError
from mjtvm.grasp.resolve.state import geom_id
from mjtvm.physics.rig import Rig, finger_contacts, twist_errors
from mjtvm.physics.witness import Drive

__all__ = [
    "RolloutResult",
    "SimSettings",
    "held",
    "inertial_demand",
    "rerun_data",
    "rollout",
    "settle",
    "sim_model",
]

_F64 = NDArray[np.float64]


@dataclass(frozen=True)
class SimSettings:
    r"""Simulation and pass/fail settings (module docstring; SI units, angles in degrees).

    ``armature_scale`` scales the actuators' rotor inertia and ``inertial_ff`` adds the
    computed inertial and Coriolis torques of the tracked setpoints to the feedforward:
    both are ablations of the quasi-static assumption, off by default.
    """

    timestep: float = 2.5e-4
    cone: Literal["elliptic", "pyramidal"] = "elliptic"
    solref: tuple[float, float] = (0.002, 1.0)
    solimp: tuple[float, float, float, float, float] = (0.9, 0.95, 0.001, 0.5, 2.0)
    impratio: float = 10.0
    settle: float = 0.03
    startup: float = 0.002
    window: float = 0.005
    track: bool = True
    inertial_ff: bool = False
    armature_scale: float = 1.0
    speed_tol: float = 0.10
    angle_tol: float = 10.0
    slip_tol: float = 0.05
    slip_floor: float = 1e-5
    lost_gap: float = 5e-4

    def __post_init__(self) -> None:
        for name in (
            "timestep",
            "settle",
            "startup",
            "window",
            "speed_tol",
            "angle_tol",
            "slip_tol",
            "slip_floor",
            "lost_gap",
            "impratio",
            "armature_scale",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0) or (name in ("timestep", "window") and value == 0):
                raise ParamError(name, f"expected a finite number >= 0, got {value!r}", value)
        if self.cone not in ("elliptic", "pyramidal"):
            raise ParamError("cone", f"expected 'elliptic' or 'pyramidal', got {self.cone!r}", self.cone)

    def steps(self, seconds: float) -> int:
        return round(seconds / self.timestep)


def sim_model(
    model: mujoco.MjModel,
    contact_types: Mapping[str, str],
    *,
    mu: float,
    mg: float | None = None,
    object_body: str = "object",
    settings: SimSettings | None = None,
) -> mujoco.MjModel:
    r"""A copy of ``model`` set up for rollouts (step 1 of the module docstring).

    Parameters
    ----------
    model
        A model whose state joints each have one ``<dcmotor>`` with ``input="vel ff"``
        ([`attach_dcmotors()`][mjtvm.physics.motors.attach_dcmotors] gives any hand those).
    contact_types
        Geom label (`geom_label()`: its name, or ``"<body>/geom<n>"``
        when unnamed) -> ``"F"``, ``"L"``, ``"S"`` or ``"D"`` (a state's contacts). Geoms
        not listed: ``"D"`` on the world body, else ``"F"``.
    mu
        Coulomb coefficient of the F- and S-geoms (and of finger geoms not listed).
    mg
        Object weight (N); the object body's mass and inertia are scaled to it. Default: as is.

    Raises
    ------
    ModelError
        Unknown object body or a contact-type key that is no geom of the model.
    """
    st = settings or SimSettings()
    m = copy.deepcopy(model)
    m.opt.timestep = st.timestep
    m.opt.cone = int(
        mujoco.mjtCone.mjCONE_ELLIPTIC if st.cone == "elliptic" else mujoco.mjtCone.mjCONE_PYRAMIDAL
    )
    m.opt.impratio = st.impratio
    m.actuator_armature[:] *= st.armature_scale
    ob = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, object_body)
    if ob < 0:
        raise ModelError(f"body {object_body!r}", "not in the model")
    if mg is not None:
        if not (math.isfinite(mg) and mg > 0):
            raise ParamError("mg", f"expected a positive weight (N), got {mg!r}", mg)
        g = float(np.linalg.norm(m.opt.gravity))  # the weight along the model's gravity, as the REFS
        if g == 0.0 or float(m.body_mass[ob]) == 0.0:
            raise ParamError(
                "mg",
                "the object has no weight to scale (the model's gravity or the object's mass is 0): "
                'give the model a gravity (<option gravity="0 0 -9.81"/>) and the object a mass',
            )
        scale = mg / (float(m.body_mass[ob]) * g)
        m.body_mass[ob] *= scale
        m.body_inertia[ob] *= scale
    kinds = {geom_id(m, label, "contact_types geom"): kind for label, kind in contact_types.items()}
    inside = {ob}
    for b in range(ob + 1, m.nbody):  # parents precede children: the object's subtree
        if int(m.body_parentid[b]) in inside:
            inside.add(b)
    for g in range(m.ngeom):
        m.geom_solref[g] = st.solref
        m.geom_solimp[g] = st.solimp
        if int(m.geom_bodyid[g]) in inside:
            continue
        kind = kinds.get(g, "D" if int(m.geom_bodyid[g]) == 0 else "F")
        m.geom_priority[g] = 1  # the finger's (palm's) parameters decide the contact
        m.geom_condim[g] = 3 if kind in ("F", "S") else 1
        m.geom_friction[g] = (mu, 0.005, 0.0001)
    return m


# ------------------------------------------------------------------ witnesses
@dataclass(frozen=True, eq=False)
class RolloutResult:
    r"""Outcome of one rollout (maxima over the window).

    Attributes
    ----------
    passed, reason
        Whether every criterion held; the first violation (``""`` when passed).
    speed_error, angle_error
        Largest $|\,|\dot r|/|\dot r^*| - 1|$ and direction error (deg) of [v; R omega].
    slip_ratio
        Largest F-point slip over the window divided by its tolerance (1 = at tolerance).
    gap
        Largest finger-object distance (m; negative = penetration throughout).
    saturated
        Joints (actuators, with a transmission) whose motor reached its torque saturation.
    clamp_fraction
        Fraction of (step, motor) pairs with the drive voltage at Vmax (speed-torque line).
    settle_drift
        Object displacement during the settle phase (m).
    friction
        Per L/S geom: its mean tangential force on the object (N) and the mean slip of the
        object's contact point relative to the finger's (m/s) over the window, world frame.
    joints
        The driven joints (the column order of the trace's ``qvel`` and ``torque``, the joint
        torques ``qfrc_actuator`` with a transmission).
    limit_margin, limit_joint
        The smallest distance of a driven joint to either end of its ``jnt_range``, less its
        ``jnt_margin`` (rad or m), over the run (startup and window), and that joint: 0 or
        below, MuJoCo's limit constraint engages. ``inf`` and ``""`` when no driven joint is
        limited.
    failure
        The first violation's kind (``"twist magnitude"``, ``"twist direction"``, ``"moves at
        rest"``, ``"slip"``, ``"contact lost"``, ``"torque limit"``; ``""`` when passed) and
        where (the geom, or the saturated joints or actuators; ``""`` for the twist).
    trace
        Per-step arrays when requested ([`rerun_data()`][mjtvm.physics.simulate.rerun_data]), else empty.
    """

    passed: bool
    reason: str
    speed_error: float
    angle_error: float
    slip_ratio: float
    gap: float
    saturated: tuple[str, ...]
    clamp_fraction: float
    settle_drift: float
    friction: Mapping[str, tuple[_F64, _F64]]
    joints: tuple[str, ...] = ()
    failure: tuple[str, str] = ("", "")
    trace: Mapping[str, _F64] = field(default_factory=dict, repr=False)
    limit_margin: float = math.inf
    limit_joint: str = ""

    @property
    def limit_reached(self) -> bool:
        """Whether a driven joint reached its limit in the run (`limit_margin` <= 0)."""
        return self.limit_margin <= 0.0


def held(m: mujoco.MjModel, qpos: _F64, rig: Rig, drive: Drive) -> mujoco.MjData:
    """New data at ``qpos``, the drive's feed-forward torques applied (after ``mj_forward``):
    where a rollout settles and the hold test ([`hold`][mjtvm.physics.hold]) starts."""
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    if rig.coupled:  # the motors' ratio to the state's moment rows, at the state
        mujoco.mj_forward(m, d)
        rig.bind(d, drive)
    d.ctrl[rig.cadr] = 0.0
    d.ctrl[rig.cadr + 1] = rig.hold_torques(drive) / rig.gear
    mujoco.mj_forward(m, d)
    return d


def settle(
    m: mujoco.MjModel, qpos: _F64, rig: Rig, drive: Drive, st: SimSettings
) -> tuple[mujoco.MjData, float]:
    """Step 3: the configuration ``qpos`` held by the drive's feed-forward torques for the settle
    time; returns the data and how far the object drifted (m)."""
    d = held(m, qpos, rig, drive)
    p0 = d.xpos[rig.ob].copy()
    if st.steps(st.settle):
        mujoco.mj_step(m, d, nstep=st.steps(st.settle))
    return d, float(np.linalg.norm(d.xpos[rig.ob] - p0))


def _joint_ranges(m: mujoco.MjModel, joints: tuple[str, ...]) -> tuple[_F64, _F64, _F64, _F64]:
    """Of the limited ``joints`` (hinge or slide): their indices in ``joints``, ``qpos``
    addresses, and their ranges narrowed by ``jnt_margin``, where MuJoCo's limit engages."""
    idx, adr, lo, hi = [], [], [], []
    for i, name in enumerate(joints):
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        if (
            j < 0
            or not m.jnt_limited[j]
            or int(m.jnt_type[j]) not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
        ):
            continue
        idx.append(i)
        adr.append(int(m.jnt_qposadr[j]))
        lo.append(float(m.jnt_range[j, 0] + m.jnt_margin[j]))
        hi.append(float(m.jnt_range[j, 1] - m.jnt_margin[j]))
    return np.array(idx, dtype=int), np.array(adr, dtype=int), np.array(lo), np.array(hi)


def _start(d: mujoco.MjData, rig: Rig, drive: Drive, st: SimSettings) -> None:
    """Step 4: the object at the drive's twist, the joints at their (tracked) speeds, all else at rest."""
    fa, tw = rig.fadr, drive.twist
    d.qvel[:] = 0.0
    d.qvel[fa : fa + 3] = tw[:3]
    d.qvel[fa + 3 : fa + 6] = d.xmat[rig.ob].reshape(3, 3).T @ tw[3:]
    d.qvel[rig.dofs] = rig.setpoints(d, drive) if st.track else drive.speeds


def rollout(
    model: mujoco.MjModel,
    qpos: _F64,
    drive: Drive,
    *,
    settings: SimSettings | None = None,
    object_body: str = "object",
    record: bool = False,
) -> RolloutResult:
    r"""Settle, start and run one drive from ``qpos`` (module docstring, steps 3-5).

    ``model`` comes from [`sim_model()`][mjtvm.physics.simulate.sim_model]. ``record`` keeps per-step arrays (``trace``).
    """
    st = settings or SimSettings()
    rig, m = Rig(model, drive, object_body), model
    if rig.coupled and st.inertial_ff:
        raise ParamError(
            "inertial_ff", "not available for a hand with a transmission (joint torques, not actuator forces)"
        )
    d, drift = settle(m, qpos, rig, drive, st)
    _start(d, rig, drive, st)
    fa, tw = rig.fadr, drive.twist
    target = np.r_[tw[:3], rig.radius * tw[3:]]
    tnorm = float(np.linalg.norm(target))
    n0, n1 = st.steps(st.startup), st.steps(st.startup) + st.steps(st.window)
    travel = tnorm * st.steps(st.window) * st.timestep
    slip_tol = st.slip_tol * travel + st.slip_floor
    slip = dict.fromkeys((f[0] for f in rig.fingers if f[4] == "F"), 0.0)
    fsum = {f[0]: np.zeros(3) for f in rig.fingers if f[4] != "F"}
    ssum = {f[0]: np.zeros(3) for f in rig.fingers if f[4] != "F"}
    worst = {"speed": 0.0, "angle": 0.0, "gap": -np.inf}
    saturated: set[str] = set()
    clamped, reason, gap_geom, failure = 0, "", "", ["", ""]
    trace: dict[str, list[Any]] = {k: [] for k in ("time", "object_pos", "twist", "qvel", "torque", "gap")}
    f6, pred = np.zeros(6), mujoco.MjData(m) if st.inertial_ff else None
    names = drive.actuators or drive.joints
    lim_idx, lim_adr, lim_lo, lim_hi = _joint_ranges(m, drive.joints)
    lim_margin, lim_joint = math.inf, ""
    for step in range(n1):
        qset = rig.setpoints(d, drive) if st.track else drive.speeds
        sp, ff = rig.controls(d, drive, qset)
        if st.inertial_ff and pred is not None:
            ff += _inertial(m, d, pred, rig, drive, qset)
        d.ctrl[rig.cadr] = sp
        d.ctrl[rig.cadr + 1] = ff / rig.gear
        mujoco.mj_step(m, d)
        if len(lim_adr):  # over the startup too: the joints move from the start
            q = d.qpos[lim_adr]
            room = np.minimum(q - lim_lo, lim_hi - q)
            near = int(np.argmin(room))
            if room[near] < lim_margin:
                lim_margin, lim_joint = float(room[near]), drive.joints[lim_idx[near]]
        if step < n0:
            continue
        lvel = d.actuator_velocity[rig.acts]
        tau_cmd = rig.kd * (sp - lvel) + ff / rig.gear
        clamped += int(np.sum(np.abs(rig.r_k / rig.kt * tau_cmd + rig.kt * lvel) > rig.vmax * (1 + 1e-9)))
        force = d.actuator_force[rig.acts]
        for j in np.nonzero(np.abs(force) >= rig.fmax * (1 - 1e-9))[0]:
            saturated.add(names[j])
        v = d.qvel[fa : fa + 3]
        om = d.xmat[rig.ob].reshape(3, 3) @ d.qvel[fa + 3 : fa + 6]
        now = np.r_[v, rig.radius * om]
        twist_errors(worst, now, target, tnorm)
        gaps = finger_contacts(m, d, rig, st.timestep, slip, ssum, fsum, f6)
        if max(gaps) > worst["gap"]:
            worst["gap"], gap_geom = max(gaps), rig.fingers[int(np.argmax(gaps))][0]
        if record:
            for key, val in (
                ("time", d.time),
                ("object_pos", d.xpos[rig.ob].copy()),
                ("twist", now.copy()),
                ("qvel", d.qvel[rig.dofs].copy()),
                ("torque", d.qfrc_actuator[rig.dofs].copy() if rig.coupled else force * rig.gear),
                ("gap", gaps),
            ):
                trace[key].append(val)
        if not reason:
            reason, *failure = _violation(st, worst, slip, slip_tol, saturated, tnorm, gap_geom)
            if reason:
                reason = f"{reason} at t = {1e3 * (step + 1 - n0) * st.timestep:.2f} ms"
    nwin = max(1, n1 - n0)
    friction = {g: (fsum[g] / nwin, ssum[g] / nwin) for g in fsum}
    return RolloutResult(
        passed=not reason,
        reason=reason,
        speed_error=worst["speed"],
        angle_error=worst["angle"],
        slip_ratio=max(slip.values(), default=0.0) / slip_tol,
        gap=float(worst["gap"]),
        saturated=tuple(sorted(saturated)),
        clamp_fraction=clamped / max(1, (n1 - n0) * len(rig.acts)),
        settle_drift=drift,
        friction=friction,
        joints=drive.joints,
        failure=(failure[0], failure[1]),
        trace={k: np.array(v, dtype=float) for k, v in trace.items()} if record else {},
        limit_margin=lim_margin,
        limit_joint=lim_joint,
    )


def _violation(
    st: SimSettings,
    worst: dict[str, float],
    slip: dict[str, float],
    slip_tol: float,
    saturated: set[str],
    tnorm: float,
    gap_geom: str,
) -> tuple[str, str, str]:
    """The first violated criterion as (text, kind, where) ([`RolloutResult.failure`][mjtvm.physics.simulate.RolloutResult.failure])."""
    if tnorm > 0 and worst["speed"] > st.speed_tol:
        return f"twist magnitude off by {100 * worst['speed']:.1f} %", "twist magnitude", ""
    if tnorm == 0 and worst["speed"] > st.slip_floor / max(st.window, 1e-12):
        return f"object moves at {worst['speed']:.3g} m/s", "moves at rest", ""
    if worst["angle"] > st.angle_tol:
        return f"twist direction off by {worst['angle']:.1f} deg", "twist direction", ""
    for geom, dist in slip.items():
        if dist > slip_tol:
            return f"{geom} slips {1e3 * dist:.3f} mm", "slip", geom
    if worst["gap"] > st.lost_gap:
        return f"contact lost ({gap_geom} {1e3 * worst['gap']:.2f} mm)", "contact lost", gap_geom
    if saturated:
        names = ", ".join(sorted(saturated))
        return f"torque saturated ({names})", "torque limit", names
    return "", "", ""


def _inertial(
    m: mujoco.MjModel, d: mujoco.MjData, pred: mujoco.MjData, rig: Rig, drive: Drive, qset: _F64
) -> _F64:
    """Computed torque of the tracked setpoints: M qdd (one-step prediction) + Coriolis (ablation)."""
    pred.qpos[:] = d.qpos
    mujoco.mj_integratePos(m, pred.qpos, d.qvel, m.opt.timestep)
    mujoco.mj_kinematics(m, pred)
    mujoco.mj_comPos(m, pred)
    acc = np.zeros(m.nv)
    acc[rig.dofs] = (rig.setpoints(pred, drive) - qset) / m.opt.timestep
    out = np.zeros(m.nv)
    mujoco.mj_mulM(m, d, out, acc)
    return np.asarray((out + d.qfrc_bias - _gravity(m, pred, d.qpos))[rig.dofs], dtype=float)


def _gravity(m: mujoco.MjModel, scratch: mujoco.MjData, qpos: _F64) -> _F64:
    """Gravity part of ``qfrc_bias`` at ``qpos`` (RNE at zero velocity, on ``scratch``)."""
    scratch.qpos[:] = qpos
    scratch.qvel[:] = 0.0
    mujoco.mj_kinematics(m, scratch)
    mujoco.mj_comPos(m, scratch)
    mujoco.mj_comVel(m, scratch)
    out = np.zeros(m.nv)
    mujoco.mj_rne(m, scratch, 0, out)
    return out


def inertial_demand(
    model: mujoco.MjModel, qpos: _F64, drive: Drive, *, duration: float = 0.005, object_body: str = "object"
) -> _F64:
    r"""``(M,)`` largest joint torque (N m) that inertia and Coriolis forces add along the ideal motion.

    The drive's motion (tracked setpoints, object at the drive's twist) is integrated
    kinematically for ``duration``; the torque is $M(q)\ddot q + c(q, \dot q)$ on the
    driven joints (rotor inertia included, object excluded): what the quasi-static TVMMP
    (eq. 19) leaves out.
    """
    m, d, scratch = model, mujoco.MjData(model), mujoco.MjData(model)
    rig = Rig(m, drive, object_body)
    d.qpos[:] = qpos
    dt, fa, worst = m.opt.timestep, rig.fadr, np.zeros(len(drive.joints))
    mujoco.mj_forward(m, d)
    qset = rig.setpoints(d, drive)
    for _ in range(max(2, round(duration / dt))):
        d.qvel[:] = 0.0
        d.qvel[rig.dofs] = qset
        d.qvel[fa : fa + 3] = drive.twist[:3]
        d.qvel[fa + 3 : fa + 6] = d.xmat[rig.ob].reshape(3, 3).T @ drive.twist[3:]
        mujoco.mj_forward(m, d)
        grav = _gravity(m, scratch, d.qpos)
        mujoco.mj_integratePos(m, d.qpos, d.qvel, dt)
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        nxt = rig.setpoints(d, drive)
        acc, out = np.zeros(m.nv), np.zeros(m.nv)
        acc[rig.dofs] = (nxt - qset) / dt
        mujoco.mj_mulM(m, d, out, acc)
        worst = np.maximum(worst, np.abs((out + d.qfrc_bias - grav)[rig.dofs]))
        qset = nxt
    return worst


def rerun_data(result: RolloutResult, *, prefix: str = "rollout") -> dict[str, dict[str, _F64]]:
    r"""Entity path -> named arrays to log (no rerun import here): a recorded rollout's trace.

    ``time`` (s) is the timeline of every entity; ``object/position`` (N, 3) for
    ``Points3D``/``LineStrips3D``; scalars per step for ``Scalars``.
    """
    tr = result.trace
    if not tr:
        raise ParamError("rollout", "the rollout was not recorded (record=True)")
    t = tr["time"]
    out = {
        f"{prefix}/object/position": {"time": t, "positions": tr["object_pos"]},
        f"{prefix}/object/speed": {"time": t, "scalars": np.linalg.norm(tr["twist"], axis=1)},
        f"{prefix}/contacts/max_gap": {"time": t, "scalars": np.max(tr["gap"], axis=1)},
    }
    for j, name in enumerate(result.joints):
        out[f"{prefix}/joints/{name}/speed"] = {"time": t, "scalars": tr["qvel"][:, j]}
        out[f"{prefix}/joints/{name}/torque"] = {"time": t, "scalars": tr["torque"][:, j]}
    return out
