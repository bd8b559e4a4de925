r"""Joint values and a posed hand base from a grasp file's ``configuration`` (``docs/grasp-format.md``).

``configuration.qpos`` gives a hinge or slide joint one number and a free joint its 7 numbers
``[x, y, z, qw, qx, qy, qz]`` (MuJoCo's ``qpos`` layout: position in m, then a unit
quaternion); ``configuration.base`` poses one body that has a pose of its own: a mocap body
(``data.mocap_pos``/``mocap_quat``) or a body on a free joint (its ``qpos``). Both are set
after the keyframe (if any) and before IK, whose variables are hinge and slide joints only
(`solve_ik()`): a posed base stays where the file puts it.

World frame, SI units.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import mujoco

from mjtvm.grasp.document.checks import GraspError, key_of
from mjtvm.grasp.resolve.model import names_of, suggest

__all__ = ["hold_mocap_poses", "set_base_pose", "set_joint_values"]

_OBJ = mujoco.mjtObj
_JNT = mujoco.mjtJoint
_SCALAR = (int(_JNT.mjJNT_HINGE), int(_JNT.mjJNT_SLIDE))
_KEYFRAME = "set it from a keyframe (configuration.keyframe, the model's <key qpos=... mpos=... mquat=...>)"


def set_joint_values(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    values: Mapping[str, float | Sequence[float]],
    file: str,
    where: str,
) -> None:
    """Write ``values`` (joint name -> a number, or a free joint's 7 numbers) into ``data.qpos``.

    Raises
    ------
    GraspError
        ``<where>.<joint>``: not a joint of the model (with the closest name), a number for a
        free joint or 7 numbers for a hinge or slide joint, or a ball joint (whose
        quaternion a keyframe gives).
    """
    for name, value in values.items():
        field = f"{where}.{key_of(name)}"
        j = mujoco.mj_name2id(model, _OBJ.mjOBJ_JOINT, name)
        if j < 0:
            known = names_of(model, _OBJ.mjOBJ_JOINT, model.njnt)
            raise GraspError(file, field, f"{name!r} is not a joint of the model{suggest(name, known)}")
        kind, adr = int(model.jnt_type[j]), int(model.jnt_qposadr[j])
        if kind == int(_JNT.mjJNT_FREE):
            if not isinstance(value, Sequence) or len(value) != 7:
                raise GraspError(
                    file,
                    field,
                    f"joint {name!r} is a free joint: expected its 7 numbers [x, y, z, qw, qx, qy, qz] "
                    f"(m; unit quaternion), or configuration.base = {{ body = ..., position = [...], "
                    f"quaternion = [...] }}, or {_KEYFRAME}",
                )
            data.qpos[adr : adr + 7] = value
        elif kind in _SCALAR:
            if isinstance(value, Sequence):
                raise GraspError(
                    file, field, f"joint {name!r} is a hinge or slide joint: expected one number, got a list"
                )
            data.qpos[adr] = value
        else:
            raise GraspError(file, field, f"joint {name!r} is a ball joint: {_KEYFRAME}")


def set_base_pose(model: mujoco.MjModel, data: mujoco.MjData, base: Mapping[str, Any], file: str) -> None:
    r"""Pose ``base["body"]``: a mocap body's ``mocap_pos``/``mocap_quat``, or a free-jointed
    body's ``qpos``; ``position`` (m) and ``quaternion`` (w, x, y, z), each kept when ``None``.

    Raises
    ------
    GraspError
        ``configuration.base.body``: not a body of the model (with the closest name), or a
        body that is neither a mocap body nor on a free joint (its pose follows its parent's
        joints).
    """
    field = "configuration.base.body"
    name = str(base["body"])
    b = mujoco.mj_name2id(model, _OBJ.mjOBJ_BODY, name)
    if b < 0:
        known = names_of(model, _OBJ.mjOBJ_BODY, model.nbody)
        raise GraspError(file, field, f"{name!r} is not a body of the model{suggest(name, known)}")
    position, quaternion = base["position"], base["quaternion"]
    mocap = int(model.body_mocapid[b])
    if mocap >= 0:
        if position is not None:
            data.mocap_pos[mocap] = position
        if quaternion is not None:
            data.mocap_quat[mocap] = quaternion
        return
    free = [
        j
        for j in range(int(model.body_jntadr[b]), int(model.body_jntadr[b] + model.body_jntnum[b]))
        if int(model.jnt_type[j]) == int(_JNT.mjJNT_FREE)
    ]
    if not free:
        raise GraspError(
            file,
            field,
            f"body {name!r} is neither a mocap body nor on a free joint: its pose follows its parent "
            f"and its joints (set those in configuration.qpos), or {_KEYFRAME}",
        )
    adr = int(model.jnt_qposadr[free[0]])
    if position is not None:
        data.qpos[adr : adr + 3] = position
    if quaternion is not None:
        data.qpos[adr + 3 : adr + 7] = quaternion


def hold_mocap_poses(model: mujoco.MjModel, data: mujoco.MjData) -> None:
    """Copy the mocap bodies' poses of ``data`` (a keyframe's ``mpos``/``mquat``, a posed
    ``base``) into ``model.body_pos``/``body_quat``: every ``mjData`` made later from the
    model and a ``qpos`` (the lift's states, a replay) starts its mocap bodies there."""
    for b in range(model.nbody):
        mocap = int(model.body_mocapid[b])
        if mocap >= 0:
            model.body_pos[b] = data.mocap_pos[mocap]
            model.body_quat[b] = data.mocap_quat[mocap]
