r"""The launch from rest: does the hand get the object up to speed within a stated distance?

Every other rollout starts impulsively, at the drive's speeds ([`rollout()`][mjtvm.physics.simulate.rollout],
step 4): it tests whether a speed can be *kept*, not whether it can be *reached*. A launch
starts where a rollout's settle ends, at rest, and commands the pair's witness with its speed
ramped up at a constant rate: the speed factor $\sigma(t) = \min(1, t / t_r)$ times the
joint speeds of $\alpha_{kl}\hat r_l$ (tracked at the current configuration, as in a
rollout's run), the witness's torques fed forward, so that an object following the command
covers ``distance`` D when it reaches the LP's speed: $t_r = 2D / \alpha_{kl}$. The
motors then accelerate the fingers and the object with what their speed-torque lines and
saturation give, against the rotor and link inertia the quasi-static LP leaves out.

The launch ends when the object has travelled D along $\hat r_l$ (its twist
$[v; R\omega]$ projected on the target's direction and integrated: metres, R the object's
bounding radius), when a contact is lost (a finger more than ``lost_gap`` from the object) or an
F-point slips beyond ``lost_gap`` + ``slip_tol`` x the travel (0.5 mm + 5 %: the hold test's
bound, since the fingers' speed loops lag their commands by different amounts while they
accelerate, and a rollout's 0.01 mm floor, meant for a window at speed, would stop every launch
in its first milliseconds), or at $2 t_r$. It
reports the largest speed along $\hat r_l$ reached ([`LaunchResult`][mjtvm.physics.launch.LaunchResult]): at most
about $\alpha_{kl}$ (the command's), less when the hand cannot accelerate the object
that fast, or loses it on the way.

D is stated, not physical: [`LAUNCH_DISTANCE`][mjtvm.physics.launch.LAUNCH_DISTANCE] (10 mm) by default, ``mjtvm verify
--launch METRES`` (``docs/physics-check.md``, "From rest"); the ramp's acceleration
$\alpha_{kl}^2 / 2D$ grows as D shrinks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError
from mjtvm.physics.rig import Rig, finger_contacts
from mjtvm.physics.settings import SimSettings
from mjtvm.physics.simulate import settle
from mjtvm.physics.witness import Drive

__all__ = ["LAUNCH_DISTANCE", "LaunchResult", "launch", "launch_row"]

_F64 = NDArray[np.float64]

LAUNCH_DISTANCE = 0.01
"""Default stated distance D (m) of a launch (module docstring)."""


@dataclass(frozen=True)
class LaunchResult:
    """Outcome of [`launch()`][mjtvm.physics.launch.launch] (SI units; speeds and distances of the twist [v; R omega]
    projected on the target direction).

    Attributes
    ----------
    speed
        The largest speed along the target direction reached before the launch ended (m/s).
    distance
        The distance travelled along it when the launch ended (m); ``target`` when reached.
    time
        How long the launch ran (s, from the end of the settle).
    target
        The stated distance (m).
    verdict
        ``reached``, ``contact lost at C``, ``slip at contact C`` or ``time limit`` (D not
        covered in twice the ramp's time).
    """

    speed: float
    distance: float
    time: float
    target: float
    verdict: str

    @property
    def reached(self) -> bool:
        """Whether the object travelled the stated distance with the grasp intact."""
        return self.verdict == "reached"


def launch(
    model: mujoco.MjModel,
    qpos: _F64,
    drive: Drive,
    *,
    distance: float | None = None,
    settings: SimSettings | None = None,
    object_body: str = "object",
) -> LaunchResult:
    r"""Launch the object from rest with ``drive`` (module docstring).

    Parameters
    ----------
    model
        From [`sim_model()`][mjtvm.physics.settings.sim_model].
    drive
        The pair's witness drive at the speed to reach (s = 1: $\alpha_{kl}\hat r_l$).
    distance
        The stated distance D (m) along the target direction; default [`LAUNCH_DISTANCE`][mjtvm.physics.launch.LAUNCH_DISTANCE].

    Raises
    ------
    ParamError
        A drive without a twist, or a distance that is not a positive length.
    """
    st = settings or SimSettings()
    rig, m = Rig(model, drive, object_body), model
    target = np.r_[drive.twist[:3], rig.radius * drive.twist[3:]]
    tnorm = float(np.linalg.norm(target))
    if not tnorm > 0:
        raise ParamError("drive.twist", "the launch needs a twist to reach (alpha_kl > 0)")
    goal = LAUNCH_DISTANCE if distance is None else float(distance)
    if not (math.isfinite(goal) and goal > 0):
        raise ParamError("distance", f"expected a positive length (m), got {distance!r}", distance)
    along, dt = target / tnorm, st.timestep
    d, _drift = settle(m, qpos, rig, drive, st)
    fa, f6 = rig.fadr, np.zeros(6)
    slip = dict.fromkeys((f[0] for f in rig.fingers if f[4] == "F"), 0.0)
    ssum = {f[0]: np.zeros(3) for f in rig.fingers if f[4] != "F"}
    fsum = {f[0]: np.zeros(3) for f in rig.fingers if f[4] != "F"}
    travel, top, steps, verdict = 0.0, 0.0, 0, "time limit"
    ramp = 2.0 * goal / tnorm  # s: the command reaches the LP's speed after D at this rate
    for steps in range(1, max(1, math.ceil(2.0 * ramp / dt)) + 1):
        now = _ramped(drive, min(1.0, (steps - 1) * dt / ramp))
        qset = rig.setpoints(d, now) if st.track else now.speeds
        sp, ff = rig.controls(d, now, qset)
        d.ctrl[rig.cadr] = sp
        d.ctrl[rig.cadr + 1] = ff / rig.gear
        mujoco.mj_step(m, d)
        om = d.xmat[rig.ob].reshape(3, 3) @ d.qvel[fa + 3 : fa + 6]
        speed = float(np.r_[d.qvel[fa : fa + 3], rig.radius * om] @ along)
        travel += speed * dt
        top = max(top, speed)
        gaps = finger_contacts(m, d, rig, dt, slip, ssum, fsum, f6)
        if max(gaps, default=0.0) > st.lost_gap:
            verdict = f"contact lost at {rig.fingers[int(np.argmax(gaps))][0]}"
            break
        slipped = [g for g, s in slip.items() if s > st.slip_tol * max(travel, 0.0) + st.lost_gap]
        if slipped:
            verdict = f"slip at contact {slipped[0]}"
            break
        if travel >= goal:
            verdict = "reached"
            break
    return LaunchResult(
        speed=top,
        distance=min(travel, goal),
        time=steps * dt,
        target=goal,
        verdict=verdict,
    )


def _ramped(drive: Drive, sigma: float) -> Drive:
    """The drive with its speeds, slip speeds and twist scaled by ``sigma`` (its torques kept)."""
    slips = {g: (rate * sigma, hat) for g, (rate, hat) in drive.slips.items()}
    return replace(drive, speeds=drive.speeds * sigma, twist=drive.twist * sigma, slips=slips)


def launch_row(
    model: mujoco.MjModel,
    qpos: _F64,
    drive: Drive,
    distance: float,
    settings: SimSettings | None,
    object_body: str,
) -> dict[str, Any]:
    """The launch's columns of a ``verify.csv`` row (``docs/outputs.md``); ``drive`` at s = 1."""
    out = launch(model, qpos, drive, distance=distance, settings=settings, object_body=object_body)
    return {
        "launch_speed": out.speed,
        "launch_distance": out.distance,
        "launch_time": out.time,
        "launch_verdict": out.verdict,
    }
