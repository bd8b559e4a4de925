r"""The physics check: MuJoCo rollouts of TVMMP witnesses with the hand's ``<dcmotor>`` actuators.

What the room holds:

* Rollouts: the settings and the model a rollout runs on ([`mjtvm.physics.settings`][mjtvm.physics.settings]),
  one rollout and its pass/fail criteria ([`rollout()`][mjtvm.physics.simulate.rollout],
  [`RolloutResult`][mjtvm.physics.simulate.RolloutResult]), its per-step pieces ([`Rig`][mjtvm.physics.rig.Rig]),
  the inertial torques the quasi-static LP leaves out ([`mjtvm.physics.inertia`][mjtvm.physics.inertia]), and
  alpha_sim by bisection on rollouts ([`alpha_sim()`][mjtvm.physics.bisection.alpha_sim]).
* Witnesses: the motion and forces a rollout drives ([`witness_drive()`][mjtvm.physics.witness.witness_drive]).
* A dataset grasp's simulation (``mjtvm rank --verify``): DexGraspBench's hold test under six
  pushes ([`disturb_test()`][mjtvm.physics.disturb.disturb_test]) and the speed test at 0.8,
  1.0, 1.2 alpha ([`grasp_sim()`][mjtvm.physics.grasp_sim.grasp_sim]).
* The hold test at rest ([`hold_test()`][mjtvm.physics.hold.hold_test]), the launch from rest
  ([`mjtvm.physics.launch`][mjtvm.physics.launch]) and a verdict in words per pair
  ([`mjtvm.physics.verdict`][mjtvm.physics.verdict]).
* The dynamic alpha's MuJoCo side: the torque the witness motion needs beyond eq. (19)
  ([`dynamic_pair()`][mjtvm.physics.dynamic.dynamic_pair]).
* Motors: [`attach_dcmotors()`][mjtvm.physics.attach.attach_dcmotors] gives any hand DC motors,
  [`attach_actuator_dcmotors()`][mjtvm.physics.attach.attach_actuator_dcmotors] the actuators of a hand with a
  transmission; which motors a grasp gets is [`mjtvm.physics.motors`][mjtvm.physics.motors].

The applications along a lift live in [`mjtvm.jobs`][mjtvm.jobs]:
[`verify_lift()`][mjtvm.jobs.verify.verify_lift] (alpha_sim against alpha_kl),
[`slide_check()`][mjtvm.jobs.slide_check.slide_check] and [`gear_sweep()`][mjtvm.jobs.gears.gear_sweep].

What it may import: the rooms below it (``mjtvm.lift``, ``mjtvm.paper_hand``, ``mjtvm.grasp``,
``mjtvm.measures``, ``mjtvm.polytopes``, ``mjtvm.problem2``, ``mjtvm.formats``, ``mjtvm.model``,
``mjtvm.lp``, ``mjtvm.errors``), MuJoCo, NumPy, SciPy and Clarabel; never ``mjtvm.jobs``,
``mjtvm.viewer`` or ``mjtvm.cli``, nor rerun (``pyproject.toml``, import-linter contracts).

The names below are imported on first use: ``import mjtvm.physics`` loads no MuJoCo, and
importing one module of the room does not load the others.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mjtvm._lazy import lazy_attributes

if TYPE_CHECKING:
    from mjtvm.physics.attach import attach_actuator_dcmotors, attach_dcmotors
    from mjtvm.physics.bisection import alpha_sim
    from mjtvm.physics.dynamic import dynamic_pair
    from mjtvm.physics.hold import hold_test
    from mjtvm.physics.settings import SimSettings, sim_model
    from mjtvm.physics.simulate import RolloutResult, rollout
    from mjtvm.physics.witness import witness_drive

_HOMES = {
    "attach_actuator_dcmotors": "attach",
    "attach_dcmotors": "attach",
    "alpha_sim": "bisection",
    "dynamic_pair": "dynamic",
    "hold_test": "hold",
    "SimSettings": "settings",
    "sim_model": "settings",
    "RolloutResult": "simulate",
    "rollout": "simulate",
    "witness_drive": "witness",
}

__all__ = [
    "RolloutResult",
    "SimSettings",
    "alpha_sim",
    "attach_actuator_dcmotors",
    "attach_dcmotors",
    "dynamic_pair",
    "hold_test",
    "rollout",
    "sim_model",
    "witness_drive",
]


__getattr__ = lazy_attributes(__name__, _HOMES)
