r"""The hold test: does the grasp hold the object at rest, before any speed is tested?

The state is simulated at rest: gravity on, the object free, every motor's speed setpoint 0
and its feedforward the torques (actuator forces) of the witness at alpha = 0, i.e. the forces
that balance the weight (and a contact's ``preload``): a rollout's settle phase
([`rollout()`][mjtvm.physics.simulate.rollout]). The grasp holds when, over the hold,

the object's points at the contacts stay within ``lost_gap`` (0.5 mm), counting both what they
moved during the hold and what the object's speed at its end would add over one more rollout's
length: ``drift + speed x (settle + startup + window) <= lost_gap``.

Why (``docs/physics-check.md``, "The hold test"): the hold lasts as long as a rollout
(settle + startup + window, 37 ms), the time over which the speed test claims anything. A held
object only settles onto its contacts' compression (about 0.03 mm for the rollouts' 2 ms
contacts under the paper's grasp forces); 0.5 mm is the distance at which the check itself
calls a contact lost: an object that moved that far at rest, or is on its way there within a
rollout, has left the state whose speeds the LP gives. A longer hold (``duration``,
``mjtvm verify --hold``) asks more: the drive has no position loop (a speed setpoint of 0 is a
damper), so a neutral or unstable mode of the grasp drifts on.

Which contact lets go: per finger, the object's material point at the contact against the
finger's material point there (both fixed to their bodies at the start), split into sliding
(tangential) and opening (along the normal); the finger whose point moved most, with the
contact's normal force at the end of the settle and of the hold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError
from mjtvm.model.state import GraspState
from mjtvm.physics.rig import Rig
from mjtvm.physics.settings import SimSettings
from mjtvm.physics.simulate import held
from mjtvm.physics.squeeze import SERVO_GAIN, TORSIONAL_FRICTION, Servo, squeeze_drive, with_torsion
from mjtvm.physics.witness import Drive, witness_drive

__all__ = ["ContactHold", "HoldResult", "hold_row", "hold_test", "state_hold"]

_F64 = NDArray[np.float64]


@dataclass(frozen=True)
class ContactHold:
    """One finger contact over the hold (lengths in m, forces in N).

    Attributes
    ----------
    label, kind
        The finger geom's label and its contact type (F, L, S).
    slide, opening
        The object's contact point relative to the finger's, tangential and along the start
        normal (positive: the object left the finger).
    force_start, force_end
        The contact's normal force at the end of the rollouts' settle time and at the end of
        the hold (0 when the finger no longer touches).
    """

    label: str
    kind: str
    slide: float
    opening: float
    force_start: float
    force_end: float

    @property
    def moved(self) -> float:
        """How far (m) the contact moved apart: sliding and opening together."""
        return math.hypot(self.slide, max(self.opening, 0.0))


@dataclass(frozen=True)
class HoldResult:
    """Outcome of [`hold_test()`][mjtvm.physics.hold.hold_test].

    Attributes
    ----------
    held
        Whether `reach` stays within `bound`.
    drift
        Largest displacement (m) of the object's points at the contacts over the hold.
    speed
        Largest object twist $|[v; R\\omega]|$ (m/s) in the hold's last ``window``
        (extrapolated over a rollout's length in the criterion: module docstring).
    translation, rotation
        The object origin's displacement (m) and its rotation (deg) over the hold.
    contacts
        Per finger contact, how it moved and its force ([`ContactHold`][mjtvm.physics.hold.ContactHold]).
    reach
        `drift` plus `speed` times a rollout's length (m): where the contacts are
        headed within one more rollout.
    duration, bound
        The hold's length (s) and the bound on `reach` (m).
    rotor_inertia
        The largest rotor inertia of the state's motors reflected through their gear (kg m^2
        at a joint, or in the units of the actuator's transmission): MuJoCo's actuator
        ``armature`` x gear^2; 0 when the motor data give none (a servo datasheet without
        ``rotor_inertia_kgm2``).
    """

    held: bool
    drift: float
    speed: float
    reach: float
    translation: float
    rotation: float
    contacts: tuple[ContactHold, ...]
    duration: float
    bound: float
    rotor_inertia: float = 0.0

    @property
    def lets_go(self) -> ContactHold | None:
        """The contact that moved most (``None`` without finger contacts)."""
        return max(self.contacts, key=lambda c: c.moved, default=None)

    def message(self) -> str:
        """One line: how far and how fast the object moves, and the contact that lets go."""
        text = (
            f"does not hold at rest: in {1e3 * self.duration:.0f} ms the object moves "
            f"{1e3 * self.drift:.3g} mm at its contacts ({1e3 * self.translation:.3g} mm, "
            f"{self.rotation:.3g} deg) and {1e3 * self.speed:.3g} mm/s at the end, "
            f"{1e3 * self.reach:.3g} mm within one more rollout (bound {1e3 * self.bound:g} mm)"
        )
        c = self.lets_go
        if c is not None:
            text += (
                f"; {c.label} lets go: slides {1e3 * c.slide:.3g} mm, opens "
                f"{1e3 * max(c.opening, 0.0):.3g} mm, normal force {c.force_start:.3g} -> {c.force_end:.3g} N"
            )
        return text


def hold_test(
    model: mujoco.MjModel,
    qpos: _F64,
    drive: Drive,
    *,
    settings: SimSettings | None = None,
    object_body: str = "object",
    duration: float | None = None,
    servo: float = 0.0,
    torsional: float = 0.0,
) -> HoldResult:
    r"""Hold the state ``qpos`` at rest with the drive's torques (module docstring).

    Parameters
    ----------
    model
        From [`sim_model()`][mjtvm.physics.settings.sim_model].
    drive
        The witness drive at speed factor 0 (its torques hold the object; its speeds are 0).
    settings
        The rollouts' settings: ``settle``, ``startup``, ``window`` and ``lost_gap`` (the
        drift bound).
    duration
        Length of the hold (s); default: a rollout's, ``settle + startup + window``.
    servo, torsional
        The position loop's speed gain (1/s, [`Servo`][mjtvm.physics.squeeze.Servo]; 0: speed
        setpoints 0) and the contacts' torsional friction (m,
        [`with_torsion()`][mjtvm.physics.squeeze.with_torsion]; 0: the rollouts' contacts),
        as the pushes of [`disturb_test()`][mjtvm.physics.disturb.disturb_test] hold the grasp.

    Raises
    ------
    ParamError
        ``duration`` not a positive time, ``servo`` or ``torsional`` negative.
    """
    st = settings or SimSettings()
    total = st.settle + st.startup + st.window if duration is None else duration
    if not (math.isfinite(total) and total > 0):
        raise ParamError("duration", f"expected a positive time (s), got {duration!r}", duration)
    n_all, n_win = max(1, st.steps(total)), max(1, min(st.steps(st.window), st.steps(total)))
    m = with_torsion(model, torsional)
    rig = Rig(m, drive, object_body)
    d = held(m, qpos, rig, drive)
    loop = Servo(m, d, rig.acts, rig.cadr, servo)
    starts = [_anchor(d, rig, g, body) for _label, g, body, _c, _k in rig.fingers]
    p0, r0 = d.xpos[rig.ob].copy(), d.xmat[rig.ob].reshape(3, 3).copy()
    n_settle = min(max(1, st.steps(st.settle)), n_all)
    loop.step(n_settle)
    f_start = [_normal_force(m, d, g, rig) for _label, g, _b, _c, _k in rig.fingers]
    speed = 0.0
    for step in range(n_settle, n_all):
        loop.step(1)
        if step >= n_all - n_win:
            om = d.xmat[rig.ob].reshape(3, 3) @ d.qvel[rig.fadr + 3 : rig.fadr + 6]
            speed = max(speed, float(np.linalg.norm(np.r_[d.qvel[rig.fadr : rig.fadr + 3], rig.radius * om])))
    rot = d.xmat[rig.ob].reshape(3, 3) @ r0.T
    angle = math.degrees(math.acos(max(-1.0, min(1.0, 0.5 * (float(np.trace(rot)) - 1.0)))))
    contacts, drift = [], float(np.linalg.norm(d.xpos[rig.ob] - p0))
    if rig.fingers:
        drift = 0.0
    for (label, g, body, _c, kind), (on_obj, on_fin, n0), f0 in zip(
        rig.fingers, starts, f_start, strict=True
    ):
        obj_now = d.xpos[rig.ob] + d.xmat[rig.ob].reshape(3, 3) @ on_obj
        fin_now = d.xpos[body] + d.xmat[body].reshape(3, 3) @ on_fin
        drift = max(drift, float(np.linalg.norm(obj_now - (p0 + r0 @ on_obj))))
        n = d.xmat[body].reshape(3, 3) @ n0  # the start normal, turned with the finger
        rel = obj_now - fin_now
        contacts.append(
            ContactHold(
                label=label,
                kind=kind,
                slide=float(np.linalg.norm(rel - (rel @ n) * n)),
                opening=float(rel @ n),
                force_start=f0,
                force_end=_normal_force(m, d, g, rig),
            )
        )
    reach = drift + speed * (st.settle + st.startup + st.window)
    return HoldResult(
        held=reach <= st.lost_gap,
        drift=drift,
        speed=speed,
        reach=reach,
        translation=float(np.linalg.norm(d.xpos[rig.ob] - p0)),
        rotation=angle,
        contacts=tuple(contacts),
        duration=n_all * st.timestep,
        bound=st.lost_gap,
        rotor_inertia=float(
            np.max(m.actuator_armature[rig.acts] * m.actuator_gear[rig.acts, 0] ** 2, initial=0.0)
        ),
    )


def state_hold(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    result: Any,
    *,
    settings: SimSettings | None = None,
    object_body: str = "object",
    duration: float | None = None,
    squeeze: bool = False,
) -> HoldResult | None:
    """The hold test of a grasp state with the central witness at alpha = 0 (the same for every
    RVDS vertex: no twist to produce); ``None`` when no pair of ``result`` (the state's
    [`TvmmpResult`][mjtvm.problem2.tvmmp.TvmmpResult]) has a witness. ``squeeze``: held as the
    pushes of ``rank --verify`` hold it instead, by
    [`squeeze_drive()`][mjtvm.physics.squeeze.squeeze_drive] with its position loop
    (`SERVO_GAIN`) and torsional friction (`TORSIONAL_FRICTION`)."""
    optimal = [l for l, status in enumerate(result.status[0]) if status == "optimal"]
    if not optimal:
        return None
    if squeeze:
        drive = squeeze_drive(state, result)
        if drive is None:
            return None
        return hold_test(
            model, qpos, drive, settings=settings, object_body=object_body, duration=duration,
            servo=SERVO_GAIN, torsional=TORSIONAL_FRICTION,
        )  # fmt: skip
    l = optimal[0]
    drive = witness_drive(state, 0, l, float(result.alpha[0, l]), 0.0, witness="central")
    return hold_test(model, qpos, drive, settings=settings, object_body=object_body, duration=duration)


def _anchor(d: mujoco.MjData, rig: Rig, g: int, body: int) -> tuple[_F64, _F64, _F64]:
    """The contact's point (midway between the nearest points) in the object's and the finger
    body's frames, and the normal (finger into object) in the finger body's frame."""
    _dist, _og, on_f, on_o, n = rig.nearest(d, g)
    p = 0.5 * (on_f + on_o)
    ro, rb = d.xmat[rig.ob].reshape(3, 3), d.xmat[body].reshape(3, 3)
    return ro.T @ (p - d.xpos[rig.ob]), rb.T @ (p - d.xpos[body]), rb.T @ n


def _normal_force(m: mujoco.MjModel, d: mujoco.MjData, g: int, rig: Rig) -> float:
    """Normal force (N) of finger geom ``g`` on the object, summed over their active contacts."""
    f6, total = np.zeros(6), 0.0
    for i in range(d.ncon):
        c = d.contact[i]
        g1, g2 = int(c.geom1), int(c.geom2)
        if c.exclude or not ((g1 == g and g2 in rig.ogs) or (g2 == g and g1 in rig.ogs)):
            continue
        mujoco.mj_contactForce(m, d, i, f6)
        total += float(f6[0])
    return total


def hold_row(hold: HoldResult) -> dict[str, Any]:
    """The hold test's columns of a ``verify.csv`` row (``docs/outputs.md``); a grasp that does
    not hold gets its verdict here, and no speed is tested."""
    c = hold.lets_go
    row: dict[str, Any] = {
        "held": hold.held,
        "hold_drift": hold.drift,
        "hold_speed": hold.speed,
        "hold_reach": hold.reach,
        "hold_rotation": hold.rotation,
        "hold_contact": c.label if c is not None else "",
        "rotor_inertia": hold.rotor_inertia,
    }
    if not hold.held:
        row["verdict"] = hold.message()
    return row
