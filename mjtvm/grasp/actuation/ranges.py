r"""Each joint's operation range (eq. 1-3) from a grasp file's ``ranges`` table.

A joint's entry is its exact name, else the first glob pattern (``fnmatch``, in file order)
that matches it, else ``"*"``. Four sources (``docs/grasp-format.md``):

* ``dcmotor``: the model's ``<dcmotor>`` driving the joint
  ([`operation_range_from_actuator()`][mjtvm.grasp.actuation.actuator.operation_range_from_actuator]), exact;
* ``datasheet``: a motor datasheet entry, in maxon's form (no-load speed, nominal point, max
  permissible speed, gear ratio and efficiency) through
  [`from_datasheet()`][mjtvm.model.operation_range.OperationRange.from_datasheet], exact for the motor's
  continuous operation, or in the servo form (stall torque, no-load speed, optional gear,
  continuous torque, rotor inertia) through [`ServoDatasheet`][mjtvm.grasp.actuation.servo.ServoDatasheet];
  the same entry gives the physics check its ``<dcmotor>``
  ([`from_datasheet()`][mjtvm.grasp.actuation.dcmotor.DCMotor.from_datasheet],
  [`motor()`][mjtvm.grasp.actuation.servo.ServoDatasheet.motor]) when the gear is ideal;
* ``actuator`` + ``speed_limit``: the box ``|tau| <= gear x forcerange``,
  ``|qdot| <= speed_limit`` of a (e.g. position) actuator. **An approximation**: a real
  motor's speed falls with torque (the datasheet's speed-torque line), so the box promises
  more than the motor gives at high torque and speed together;
* ``polygon``: the vertices (|tau| N m, |qdot| rad/s) of a down-closed polygon, as given.
"""

from __future__ import annotations

import fnmatch
import json
import threading
from collections import OrderedDict
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from mjtvm.errors import MjtvmError
from mjtvm.grasp.actuation.actuator import operation_range_from_actuator
from mjtvm.grasp.actuation.datasheets import from_datasheet_entry, shipped_datasheets
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.grasp.document.checks import GraspError, key_of
from mjtvm.model.operation_range import OperationRange

__all__ = ["MEMO_SIZE", "RangesMemo", "actuator_ranges", "joint_ranges", "range_entry", "shipped_datasheets"]

_HINT = (
    'add [ranges."{j}"] (or a glob pattern, or "*") with one of: dcmotor = true, '
    'datasheet = "maxon_re25_20w" (+ gear_ratio), actuator = true + speed_limit, polygon = [...]'
)


#: Results a `mjtvm.grasp.actuation.ranges.RangesMemo` keeps, the last used: a
#: hand whose moments vary with the configuration (a spatial tendon) misses every time, and
#: the memo must not grow with the dataset.
MEMO_SIZE = 8

RangesMemo = OrderedDict[tuple[Any, ...], Any]
"""A memo of [`joint_ranges()`][mjtvm.grasp.actuation.ranges.joint_ranges] and
[`actuator_ranges()`][mjtvm.grasp.actuation.ranges.actuator_ranges] (``memo=``): an empty
``OrderedDict`` the caller keeps across the grasps of one document (``BatchModels``)."""

# Every model field the ranges are read from (here, in operation_range_from_actuator and in
# the names behind model.joint(name) and model.actuator(name)): a memo's key holds their
# bytes, so a model that differs in any of them is read anew. The configuration is not among
# them: the ranges depend on it only through the moment, which is part of the key too.
_READ_FIELDS = (
    "names",
    "name_actuatoradr",
    "name_jntadr",
    "actuator_trntype",
    "actuator_trnid",
    "actuator_gear",
    "actuator_forcelimited",
    "actuator_forcerange",
    "actuator_gaintype",
    "actuator_gainprm",
    "actuator_biasprm",
    "actuator_damping",
    "actuator_dampingpoly",
    "actuator_ctrlspec",
    "actuator_ctrladr",
    "actuator_ctrlnum",
    "actuator_ctrllimited",
    "actuator_ctrlrange",
    "jnt_actfrclimited",
    "jnt_actfrcrange",
    "jnt_dofadr",
    "dof_damping",
    "dof_frictionloss",
)

_LOCK = threading.Lock()

_Found = tuple[dict[str, OperationRange], dict[str, DCMotor | str | None]]


def _memoized(
    memo: RangesMemo | None,
    model: mujoco.MjModel,
    ranges: Mapping[str, Any],
    parts: tuple[Any, ...],
    compute: Callable[[], _Found],
) -> _Found:
    """``compute()``, or the memo's result for the key of ``parts`` and the bytes of the model's
    `_READ_FIELDS` (copies of its dicts): of the same ``ranges`` object only, not another at a
    reused id. Without a memo nothing is keyed."""
    if memo is None:
        return compute()
    fields = (getattr(model, f) for f in _READ_FIELDS)
    key = (id(ranges), *parts, *(v if isinstance(v, bytes) else v.tobytes() for v in fields))
    with _LOCK:  # a Dask worker's threads share one batch, and so its memo
        hit = memo.get(key)
        if hit is not None and hit[0] is ranges:
            memo.move_to_end(key)
            return dict(hit[1]), dict(hit[2])
    found = compute()
    with _LOCK:
        memo[key] = (ranges, dict(found[0]), dict(found[1]))
        while len(memo) > MEMO_SIZE:
            memo.popitem(last=False)
    return found


def range_entry(ranges: Mapping[str, Mapping[str, Any]], joint: str) -> tuple[str, Mapping[str, Any]] | None:
    """The ``(key, entry)`` of ``ranges`` that applies to ``joint`` (module docstring), or None."""
    if joint in ranges:
        return joint, ranges[joint]
    for key, entry in ranges.items():
        if key != "*" and fnmatch.fnmatchcase(joint, key):
            return key, entry
    return ("*", ranges["*"]) if "*" in ranges else None


def _drivers(model: mujoco.MjModel, j: int) -> list[int]:
    return [
        a
        for a in range(model.nactuator)
        if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT)
        and int(model.actuator_trnid[a, 0]) == j
    ]


def _actuator(model: mujoco.MjModel, j: int, joint: str, value: Any, fail: Any) -> int:
    if isinstance(value, str):
        a = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, value)
        if a < 0:
            raise fail(f"actuator {value!r} is not in the model")
        if int(model.actuator_trnid[a, 0]) != j or int(model.actuator_trntype[a]) != int(
            mujoco.mjtTrn.mjTRN_JOINT
        ):
            raise fail(f"actuator {value!r} does not drive joint {joint!r}")
        return int(a)
    drivers = _drivers(model, j)
    if len(drivers) != 1:
        if not drivers:
            raise fail(
                "no actuator drives this joint (a passive joint): give its range as a datasheet or a polygon"
            )
        raise fail(f"{len(drivers)} actuators drive this joint: name one")
    return drivers[0]


def _force_limit(model: mujoco.MjModel, a: int, fail: Any) -> float:
    """The largest force (or torque) of actuator ``a`` both ways: its ``forcerange``."""
    if not model.actuator_forcelimited[a]:
        raise fail("the actuator has no forcerange: give a datasheet or a polygon instead")
    lo, hi = model.actuator_forcerange[a]
    return min(-float(lo), float(hi))


def _box(model: mujoco.MjModel, a: int, j: int, speed: float, fail: Any) -> OperationRange:
    """gear x forcerange (capped by the joint's actuatorfrcrange) by the speed limit: a box."""
    torque = abs(float(model.actuator_gear[a, 0])) * _force_limit(model, a, fail)
    if model.jnt_actfrclimited[j]:
        flo, fhi = model.jnt_actfrcrange[j]
        torque = min(torque, -float(flo), float(fhi))
    if not torque > 0:
        raise fail("the actuator's force range gives no positive torque")
    return OperationRange.box(torque, speed)


def joint_ranges(
    model: mujoco.MjModel,
    joints: tuple[str, ...],
    ranges: Mapping[str, Mapping[str, Any]],
    *,
    base: Path | None,
    file: str,
    losses: bool = True,
    memo: RangesMemo | None = None,
) -> tuple[dict[str, OperationRange], dict[str, DCMotor | str | None]]:
    r"""Operation range and motor of each joint (module docstring).

    With ``losses`` (the grasp file's ``joint_losses = "fold"``, the default) each range is the
    torque left after the joint's own damping and friction loss in the model
    ([`with_losses()`][mjtvm.model.operation_range.OperationRange.with_losses]): public hand models often
    carry joint damping (the Allegro's 1 N m s/rad eats 1.5 N m at 1.5 rad/s, more than its
    0.7 N m motors give), which the motor must overcome before it moves the object.

    Returns
    -------
    ranges
        Joint name -> `OperationRange` at the joint.
    motors
        Joint name -> a `DCMotor` (datasheet source), ``None`` when the
        model's own ``<dcmotor>`` drives it, or a string saying why there is no motor model
        (the physics check refuses such joints with it).

    Raises
    ------
    GraspError
        A joint without an entry (the message says how to give one), or an entry that
        does not fit the model (named by its key).

    ``memo``: a `mjtvm.grasp.actuation.ranges.RangesMemo` the caller keeps; the
    result is then computed once per ``ranges`` object, joints, ``base``, ``file``, ``losses``
    and model fields it reads (a datasheet file is read once per memo).
    """
    return _memoized(
        memo, model, ranges, ("joint", tuple(joints), base, file, losses),
        lambda: _joint_ranges(model, joints, ranges, base=base, file=file, losses=losses),
    )  # fmt: skip


def _joint_ranges(
    model: mujoco.MjModel,
    joints: tuple[str, ...],
    ranges: Mapping[str, Mapping[str, Any]],
    *,
    base: Path | None,
    file: str,
    losses: bool,
) -> _Found:
    out: dict[str, OperationRange] = {}
    motors: dict[str, DCMotor | str | None] = {}
    for joint in joints:
        found = range_entry(ranges, joint)
        if found is None:
            raise GraspError(
                file,
                f"ranges.{key_of(joint)}",
                "no operation range for this joint: " + _HINT.format(j=json.dumps(joint)[1:-1]),
            )
        key, entry = found
        j = int(model.joint(joint).id)

        def fail(problem: str, key: str = key, joint: str = joint) -> GraspError:
            return GraspError(file, f"ranges.{key_of(key)}", f"joint {joint!r}: {problem}")

        source = entry["source"]
        if source == "dcmotor":
            a = _actuator(model, j, joint, entry["dcmotor"], fail)
            try:
                out[joint] = operation_range_from_actuator(model, a)
            except MjtvmError as e:
                raise fail(str(e)) from e
            motors[joint] = None
        elif source == "datasheet":
            out[joint], motors[joint] = from_datasheet_entry(entry, base, fail)
        elif source == "actuator":
            a = _actuator(model, j, joint, entry["actuator"], fail)
            out[joint] = _box(model, a, j, float(entry["speed_limit"]), fail)
            motors[joint] = "its range is an actuator's force range and a speed limit, not a motor model"
        else:
            try:
                out[joint] = OperationRange(np.array(entry["polygon"], dtype=float))
            except MjtvmError as e:
                raise fail(f"polygon: {e}") from e
            motors[joint] = "its range is a polygon, not a motor model"
        dof = int(model.jnt_dofadr[j])
        if losses and (model.dof_damping[dof] > 0 or model.dof_frictionloss[dof] > 0):
            try:
                out[joint] = out[joint].with_losses(
                    damping=float(model.dof_damping[dof]), friction=float(model.dof_frictionloss[dof])
                )
            except MjtvmError as e:
                raise fail(f"its damping and friction loss in the model leave no range: {e}") from e
    return out, motors


def _actuator_box(model: mujoco.MjModel, a: int, speed: float, fail: Any) -> OperationRange:
    """|u| <= forcerange (capped by a driven joint's actuatorfrcrange / gear), |s| <= speed."""
    force = _force_limit(model, a, fail)
    gear = abs(float(model.actuator_gear[a, 0]))
    if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT) and gear > 0:
        j = int(model.actuator_trnid[a, 0])
        if model.jnt_actfrclimited[j]:
            flo, fhi = model.jnt_actfrcrange[j]
            force = min(force, -float(flo) / gear, float(fhi) / gear)
    if not force > 0:
        raise fail("the actuator's force range gives no positive force")
    return OperationRange.box(force, speed)


def _output_to_actuator(rng: OperationRange, gear: float) -> OperationRange:
    """A range at the gear's output (the joint or tendon the actuator pulls on) in the actuator's
    units: MuJoCo's moment includes the gear g, so u = tau / g and s = g x speed."""
    if gear == 1.0:
        return rng
    return rng.scaled(torque=1.0 / gear, speed=gear)


def actuator_ranges(
    model: mujoco.MjModel,
    actuators: tuple[str, ...],
    moment: np.ndarray,
    dofs: tuple[int, ...],
    ranges: Mapping[str, Mapping[str, Any]],
    *,
    base: Path | None,
    file: str,
    losses: bool = True,
    memo: RangesMemo | None = None,
) -> tuple[dict[str, OperationRange], dict[str, DCMotor | str | None]]:
    r"""Operation range and motor of each actuator of a transmission (``docs/grasp-format.md``).

    The ranges are in the actuator's units: force ``u`` (MuJoCo's ``actuator_force``) and speed
    ``s = moment @ qd`` (``actuator_velocity``), the moment including the actuator's gear. An
    entry is found by the actuator's name as a joint's is ([`range_entry()`][mjtvm.grasp.actuation.ranges.range_entry]). Sources:

    * ``actuator = true`` (or the actuator's own name) + ``speed_limit``: the box
      ``|u| <= forcerange``, ``|s| <= speed_limit`` (s in the actuator's units: for the Shadow
      hand's tendon J2 + J1, rad/s of J2 + J1). **An approximation**, as for a joint;
    * ``datasheet``: the motor behind its ``gear_ratio``, the range at the gear's output, i.e.
      at the joint or tendon MuJoCo's actuator pulls on; converted with the actuator's MuJoCo
      gear g (u = tau / g, s = g x speed; g = 1 for the shipped hands);
    * ``dcmotor``: the model's ``<dcmotor>`` (a joint transmission only), converted likewise;
    * ``polygon``: vertices (|u|, |s|) as given.

    With ``losses`` the joints' friction loss is folded into the actuators' ranges: each
    actuator's force must overcome ``max_j frictionloss_j / |moment_aj|`` over the joints it
    moves (exact for an actuator on one joint, conservative for a tendon); a passive joint's
    friction loss has no actuator to take it and is not modelled. The joints' damping is not
    folded: the transmission carries it (``b qd`` in the balance).

    Raises
    ------
    GraspError
        An actuator without an entry (the message says how to give one), an ``actuator``
        entry naming another actuator, or an entry that does not fit the model.

    ``memo``: as [`joint_ranges()`][mjtvm.grasp.actuation.ranges.joint_ranges]'s, the
    ``moment`` (its bytes) and ``dofs`` part of the key: the ranges depend on the
    configuration only through the moment (constant for joint and fixed-tendon
    transmissions, not for a spatial tendon's moment arms).
    """
    moment = np.asarray(moment)
    parts = (
        "actuator", tuple(actuators), moment.dtype.str, moment.shape, moment.tobytes(),
        tuple(int(d) for d in dofs), base, file, losses,
    )  # fmt: skip
    return _memoized(
        memo, model, ranges, parts,
        lambda: _actuator_ranges(model, actuators, moment, dofs, ranges, base=base, file=file, losses=losses),
    )  # fmt: skip


def _actuator_ranges(
    model: mujoco.MjModel,
    actuators: tuple[str, ...],
    moment: np.ndarray,
    dofs: tuple[int, ...],
    ranges: Mapping[str, Mapping[str, Any]],
    *,
    base: Path | None,
    file: str,
    losses: bool,
) -> _Found:
    out: dict[str, OperationRange] = {}
    motors: dict[str, DCMotor | str | None] = {}
    hint = _HINT.replace("dcmotor = true, ", "dcmotor = true (joint actuators), ")
    for row, name in enumerate(actuators):
        found = range_entry(ranges, name)
        if found is None:
            raise GraspError(
                file,
                f"ranges.{key_of(name)}",
                "no operation range for this actuator (the hand has coupled joints: ranges are "
                "keyed by actuator): " + hint.format(j=json.dumps(name)[1:-1]),
            )
        key, entry = found
        a = int(model.actuator(name).id)

        def fail(problem: str, key: str = key, name: str = name) -> GraspError:
            return GraspError(file, f"ranges.{key_of(key)}", f"actuator {name!r}: {problem}")

        gear = abs(float(model.actuator_gear[a, 0])) or 1.0
        source = entry["source"]
        if source in ("actuator", "dcmotor") and isinstance(entry[source], str) and entry[source] != name:
            raise fail(
                f"names actuator {entry[source]!r}: a range keyed by actuator takes true or its own name"
            )
        if source == "dcmotor":
            try:
                out[name] = _output_to_actuator(operation_range_from_actuator(model, a), gear)
            except MjtvmError as e:
                raise fail(str(e)) from e
            motors[name] = None
        elif source == "datasheet":
            rng, motors[name] = from_datasheet_entry(entry, base, fail)
            out[name] = _output_to_actuator(rng, gear)
        elif source == "actuator":
            out[name] = _actuator_box(model, a, float(entry["speed_limit"]), fail)
            motors[name] = "its range is an actuator's force range and a speed limit, not a motor model"
        else:
            try:
                out[name] = OperationRange(np.array(entry["polygon"], dtype=float))
            except MjtvmError as e:
                raise fail(f"polygon: {e}") from e
            motors[name] = "its range is a polygon, not a motor model"
        arms = np.abs(moment[row])
        friction = max(
            (float(model.dof_frictionloss[d]) / r for d, r in zip(dofs, arms, strict=True) if r > 0),
            default=0.0,
        )
        if losses and friction > 0:
            try:
                out[name] = out[name].with_losses(damping=0.0, friction=friction)
            except MjtvmError as e:
                raise fail(f"the friction loss of its joints in the model leaves no range: {e}") from e
    return out, motors
