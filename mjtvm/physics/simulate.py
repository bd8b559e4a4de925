r"""MuJoCo rollouts of TVMMP witnesses: is $s\,\alpha_{kl}\hat r_l$ physically achievable?

A rollout drives the hand with MuJoCo's own ``<dcmotor>`` actuators (``input="vel ff"``:
velocity setpoint in actuator-length units, i.e. joint speed x gear, plus a torque
feedforward; drive voltage clamped at Vmax; motor torque clamped at the continuous torque),
so the speed-torque line, the torque saturation and the rotor inertia are MuJoCo's motor
physics. The object is free under gravity. Protocol (``docs/physics-check.md``):

1. *Model* ([`sim_model()`][mjtvm.physics.settings.sim_model]): a copy of the lift's model with elliptic friction cones,
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

The settings and the model (step 1) are [`mjtvm.physics.settings`][mjtvm.physics.settings], the
inertial torques (``inertial_ff``, [`inertial_demand()`][mjtvm.physics.inertia.inertial_demand])
[`mjtvm.physics.inertia`][mjtvm.physics.inertia]; their names are importable from here too.

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
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError
from mjtvm.physics.inertia import inertial_demand, inertial_feedforward
from mjtvm.physics.rig import Nearest, Rig, finger_contacts, twist_errors
from mjtvm.physics.settings import SimSettings, sim_model
from mjtvm.physics.squeeze import Servo
from mjtvm.physics.witness import Drive

__all__ = [
    "RolloutResult",
    "SettleCache",
    "SimSettings",
    "held",
    "inertial_demand",
    "rerun_data",
    "rollout",
    "settle",
    "sim_model",
]

_F64 = NDArray[np.float64]


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
        rest"``, ``"slip"``, ``"contact lost"``, ``"speed edge"``, ``"torque limit"``; ``""``
        when passed) and where (the geom, the actuator or joint past its speed edge, or the
        saturated joints or actuators; ``""`` for the twist).
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
    time (with ``st.servo`` > 0 the position loop on ``qpos`` too); returns the data and how
    far the object drifted (m)."""
    d = held(m, qpos, rig, drive)
    p0 = d.xpos[rig.ob].copy()
    Servo(m, d, rig.acts, rig.cadr, st.servo).step(st.steps(st.settle))
    return d, float(np.linalg.norm(d.xpos[rig.ob] - p0))


class SettleCache:
    """Settled states of the rollouts of one model and ``qpos``, by drive (``rollout(settled=)``).

    Step 3 depends on the model, ``qpos``, the drive's feedforward (``Rig.hold_torques``) and
    the rig (its joints, actuators, moment rows and contacts), not on the speeds or the twist:
    the central witness at s >= 1 has the torques of s = 1 (``witness_drive``), so those
    rollouts share one settle. Each use gets its own copy of the settled data. The rig is
    shared by every drive of the same joints, actuators, moment rows, contacts and ``qpos``
    (the drives of every direction of a grasp): it holds indices, the motors' ratios at
    ``qpos`` (`Rig.bind`) and scratch arrays that each step overwrites.
    """

    def __init__(self) -> None:
        self._done: dict[tuple[Any, ...], tuple[Rig, mujoco.MjData, float]] = {}
        self._rigs: dict[tuple[Any, ...], Rig] = {}

    @staticmethod
    def _key(m: mujoco.MjModel, qpos: _F64, drive: Drive, object_body: str) -> tuple[Any, ...]:
        moment = None if drive.moment is None else np.asarray(drive.moment, dtype=float).tobytes()
        return (
            id(m),
            np.asarray(qpos, dtype=float).tobytes(),
            np.asarray(drive.torques, dtype=float).tobytes(),
            drive.joints,
            drive.actuators,
            moment,
            drive.contacts,
            object_body,
        )

    def get(
        self, m: mujoco.MjModel, qpos: _F64, drive: Drive, st: SimSettings, object_body: str
    ) -> tuple[Rig, mujoco.MjData, float]:
        """The rig, a copy of the settled data and the settle drift of ``drive`` (settled on a miss)."""
        key = (*self._key(m, qpos, drive, object_body), st)
        if key not in self._done:
            rkey = key[:2] + key[3:-1]  # all but the torques and the settings
            rig = self._rigs.get(rkey)
            if rig is None:
                rig = self._rigs[rkey] = Rig(m, drive, object_body)
            self._done[key] = (rig, *settle(m, qpos, rig, drive, st))
        rig, d, drift = self._done[key]
        return rig, copy.copy(d), drift


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
    stop_early: bool = False,
    settled: SettleCache | None = None,
) -> RolloutResult:
    r"""Settle, start and run one drive from ``qpos`` (module docstring, steps 3-5).

    ``model`` comes from [`sim_model()`][mjtvm.physics.settings.sim_model]. ``record`` keeps per-step arrays (``trace``).
    ``stop_early``: end the run at the first violation (``passed`` and ``reason`` are the
    full run's, since the first violation decides both; the maxima are then those up to it).
    ``settled``: a [`SettleCache`][mjtvm.physics.simulate.SettleCache] shared by rollouts of
    one model and ``qpos``: a drive with the same feedforward and contacts as an earlier one
    starts from a copy of that one's settled state (the settle depends on nothing else).
    """
    st = settings or SimSettings()
    m = model
    if settled is not None:
        rig, d, drift = settled.get(m, qpos, drive, st, object_body)
    else:
        rig = Rig(model, drive, object_body)
        d, drift = settle(m, qpos, rig, drive, st)
    if rig.coupled and st.inertial_ff:
        raise ParamError(
            "inertial_ff", "not available for a hand with a transmission (joint torques, not actuator forces)"
        )
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
    edge = {"ratio": 0.0, "where": ""}  # the largest speed over the speed edge (Drive.speed_limits)
    clamped, reason, gap_geom, failure = 0, "", "", ["", ""]
    trace: dict[str, list[Any]] = {k: [] for k in ("time", "object_pos", "twist", "qvel", "torque", "gap")}
    f6, pred = np.zeros(6), mujoco.MjData(m) if st.inertial_ff else None
    names = drive.actuators or drive.joints
    lim_idx, lim_adr, lim_lo, lim_hi = _joint_ranges(m, drive.joints)
    lim_margin, lim_joint = math.inf, ""
    points: list[Nearest] = []  # the fingers' nearest points at d, from finger_contacts
    for step in range(n1):
        qset = rig.setpoints(d, drive, points if step > n0 else None) if st.track else drive.speeds
        sp, ff = rig.controls(d, drive, qset)
        if st.inertial_ff and pred is not None:
            ff += inertial_feedforward(m, d, pred, rig, drive, qset)
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
        if drive.speed_limits is not None:
            # Range units: the motor's speed over its gear (joint side, or P qd with a transmission).
            over = np.abs(lvel / rig.gear) / np.maximum(drive.speed_limits, 1e-300)
            fastest = int(np.argmax(over))
            if over[fastest] > edge["ratio"]:
                edge["ratio"], edge["where"] = float(over[fastest]), names[fastest]
        v = d.qvel[fa : fa + 3]
        om = d.xmat[rig.ob].reshape(3, 3) @ d.qvel[fa + 3 : fa + 6]
        now = np.r_[v, rig.radius * om]
        twist_errors(worst, now, target, tnorm)
        gaps = finger_contacts(m, d, rig, st.timestep, slip, ssum, fsum, f6, points)
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
            reason, *failure = _violation(st, worst, slip, slip_tol, saturated, tnorm, gap_geom, edge)
            if reason:
                reason = f"{reason} at t = {1e3 * (step + 1 - n0) * st.timestep:.2f} ms"
                if stop_early:
                    break
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
    edge: dict[str, Any] | None = None,
) -> tuple[str, str, str]:
    """The first violated criterion as (text, kind, where) (`RolloutResult.failure`)."""
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
    if edge is not None and edge["ratio"] > 1.0 + st.edge_tol:
        where = edge["where"]
        return f"{where} {100 * (edge['ratio'] - 1):.1f} % past its range's speed", "speed edge", where
    if saturated:
        names = ", ".join(sorted(saturated))
        return f"torque saturated ({names})", "torque limit", names
    return "", "", ""


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
