r"""DC motors for any hand: which ``<dcmotor>`` each joint or actuator gets, and reading them back.

The physics check ([`mjtvm.physics.simulate`][mjtvm.physics.simulate]) drives each state joint with a
``<dcmotor>`` (``input="vel ff"``: a velocity setpoint in actuator-length units and a
motor-side torque feedforward; drive voltage clamped at Vmax; torque saturated at the
continuous torque; rotor inertia as the actuator's ``armature``). The generated hand has
them ([`mjcf()`][mjtvm.grasp.actuation.dcmotor.DCMotor.mjcf]); a public hand usually has position servos.
[`attach_dcmotors()`][mjtvm.physics.attach.attach_dcmotors] replaces the actuators of the given joints by ``<dcmotor>`` elements
through MuJoCo's model-editing API, with exactly the attributes
[`mjcf()`][mjtvm.grasp.actuation.dcmotor.DCMotor.mjcf] writes, so the compiled arrays are the template's
(the editing is [`mjtvm.physics.attach`][mjtvm.physics.attach]; its names are importable from here too).

Where a joint's motor comes from (the ``[ranges]`` of a grasp file, ``docs/grasp-format.md``,
resolved by [`mjtvm.grasp.actuation.ranges.joint_ranges()`][mjtvm.grasp.actuation.ranges.joint_ranges] into ``Grasp.motors``): a ``<dcmotor>`` of
the model ([`motor_of_actuator()`][mjtvm.physics.motors.motor_of_actuator] reads it back) or a datasheet
([`from_datasheet()`][mjtvm.grasp.actuation.dcmotor.DCMotor.from_datasheet]); a polygon or an actuator with a speed limit
is an operation range without a motor, and a datasheet with a gear efficiency other than 1
cannot be a ``<dcmotor>`` (MuJoCo's gear is ideal): [`require_motors()`][mjtvm.physics.motors.require_motors] refuses those,
naming the joint and how to give motor data.

A hand with a transmission (coupled joints, a linkage) is driven by actuator instead:
[`attach_actuator_dcmotors()`][mjtvm.physics.attach.attach_actuator_dcmotors] replaces each actuator of the state by a ``<dcmotor>`` of the
same name on the same joint or tendon, and [`box_motor()`][mjtvm.physics.motors.box_motor] stands for an ``actuator = true``
box (the motor whose speed-torque line passes through the box's corner).

Units: SI, motor side unless said otherwise (torques N m, speeds rad/s, inertia kg m^2).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.physics.attach import CTRLSPEC, attach_actuator_dcmotors, attach_dcmotors

__all__ = [
    "BOX_SPEED_MARGIN",
    "CTRLSPEC",
    "actuator_model",
    "actuator_motors",
    "attach_actuator_dcmotors",
    "attach_dcmotors",
    "box_motor",
    "dcmotor_of_actuator",
    "dcmotor_of_joint",
    "grasp_source",
    "joint_actuators",
    "motor_of_actuator",
    "require_motors",
    "same_model",
]

_NO_MOTOR = (
    "give its [ranges] entry as a datasheet with gear_efficiency = 1, or dcmotor = true with a <dcmotor>"
)


# ------------------------------------------------------------------ reading a model
def joint_actuators(model: mujoco.MjModel, joint: int) -> list[int]:
    """Ids of the actuators whose transmission is joint ``joint`` (``mjTRN_JOINT``), in model order."""
    return [
        a
        for a in range(model.nactuator)
        if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT)
        and int(model.actuator_trnid[a, 0]) == int(joint)
    ]


def dcmotor_of_joint(model: mujoco.MjModel, joint: str) -> int | None:
    """The id of the single ``<dcmotor>`` with ``input="vel ff"`` driving ``joint``, else ``None``.

    ``None`` also when other actuators drive the joint too: the rollout's torques would not
    be the motor's alone.
    """
    j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, joint)
    if j < 0:
        raise ModelError(f"joint {joint!r}", "not in the model")
    acts = joint_actuators(model, j)
    if len(acts) != 1:
        return None
    a = acts[0]
    dc = int(model.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_DCMOTOR)
    return a if dc and int(model.actuator_ctrlspec[a]) == CTRLSPEC else None


def dcmotor_of_actuator(model: mujoco.MjModel, name: str) -> int:
    """The id of the ``<dcmotor>`` with ``input="vel ff"`` named ``name`` (a transmission's actuator).

    Raises
    ------
    ModelError
        No actuator of that name, or not such a ``<dcmotor>``.
    """
    a = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
    if a < 0:
        raise ModelError(f"actuator {name!r}", "not in the model")
    dc = int(model.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_DCMOTOR)
    if not (dc and int(model.actuator_ctrlspec[a]) == CTRLSPEC):
        raise ModelError(
            f"actuator {name!r}",
            'expected a <dcmotor> with input="vel ff" (mjtvm.physics.motors.attach_actuator_dcmotors)',
        )
    return a


def motor_of_actuator(model: mujoco.MjModel, actuator: int) -> DCMotor:
    r"""The `DCMotor` of a compiled ``<dcmotor>`` (inverse of [`attach_dcmotors()`][mjtvm.physics.attach.attach_dcmotors]).

    ``actuator_gainprm`` holds R (Ohm), K (V s/rad), ..., kd, Vmax
    ([`operation_range_from_actuator()`][mjtvm.grasp.actuation.actuator.operation_range_from_actuator]): voltage = Vmax, stall
    torque K V / R, no-load speed V / K, continuous torque the upper ``forcerange``.
    """
    label = f"actuator {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, actuator) or f'#{actuator}'!r}"
    if int(model.actuator_gaintype[actuator]) != int(mujoco.mjtGain.mjGAIN_DCMOTOR):
        raise ModelError(label, "is not a <dcmotor>")
    r_ohm, k = float(model.actuator_gainprm[actuator, 0]), float(model.actuator_gainprm[actuator, 1])
    volts = float(model.actuator_gainprm[actuator, 7])
    if not (r_ohm > 0 and k > 0 and volts > 0 and model.actuator_forcelimited[actuator]):
        raise ModelError(label, "expected positive R, K and Vmax and a saturation (continuous torque)")
    return DCMotor(
        voltage=volts,
        stall_torque=k * volts / r_ohm,
        no_load_speed=volts / k,
        max_continuous_torque=float(model.actuator_forcerange[actuator, 1]),
        gear=float(model.actuator_gear[actuator, 0]),
        rotor_inertia=float(model.actuator_armature[actuator]),
        velocity_gain=float(model.actuator_gainprm[actuator, 6]),
    )


BOX_SPEED_MARGIN = 0.1
"""The box motor's no-load speed is ``1 + BOX_SPEED_MARGIN`` times the box's speed ([`box_motor()`][mjtvm.physics.motors.box_motor])."""


def box_motor(max_force: float, max_speed: float, *, gear: float = 1.0) -> DCMotor:
    r"""The ``<dcmotor>`` standing for an actuator's box range ``|u| <= max_force``, ``|s| <= max_speed``.

    A DC motor's speed-torque line cannot be a box; this one contains it and is close to it:
    saturation (continuous torque) ``max_force``, the line through the box's corner
    ``(max_speed, max_force)`` with its no-load speed ``(1 + BOX_SPEED_MARGIN) max_speed``
    (stall torque ``max_force (1 + m) / m``). The torque edge is the box's; past the speed
    edge the force falls to 0 within 10 % more speed, so a rollout limited by the speed edge
    may pass up to 10 % above alpha_kl. The speed loop's gain is ``max_force / max_speed``
    (an error of the whole speed range asks the whole force); no rotor inertia (the box says
    none; the joints' own armature stays in the model). Units: the actuator's (N m or N,
    rad/s or m/s), ``gear`` 1 unless given. The voltage, 1 V, only scales R and K.
    """
    for name, value in (("max_force", max_force), ("max_speed", max_speed)):
        if not (value > 0 and value < float("inf")):
            raise ModelError(name, f"expected a positive finite number for a box motor, got {value!r}")
    w0 = (1.0 + BOX_SPEED_MARGIN) * max_speed
    return DCMotor(
        voltage=1.0,
        stall_torque=max_force * (1.0 + BOX_SPEED_MARGIN) / BOX_SPEED_MARGIN,
        no_load_speed=w0,
        max_continuous_torque=max_force,
        gear=gear,
        rotor_inertia=0.0,
        velocity_gain=max_force / max_speed,
    )


# ------------------------------------------------------------------ a grasp's motors
def require_motors(
    model: mujoco.MjModel, joints: Sequence[str], motors: Mapping[str, DCMotor | str | None]
) -> dict[str, DCMotor]:
    r"""The motors to attach so that every joint of ``joints`` has its ``<dcmotor>``.

    ``motors`` follows `mjtvm.grasp.resolve.loaded.Grasp.motors` ([`mjtvm.grasp.actuation.ranges.joint_ranges()`][mjtvm.grasp.actuation.ranges.joint_ranges]):
    a `DCMotor` (from a datasheet), ``None`` (the model's own
    ``<dcmotor>`` drives the joint) or a string saying why the joint's range has no motor
    (a polygon, an actuator with a speed limit, a gear efficiency other than 1). Joints that
    already have one ``<dcmotor>`` with ``input="vel ff"`` need nothing.

    Raises
    ------
    ModelError
        One line naming the first joint without motor data, why, and how to give it.
    """
    out: dict[str, DCMotor] = {}
    for joint in joints:
        if dcmotor_of_joint(model, joint) is not None:
            continue
        motor = motors.get(joint)
        if isinstance(motor, DCMotor):
            out[joint] = motor
            continue
        why = motor if isinstance(motor, str) else 'no <dcmotor> with input="vel ff" drives it'
        raise ModelError(f"joint {joint!r}", f"{why}: the physics check needs a DC motor; {_NO_MOTOR}")
    return out


def actuator_motors(grasp: Any) -> dict[str, DCMotor]:
    r"""The ``<dcmotor>`` of each actuator of a grasp with a transmission (``docs/physics-check.md``).

    A datasheet's motor as is; an ``actuator = true`` box (``|u| <= U``, ``|s| <= S``, ``U`` the
    range's force plus the joints' friction share the range had taken off) the
    [`box_motor()`][mjtvm.physics.motors.box_motor] of ``(U, S)``; an actuator that is already a
    ``<dcmotor>`` with ``input="vel ff"`` nothing (it drives as is).

    Raises
    ------
    ModelError
        An unnamed actuator (its motor is found by name), a polygon range or a model
        ``<dcmotor>`` without ``input="vel ff"``: one line naming the actuator.
    """
    t, model = grasp.transmission, grasp.model
    dofs = np.array([int(model.joint(j).dofadr[0]) for j in t.joint_names])
    out: dict[str, DCMotor] = {}
    for a, name, row in zip(t.actuator_ids, t.actuator_names, t.moment, strict=True):
        if mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) != name:
            raise ModelError(
                f"actuator {name!r}", "has no name: the physics check finds its <dcmotor> by name"
            )
        entry = grasp.motors.get(name)
        if isinstance(entry, DCMotor):
            out[name] = entry
            continue
        dc = int(model.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_DCMOTOR)
        if entry is None and dc and int(model.actuator_ctrlspec[a]) == CTRLSPEC:
            continue
        rng = grasp.operation_ranges[name]
        if isinstance(entry, str) and rng.max_speed_at(rng.max_torque) >= rng.max_speed * (1 - 1e-12):
            arms = np.abs(row)
            friction = float(np.max(model.dof_frictionloss[dofs][arms > 0] / arms[arms > 0], initial=0.0))
            out[name] = box_motor(rng.max_torque + friction, rng.max_speed)
            continue
        why = entry if isinstance(entry, str) else 'its <dcmotor> has no input="vel ff"'
        raise ModelError(
            f"actuator {name!r}",
            f"{why}: the physics check needs a DC motor; give its [ranges] entry as a datasheet "
            "with gear_efficiency = 1, or actuator = true with a speed_limit",
        )
    return out


def actuator_model(grasp: Any) -> mujoco.MjModel:
    """The grasp's model with [`actuator_motors()`][mjtvm.physics.motors.actuator_motors] attached on the actuators' own transmissions."""
    motors = actuator_motors(grasp)
    if not motors:
        return grasp.model
    return same_model(grasp, attach_actuator_dcmotors(grasp_source(grasp), motors))


def grasp_source(grasp: Any) -> mujoco.MjSpec | Path:
    """What the motors are attached to: the grasp's ``MjSpec`` (its MJCF with the object and
    supports it adds), or its model file."""
    return grasp.spec() if hasattr(grasp, "spec") else Path(grasp.model_path)


def same_model(grasp: Any, model: mujoco.MjModel) -> mujoco.MjModel:
    """``model`` when it has the grasp model's coordinates, bodies and geoms (only actuators
    were added); else a [`ModelError`][mjtvm.errors.ModelError]."""
    if (model.nq, model.nv, model.nbody, model.ngeom) != (
        grasp.model.nq,
        grasp.model.nv,
        grasp.model.nbody,
        grasp.model.ngeom,
    ):
        raise ModelError(
            f"model {str(grasp.model_path)!r}", "differs from the grasp's model after attaching motors"
        )
    return model
