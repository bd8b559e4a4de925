r"""The physics check: MuJoCo rollouts of TVMMP witnesses with the hand's ``<dcmotor>`` actuators.

[`verify_lift()`][mjtvm.jobs.verify.verify_lift] compares alpha_sim (rollouts, [`alpha_sim()`][mjtvm.physics.bisection.alpha_sim]) with alpha_kl (the LP)
along the lift, after the hold test at rest ([`hold`][mjtvm.physics.hold]), with a verdict in
words per pair ([`verdict`][mjtvm.physics.verdict]) and optionally a launch from rest
([`launch`][mjtvm.physics.launch]); [`slide_check()`][mjtvm.jobs.slide_check.slide_check] settles the slide direction of S-points;
[`dynamic_pair()`][mjtvm.physics.dynamic.dynamic_pair] adds the torque the witness motion needs beyond eq. (19);
[`gear_sweep()`][mjtvm.jobs.gears.gear_sweep] varies the gear ratio; [`attach_dcmotors()`][mjtvm.physics.motors.attach_dcmotors] gives any hand DC motors,
[`attach_actuator_dcmotors()`][mjtvm.physics.motors.attach_actuator_dcmotors] the actuators of a hand with a transmission ([`box_motor()`][mjtvm.physics.motors.box_motor]
for a box range).

The names below are imported on first use: the report's plots load matplotlib, which a
rollout alone does not need.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mjtvm._lazy import lazy_attributes

if TYPE_CHECKING:
    from mjtvm.physics.bisection import Bisection, alpha_sim
    from mjtvm.physics.dynamic import dynamic_pair
    from mjtvm.physics.motors import attach_actuator_dcmotors, attach_dcmotors, box_motor
    from mjtvm.physics.simulate import RolloutResult, SimSettings, rollout, sim_model
    from mjtvm.physics.witness import witness_drive

_HOMES = {
    "Bisection": "bisection",
    "alpha_sim": "bisection",
    "dynamic_pair": "dynamic",
    "attach_dcmotors": "motors",
    "attach_actuator_dcmotors": "motors",
    "box_motor": "motors",
    "RolloutResult": "simulate",
    "SimSettings": "simulate",
    "rollout": "simulate",
    "sim_model": "simulate",
    "witness_drive": "witness",
}

__all__ = [
    "Bisection",
    "RolloutResult",
    "SimSettings",
    "alpha_sim",
    "attach_actuator_dcmotors",
    "attach_dcmotors",
    "box_motor",
    "dynamic_pair",
    "rollout",
    "sim_model",
    "witness_drive",
]


__getattr__ = lazy_attributes(__name__, _HOMES)
