r"""Grasp states from a MuJoCo model: the coupling between a simulation and the TVM core.

`grasp_state()` reads, at the configuration held in an ``mjData``, everything a
[`GraspState`][mjtvm.model.state.GraspState] needs: the contacts MuJoCo detects between the object and
the rest of the model, their Jacobians, the joints' gravity torques and operation ranges,
and the object's weight as the default REFS. Which contact is of which type (F, L, S, D) is
grasp data keyed by geom label, never derived here; which geoms touch is [`mjtvm.grasp.contacts.touch`][mjtvm.grasp.contacts.touch].

Frames and units: world frame, SI. Contact normals point into the object; Jacobians map the
state's joint velocities (rad/s) to the velocity (m/s) of the finger-side contact point.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, cast

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.actuator import operation_range_from_actuator
from mjtvm.grasp.actuation.transmission import (
    ModelTransmission,
    check_closed,
    is_independent,
    model_transmission,
)
from mjtvm.grasp.contacts.memo import contacts_once, scratch_copy
from mjtvm.grasp.contacts.touch import (
    DetectedContact,
    ancestors,
    detected_contacts,
    forward_touching,
    geom_id,
    geom_label,
    model_id,
    precise_collision,
    subtree,
    without_round_off,
)
from mjtvm.grasp.document.sections import JointLimitOptions
from mjtvm.model.contacts import CONTACT_TYPES, Contact
from mjtvm.model.limits import JointLimits
from mjtvm.model.operation_range import OperationRange, as_operation_range
from mjtvm.model.state import GraspState, SlipMode
from mjtvm.model.transmission import Transmission

# The contact detection lives in .touch and JointLimitOptions with the document's checks
# (.sections); their names are re-exported here, where the grasp state's callers have
# always found them.
__all__ = [
    "DetectedContact",
    "JointLimitOptions",
    "detected_contacts",
    "forward_touching",
    "geom_id",
    "geom_label",
    "grasp_state",
    "joint_limits_of",
    "limit_options",
    "model_id",
    "object_weight",
    "precise_collision",
    "subtree",
    "without_round_off",
]

_OBJ = mujoco.mjtObj


def limit_options(value: Mapping[str, float] | bool | None) -> JointLimitOptions | None:
    """The [`JointLimitOptions`][mjtvm.grasp.resolve.state.JointLimitOptions] of a grasp file's normalised ``joint_limits``
    (``false``: ``None``, no limits; a missing key: the defaults)."""
    if value is None or value is True:
        return JointLimitOptions()
    if value is False:
        return None
    return JointLimitOptions(**value)


def object_weight(
    model: mujoco.MjModel, data: mujoco.MjData, *, object_body: str = "object"
) -> NDArray[np.float64]:
    r"""``(6,)`` gravity wrench on the object subtree: [force (N); moment about its body origin (N m)].

    Each body contributes ``(1 - gravcomp) * mass * gravity`` at its centre of mass
    (``data.xipos``; call ``mj_kinematics`` or ``mj_forward`` first). World frame.
    """
    ob = model_id(model, _OBJ.mjOBJ_BODY, object_body, "body")
    origin = np.array(data.xpos[ob], dtype=float)
    wrench = np.zeros(6)
    for b in sorted(subtree(model, ob)):
        force = (
            (1.0 - float(model.body_gravcomp[b])) * float(model.body_mass[b]) * np.array(model.opt.gravity)
        )
        wrench[:3] += force
        wrench[3:] += np.cross(np.array(data.xipos[b]) - origin, force)
    return wrench


def _check_geoms(model: mujoco.MjModel, mapping: Mapping[str, object] | None, what: str) -> None:
    for key in mapping or {}:
        try:
            geom_id(model, key)
        except ModelError as e:
            raise ModelError(f"geom {key!r}", f"named in {what} but not in the model") from e


def _state_joints(model: mujoco.MjModel, joints: Sequence[str] | None, inside: set[int]) -> list[int]:
    scalar = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    if joints is None:
        ids = [
            j
            for j in range(model.njnt)
            if int(model.jnt_type[j]) in scalar and int(model.jnt_bodyid[j]) not in inside
        ]
        if not ids:
            raise ModelError("joints", "the model has no hinge or slide joint outside the object")
        return ids
    ids = []
    for name in joints:
        j = model_id(model, _OBJ.mjOBJ_JOINT, name, "joint")
        if int(model.jnt_type[j]) not in scalar:
            raise ModelError(f"joint {name!r}", "is not a hinge or slide joint")
        if int(model.jnt_bodyid[j]) in inside:
            raise ModelError(f"joint {name!r}", "moves the object, not a finger")
        ids.append(j)
    if not ids:
        raise ModelError("joints", "expected at least one joint")
    return ids


def _joint_range(model: mujoco.MjModel, j: int, name: str) -> OperationRange:
    drivers = [
        a
        for a in range(model.nactuator)
        if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT)
        and int(model.actuator_trnid[a, 0]) == j
    ]
    if len(drivers) != 1:
        problem = "no actuator drives it" if not drivers else f"{len(drivers)} actuators drive it"
        raise ModelError(f"joint {name!r}", f"{problem}; give its range in operation_ranges")
    return operation_range_from_actuator(model, drivers[0])


def grasp_state(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    *,
    contact_types: Mapping[str, str],
    mu: float | Mapping[str, float],
    refs: ArrayLike | None = None,
    rvds: ArrayLike | None = None,
    slide_directions: Mapping[str, ArrayLike] | None = None,
    object_body: str = "object",
    joints: Sequence[str] | None = None,
    operation_ranges: Mapping[str, OperationRange | ArrayLike] | None = None,
    one_contact_per_body: bool = True,
    friction_edges: int = 16,
    slip: SlipMode = "per_contact",
    contact_tolerance: float | None = None,
    joint_damping: bool = True,
    joint_limits: JointLimitOptions | None = JointLimitOptions(),  # noqa: B008 - frozen, so shared safely
    transmission: ModelTransmission | None = None,
) -> GraspState:
    r"""The grasp state (space = 3) at the configuration ``data.qpos``.

    Long only through its signature and parameter documentation (one keyword per option);
    the body is a short sequence of the named steps below it in this module.

    Works on a copy of ``data`` with zero velocities, after ``mj_forward``; ``data`` itself
    is not modified.

    Parameters
    ----------
    model, data
        The compiled model and the configuration.
    contact_types
        Geom name -> ``"F"``, ``"L"``, ``"S"`` or ``"D"``: the type of a contact between the
        object and that geom. Every geom touching the object needs an entry; entries of
        geoms not in contact are ignored (e.g. a palm the object has left).
    mu
        Friction coefficient of every contact, or geom name -> coefficient (required for
        the F and S contacts).
    refs
        ``(K, 6)`` REFS vertices [force; moment about the object origin]; default: the
        object's weight, one vertex (e.g. [0, 0, -mg, 0, 0, 0]).
    rvds
        ``(R, 6)`` RVDS vertices or ``None``.
    slide_directions
        Geom name -> ``(3,)`` slide direction of its S contact (the object's contact-point
        velocity relative to the finger's).
    object_body
        The object's body; its subtree is the object.
    joints
        The state's joints in order (hinge or slide); default: every hinge and slide joint
        outside the object, in model order.
    operation_ranges
        Joint name -> operation range, replacing the range read from the joint's actuator;
        with a transmission (below), actuator name -> operation range in the actuator's units,
        one for every driving actuator.
    one_contact_per_body
        See [`detected_contacts()`][mjtvm.grasp.contacts.touch.detected_contacts].
    friction_edges, slip
        Passed to [`GraspState`][mjtvm.model.state.GraspState].
    contact_tolerance
        A geom within this distance (m) of the object touches it ([`forward_touching()`][mjtvm.grasp.contacts.touch.forward_touching]);
        ``None``: the contacts MuJoCo reports.
    joint_damping
        With a transmission: the joints' ``dof_damping`` in the torque balance (``False``: none,
        as a grasp file's ``joint_losses = "ignore"``). Without one (each joint its own
        actuator's) this function puts no damping anywhere: the operation ranges given are
        used as they are, and a grasp file folds the model's damping and friction loss into
        them beforehand ([`joint_ranges()`][mjtvm.grasp.actuation.ranges.joint_ranges], ``joint_losses``).
    joint_limits
        The tolerance and horizon of the joints' position limits
        ([`JointLimitOptions`][mjtvm.grasp.resolve.state.JointLimitOptions]): each joint with ``jnt_limited`` carries its
        ``jnt_range`` and its ``qpos`` ([`joint_limits_of()`][mjtvm.grasp.resolve.state.joint_limits_of]); ``None``: no limits (the
        paper's LPs).
    transmission
        [`model_transmission()`][mjtvm.grasp.actuation.transmission.model_transmission] of ``joints`` at
        ``data``'s configuration, when the caller has it already (a grasp file's, read at the
        same configuration: [`Grasp.state()`][mjtvm.grasp.resolve.loaded.Grasp.state]); ``None``:
        read here.

    Returns
    -------
    GraspState
        ``object_position`` = the object body's origin (the sphere's centre); contacts named
        by their geom (``"<geom>#<k>"`` for a further contact of the same geom), positions
        MuJoCo's contact points, normals into the object, Jacobians ``(3, M)`` of the point
        fixed to the touching body (all zeros for the world body); ``gravity_torque`` =
        ``qfrc_bias - qfrc_passive`` at zero velocity, the bias torque: gravity plus the
        passive springs at the state, the joint torques that hold the fingers still.
        ``transmission``: read from MuJoCo at the configuration
        ([`model_transmission()`][mjtvm.grasp.actuation.transmission.model_transmission]) unless every driving
        actuator is a joint transmission on its own state joint and no equality acts on
        them ([`is_independent()`][mjtvm.grasp.actuation.transmission.is_independent]): then ``None`` and one
        operation range per joint, as in the paper; else the moment matrix, the equality
        rows and the damping, and one operation range per actuator.

    Raises
    ------
    ModelError
        Unknown body, joint or geom names (in the model or in the mappings), a joint without
        a single ``<dcmotor>``, a touching geom without type, an F/S contact without mu, an
        S contact without slide direction, or no contact between the object and a finger.
    """
    ob = model_id(model, _OBJ.mjOBJ_BODY, object_body, "body")
    joint_ids = _state_joints(model, joints, subtree(model, ob))
    names = [mujoco.mj_id2name(model, _OBJ.mjOBJ_JOINT, j) for j in joint_ids]
    dofs = np.array([int(model.jnt_dofadr[j]) for j in joint_ids])
    overrides = dict(operation_ranges or {})
    _check_mappings(model, contact_types, mu, slide_directions, overrides)
    work = scratch_copy(model, data, "state")  # nothing of it is kept: the state copies what it reads
    work.qvel[:] = 0.0
    mujoco.mj_forward(model, work)
    detected = _detect_contacts(model, work, object_body, joint_ids, one_contact_per_body, contact_tolerance)
    contacts = _contacts(model, work, detected, dofs, contact_types, mu, slide_directions)
    found = model_transmission(model, work, joint_ids) if transmission is None else transmission
    drive, ranges = _drive(model, joint_ids, names, overrides, joint_damping, found)
    gravity_torque = (work.qfrc_bias - work.qfrc_passive)[dofs]
    limits = None if joint_limits is None else joint_limits_of(model, work, joint_ids, joint_limits)
    if refs is None:
        refs = object_weight(model, work, object_body=object_body)[None, :]
    return GraspState(
        space=3,
        object_position=np.array(work.xpos[ob], dtype=float),
        joint_names=tuple(names),
        operation_ranges=ranges,
        gravity_torque=gravity_torque,
        contacts=tuple(contacts),
        refs=cast(NDArray[np.float64], refs),  # GraspState validates and converts
        rvds=cast(NDArray[np.float64] | None, rvds),
        friction_edges=friction_edges,
        slip=slip,
        transmission=drive,
        joint_limits=limits,
    )


def joint_limits_of(
    model: mujoco.MjModel, data: mujoco.MjData, joint_ids: Sequence[int], options: JointLimitOptions
) -> JointLimits | None:
    """The limits of the state's joints: ``jnt_range`` of each joint with ``jnt_limited``
    (a coupled hand's joints each their own) and its position ``qpos``; ``None`` when no
    joint is limited."""
    ids = np.asarray(joint_ids, dtype=int)
    limited = np.asarray(model.jnt_limited[ids], dtype=bool)
    if not limited.any():
        return None
    position = np.array(data.qpos[model.jnt_qposadr[ids]], dtype=float)
    lower = np.where(limited, model.jnt_range[ids, 0], -np.inf)
    upper = np.where(limited, model.jnt_range[ids, 1], np.inf)
    return JointLimits(position, lower, upper, options.tolerance, options.horizon)


def _drive(
    model: mujoco.MjModel,
    joint_ids: Sequence[int],
    names: Sequence[str],
    overrides: Mapping[str, OperationRange | ArrayLike],
    damping: bool,
    found: ModelTransmission,
) -> tuple[Transmission | None, tuple[OperationRange, ...]]:
    """The state's transmission (``None`` for independent joints) and its operation ranges,
    from the model's transmission ``found`` at the configuration."""
    independent = is_independent(model, found, joint_ids)
    keys = set(names) if independent else set(found.actuator_names)
    for key in sorted(set(overrides) - keys):  # a range under a name this path never reads
        raise ModelError(
            f"operation_ranges[{key!r}]",
            "names no "
            + (
                "joint of the state (each joint is driven by its own actuator here: key the ranges by joint)"
                if independent
                else "actuator driving the state's coupled joints (key the ranges by actuator)"
            ),
        )
    if independent:
        return None, tuple(
            as_operation_range(overrides[n]) if n in overrides else _joint_range(model, j, n)
            for j, n in zip(joint_ids, names, strict=True)
        )
    if not found.actuator_names:
        raise ModelError("joints", "no actuator drives any of the state's joints")
    check_closed(found)
    for a in found.actuator_names:
        if a not in overrides:
            raise ModelError(
                f"actuator {a!r}",
                "drives coupled joints: give its range (actuator units) in operation_ranges",
            )
    b = found.joint_damping if damping and np.any(found.joint_damping > 0) else None
    transmission = Transmission(
        actuator_names=found.actuator_names,
        moment=found.moment,
        constraint_names=found.constraint_names,
        constraint_jacobian=found.constraint_jacobian if found.constraint_names else None,
        joint_damping=b,
    )
    return transmission, tuple(as_operation_range(overrides[a]) for a in found.actuator_names)


def _check_mappings(
    model: mujoco.MjModel,
    contact_types: Mapping[str, str],
    mu: float | Mapping[str, float],
    slide_directions: Mapping[str, ArrayLike] | None,
    operation_ranges: Mapping[str, Any],
) -> None:
    """The contact types are known and every geom, joint and actuator named in the mappings exists."""
    for key, value in contact_types.items():
        if value not in CONTACT_TYPES:
            raise ModelError(
                f"contact_types[{key!r}]", f"expected one of {', '.join(CONTACT_TYPES)}, got {value!r}"
            )
    _check_geoms(model, contact_types, "contact_types")
    _check_geoms(model, mu if isinstance(mu, Mapping) else None, "mu")
    _check_geoms(model, slide_directions, "slide_directions")
    for key in operation_ranges:
        if mujoco.mj_name2id(model, _OBJ.mjOBJ_ACTUATOR, key) < 0:
            model_id(model, _OBJ.mjOBJ_JOINT, key, "joint")


def _detect_contacts(
    model: mujoco.MjModel,
    work: mujoco.MjData,
    object_body: str,
    joint_ids: Sequence[int],
    one_per_body: bool,
    tolerance: float | None,
) -> list[DetectedContact]:
    """The object's contacts ([`detected_contacts()`][mjtvm.grasp.contacts.touch.detected_contacts]); at least one must be on a finger
    (a body moved by one of ``joint_ids``)."""
    if tolerance is None:  # MuJoCo's own contacts at the configuration
        detected = detected_contacts(model, work, object_body=object_body, one_per_body=one_per_body)
    else:  # detected anew within the tolerance: once per configuration (a grasp's checks asked already)
        detected = contacts_once(
            model, work, object_body=object_body, one_per_body=one_per_body, tolerance=tolerance
        )
    moving = {int(model.jnt_bodyid[j]) for j in joint_ids}
    if not any(ancestors(model, c.body) & moving for c in detected):
        touching = sorted({c.geom for c in detected})
        raise ModelError(
            f"body {object_body!r}",
            f"no contact between the object and the fingers (touching: {touching or 'nothing'})",
        )
    return detected


def _contacts(
    model: mujoco.MjModel,
    work: mujoco.MjData,
    detected: Sequence[DetectedContact],
    dofs: NDArray[np.int64],
    contact_types: Mapping[str, str],
    mu: float | Mapping[str, float],
    slide_directions: Mapping[str, ArrayLike] | None,
) -> list[Contact]:
    """The state's contacts: type, friction and slide direction from the mappings, and the
    Jacobian ``(3, M)`` of the point fixed to the touching body over the state's ``dofs``."""
    contacts: list[Contact] = []
    seen: dict[str, int] = {}
    jacp = np.zeros((3, model.nv))
    for c in detected:
        if c.geom not in contact_types:
            raise ModelError(f"geom {c.geom!r}", "touches the object but has no entry in contact_types")
        ctype = contact_types[c.geom]
        seen[c.geom] = seen.get(c.geom, 0) + 1
        name = c.geom if seen[c.geom] == 1 else f"{c.geom}#{seen[c.geom] - 1}"
        coefficient = mu.get(c.geom) if isinstance(mu, Mapping) else mu
        if coefficient is None and ctype in ("F", "S"):
            raise ModelError(f"geom {c.geom!r}", f"its {ctype} contact needs a friction coefficient in mu")
        slide = None
        if ctype == "S":
            if slide_directions is None or c.geom not in slide_directions:
                raise ModelError(f"geom {c.geom!r}", "its S contact needs an entry in slide_directions")
            slide = np.asarray(slide_directions[c.geom], dtype=float)
        jacp[:] = 0.0
        if c.body > 0:
            mujoco.mj_jac(model, work, jacp, None, c.position, c.body)
        contacts.append(
            Contact(
                name=name,
                type=ctype,  # type: ignore[arg-type]  # checked against CONTACT_TYPES
                position=c.position,
                normal=c.normal,
                jacobian=without_round_off(jacp[:, dofs]),
                mu=None if coefficient is None else float(coefficient),
                slide_direction=slide,
            )
        )
    return contacts
