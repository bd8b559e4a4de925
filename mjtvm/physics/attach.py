r"""Attaching MuJoCo ``<dcmotor>`` actuators to a hand with ``mujoco.MjSpec`` (model editing).

[`attach_dcmotors()`][mjtvm.physics.attach.attach_dcmotors] replaces the actuators of the given joints by
``<dcmotor>`` elements with exactly the attributes
[`mjcf()`][mjtvm.grasp.actuation.dcmotor.DCMotor.mjcf] writes, so the compiled arrays are the template's;
[`attach_actuator_dcmotors()`][mjtvm.physics.attach.attach_actuator_dcmotors] replaces each actuator of a
hand with a transmission by a ``<dcmotor>`` of the same name on the same joint or tendon. Both
remove the sensors of a replaced actuator and keep the keyframe controls of the others. Which
motors a hand or a grasp gets, and reading them back from a model:
[`mjtvm.physics.motors`][mjtvm.physics.motors], which re-exports both names.

Units: SI, motor side unless said otherwise (torques N m, speeds rad/s, inertia kg m^2).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import mujoco

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.dcmotor import DCMotor

__all__ = ["CTRLSPEC", "attach_actuator_dcmotors", "attach_dcmotors"]

CTRLSPEC = int(mujoco.mjtCtrlInput.mjINPUT_VEL) | int(mujoco.mjtCtrlInput.mjINPUT_FF)
"""``input="vel ff"``: control 0 the velocity setpoint, control 1 the torque feedforward."""
_JOINT_TRN = (int(mujoco.mjtTrn.mjTRN_JOINT), int(mujoco.mjtTrn.mjTRN_JOINTINPARENT))
_SCALAR = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))


# ------------------------------------------------------------------ attaching motors
def _spec(source: mujoco.MjSpec | str | Path) -> mujoco.MjSpec:
    """A spec of our own: a copy of an ``MjSpec``, or parsed from an MJCF path or text."""
    if isinstance(source, mujoco.MjSpec):
        return source.copy()  # the caller's spec is left as it is
    text = str(source)
    try:
        if isinstance(source, str) and text.lstrip().startswith("<"):
            return mujoco.MjSpec.from_string(text)
        return mujoco.MjSpec.from_file(text)
    except (ValueError, OSError) as e:
        where = "MJCF text" if text.lstrip().startswith("<") else f"MJCF file {text!r}"
        raise ModelError(where, f"cannot be parsed: {str(e).splitlines()[0]}") from e


def attach_dcmotors(
    source: mujoco.MjSpec | str | Path, motors: Mapping[str, DCMotor], *, name_format: str = "{joint}"
) -> mujoco.MjModel:
    r"""The model of ``source`` with one ``<dcmotor>`` per joint of ``motors`` (compiled).

    Every actuator that moves one of those joints is removed (a ``joint`` or ``jointinparent``
    transmission, e.g. a public hand's position servos, or a tendon through the joint, e.g. the
    Shadow hand's servos of two coupled finger joints: a non-zero moment arm), with the sensors
    that measure it; keyframes keep the controls of the other actuators (the new ones get
    0). Each joint then gets a ``<dcmotor>`` named ``name_format.format(joint=...)`` with
    ``gear``, ``nominal = "voltage stall_torque no_load_speed"``, ``saturation =
    "max_continuous_torque 0 0"``, ``armature = rotor_inertia``, ``input = "vel ff"`` and
    ``controller = "0 0 velocity_gain 0 0 voltage"``: what
    [`mjcf()`][mjtvm.grasp.actuation.dcmotor.DCMotor.mjcf] writes. The new actuators come after the kept ones,
    in the joints' model order; no control range, no damping (the joint's own damping,
    armature and ``actuatorfrcrange`` stay, and the latter caps the torque).

    Parameters
    ----------
    source
        An ``mujoco.MjSpec`` (copied, not modified), an MJCF file path or MJCF text.
    motors
        Joint name -> motor (hinge or slide joints).

    Returns
    -------
    mujoco.MjModel

    Raises
    ------
    ModelError
        Unparsable MJCF, an unknown or non-scalar joint, an actuator name already taken,
        or a model that does not compile after the change.
    """
    spec = _spec(source)
    if not motors:
        raise ModelError("motors", "expected at least one joint -> DCMotor")
    order = {j.name: i for i, j in enumerate(spec.joints)}
    for name, motor in motors.items():
        joint = spec.joint(name)
        if joint is None:
            raise ModelError(f"joint {name!r}", "not in the model")
        if int(joint.type) not in _SCALAR:
            raise ModelError(f"joint {name!r}", "expected a hinge or slide joint for a <dcmotor>")
        if not isinstance(motor, DCMotor):
            raise ModelError(f"motors[{name!r}]", f"expected a DCMotor, got {type(motor).__name__}")
    layout, moves = _control_layout(spec, set(motors))
    removed = [
        a
        for i, a in enumerate(spec.actuators)
        if moves[i] or (int(a.trntype) in _JOINT_TRN and a.target in motors)
    ]
    gone = {id(a) for a in removed}
    kept = [i for i, a in enumerate(spec.actuators) if id(a) not in gone]
    for sensor in list(spec.sensors):  # they would measure an actuator that is no longer there
        if int(sensor.objtype) == int(mujoco.mjtObj.mjOBJ_ACTUATOR) and sensor.objname in {
            a.name for a in removed if a.name
        }:
            spec.delete(sensor)
    for a in removed:
        spec.delete(a)
    taken = {a.name for a in spec.actuators}
    for joint in sorted(motors, key=order.__getitem__):
        name = name_format.format(joint=joint)
        if name in taken:
            raise ModelError(f"actuator {name!r}", "already in the model; pass another name_format")
        _add_dcmotor(spec, name, joint, motors[joint])
    return _compile(spec, layout, kept, len(motors))


def _control_layout(spec: mujoco.MjSpec, joints: set[str]) -> tuple[list[tuple[int, int]], list[bool]]:
    """(first control, number of controls) of each actuator, and whether it moves one of
    ``joints`` (a non-zero moment arm on its dof at ``qpos0``: a tendon actuator such as the
    Shadow hand's coupled finger servos), from a compiled copy."""
    try:
        m = spec.copy().compile()
    except ValueError as e:
        raise ModelError("model", f"does not compile: {str(e).splitlines()[0]}") from e
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    dofs = {int(m.jnt_dofadr[m.joint(j).id]) for j in joints}
    moves = []
    for a in range(m.nactuator):
        start, count = int(d.moment_rowadr[a]), int(d.moment_rownnz[a])
        cols = d.moment_colind[start : start + count]
        arms = d.actuator_moment[start : start + count]
        moves.append(any(int(c) in dofs and arm != 0.0 for c, arm in zip(cols, arms, strict=True)))
    return [(int(m.actuator_ctrladr[a]), int(m.actuator_ctrlnum[a])) for a in range(m.nactuator)], moves


def attach_actuator_dcmotors(
    source: mujoco.MjSpec | str | Path, motors: Mapping[str, DCMotor]
) -> mujoco.MjModel:
    r"""The model of ``source`` with each actuator of ``motors`` replaced by a ``<dcmotor>`` (compiled).

    For a hand with a transmission (``docs/physics-check.md``): the new ``<dcmotor>`` keeps the
    actuator's name and its transmission (the same joint, tendon, ...) and takes the gear
    ``motor.gear x`` the actuator's own gear, so that its moment is ``motor.gear`` times the
    actuator's row of ``P``: MuJoCo applies ``P^T u`` for a motor torque ``u / motor.gear`` and
    its ``actuator_velocity`` is ``motor.gear x P qd``. Other attributes as
    [`attach_dcmotors()`][mjtvm.physics.attach.attach_dcmotors] (sensors of a replaced actuator removed, keyframe controls of the
    kept actuators kept, the new ones at 0, after the kept ones in ``motors``' order).

    Raises
    ------
    ModelError
        Unparsable MJCF, an unknown actuator, or a model that does not compile after the change.
    """
    spec = _spec(source)
    if not motors:
        raise ModelError("motors", "expected at least one actuator -> DCMotor")
    layout, _moves = _control_layout(spec, set())
    index = {a.name: i for i, a in enumerate(spec.actuators) if a.name}
    old = []
    for name, motor in motors.items():
        act = spec.actuator(name)
        if act is None:
            raise ModelError(f"actuator {name!r}", "not in the model")
        if not isinstance(motor, DCMotor):
            raise ModelError(f"motors[{name!r}]", f"expected a DCMotor, got {type(motor).__name__}")
        old.append((name, act.trntype, act.target, float(act.gear[0]), motor))
    gone = {index[n] for n in motors}
    kept = [i for i in range(len(layout)) if i not in gone]
    for sensor in list(spec.sensors):
        if int(sensor.objtype) == int(mujoco.mjtObj.mjOBJ_ACTUATOR) and sensor.objname in motors:
            spec.delete(sensor)
    for name in motors:
        spec.delete(spec.actuator(name))
    for name, trntype, target, gear, motor in old:
        _add_dcmotor(spec, name, target, motor, trntype=trntype, gear=motor.gear * gear)
    return _compile(spec, layout, kept, len(motors))


def _compile(
    spec: mujoco.MjSpec, layout: list[tuple[int, int]], kept: list[int], added: int
) -> mujoco.MjModel:
    """The spec compiled, each keyframe's controls those of the ``kept`` actuators (``layout``:
    their (start, count) in the old controls) followed by 0 for the ``added`` dcmotors' two."""
    for key in spec.keys:
        ctrl = list(key.ctrl)
        if ctrl:  # an unset ctrl stays unset (the compiler fills it)
            old = [c for i in kept for c in ctrl[layout[i][0] : layout[i][0] + layout[i][1]]]
            key.ctrl = old + [0.0] * (2 * added)
    try:
        return spec.compile()
    except ValueError as e:
        raise ModelError(
            "model", f"does not compile with the <dcmotor> actuators: {str(e).splitlines()[0]}"
        ) from e


def _add_dcmotor(
    spec: mujoco.MjSpec,
    name: str,
    joint: str,
    motor: DCMotor,
    *,
    trntype: mujoco.mjtTrn = mujoco.mjtTrn.mjTRN_JOINT,
    gear: float | None = None,
) -> None:
    """One ``<dcmotor>`` as [`mjcf()`][mjtvm.grasp.actuation.dcmotor.DCMotor.mjcf] writes it, on the
    transmission ``trntype`` to ``joint`` (a joint, tendon, ... name) with ``gear`` (default
    ``motor.gear``)."""
    act = spec.add_actuator(name=name, target=joint, trntype=trntype)
    # motorconst and resistance 0: the compiler derives K and R from `nominal`, as from the XML
    act.set_to_dcmotor(
        motorconst=[0.0, 0.0],
        resistance=0.0,
        nominal=[motor.voltage, motor.stall_torque, motor.no_load_speed],
        saturation=[motor.max_continuous_torque, 0.0, 0.0],
        controller=[0.0, 0.0, motor.velocity_gain, 0.0, 0.0, motor.voltage],
        ctrlspec=CTRLSPEC,
    )
    act.gear = [motor.gear if gear is None else gear, 0.0, 0.0, 0.0, 0.0, 0.0]
    act.armature = motor.rotor_inertia
    # a default class's <general ctrlrange/damping> would otherwise leak into the motor
    act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    act.damping = [0.0] * len(act.damping)
