r"""The grasp-synthesis pipelines' own keys, mapped onto the dataset's (``docs/datasets.md``).

*DexGraspBench* (github.com/JYChen18/DexGraspBench, ``src/task/convert_format.py``) saves one
dict per grasp (``np.save(path, dict)``): ``obj_path`` (the object's folder, relative to the
benchmark's root), ``obj_pose`` (7: position, quaternion w-x-y-z), ``obj_scale``, and the hand's
``pregrasp_qpos``, ``grasp_qpos``, ``squeeze_qpos`` (7 + J each: root pose, then the joints);
some of its converters add ``approach_qpos``, ``lift_qpos`` and ``scene_path``, which are not
read. The pose ranked is chosen by ``pose``.

*DexGraspNet* (github.com/PKU-EPIC/DexGraspNet, ``grasp_generation/main.py``) saves one list of
dicts per object (``np.save(<object code>.npy, data_list)``): ``scale`` (the object mesh's scale
factor), ``qpos`` (joint name -> value, with the root's translation ``WRJTx``, ``WRJTy``,
``WRJTz`` in m and rotation ``WRJRx``, ``WRJRy``, ``WRJRz`` as static x-y-z Euler angles in rad,
transforms3d's ``sxyz``), ``qpos_st`` (the optimisation's start) and energies, not read. The
object sits at the world's origin, unrotated.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["POSES", "pipeline_row"]

POSES = ("grasp", "pregrasp", "squeeze")
"""The poses a DexGraspBench grasp carries: ``<pose>_qpos``."""

_BENCH_UNREAD = ("approach_qpos", "lift_qpos", "scene_path")
_NET_UNREAD = ("qpos_st", "energy", "E_fc", "E_dis", "E_pen", "E_spen", "E_joints")
_NET_ROOT = ("WRJTx", "WRJTy", "WRJTz", "WRJRx", "WRJRy", "WRJRz")


class PipelineKeyError(ValueError):
    """A pipeline's key missing or misplaced: ``(key, problem)``."""

    def __init__(self, key: str, problem: str) -> None:
        super().__init__(f"{key}: {problem}")
        self.key, self.problem = key, problem


def _quat_sxyz(rx: float, ry: float, rz: float) -> list[float]:
    """The unit quaternion (w-x-y-z) of static x-y-z Euler angles: R = Rz Ry Rx."""
    cx, sx = np.cos(rx / 2), np.sin(rx / 2)
    cy, sy = np.cos(ry / 2), np.sin(ry / 2)
    cz, sz = np.cos(rz / 2), np.sin(rz / 2)
    return [
        float(cz * cy * cx + sz * sy * sx),
        float(cz * cy * sx - sz * sy * cx),
        float(cz * sy * cx + sz * cy * sx),
        float(sz * cy * cx - cz * sy * sx),
    ]


def _net_row(values: Mapping[str, Any], joint_names: Sequence[str], pose: str) -> dict[str, Any]:
    if pose != "grasp":
        raise PipelineKeyError(
            "qpos", f"a DexGraspNet grasp has one pose (qpos): --pose {pose} does not apply"
        )
    qpos = values["qpos"]
    missing = [n for n in (*_NET_ROOT, *joint_names) if n not in qpos]
    if missing:
        raise PipelineKeyError(
            f"qpos.{missing[0]}", "missing (the root's WRJT*/WRJR* and every hand joint by name)"
        )
    extra = sorted(set(qpos) - set(_NET_ROOT) - set(joint_names))
    if extra:
        raise PipelineKeyError(f"qpos.{extra[0]}", "not a joint of the hand (hand_joints)")
    for k in (*_NET_ROOT, *joint_names):
        if isinstance(qpos[k], bool) or not isinstance(qpos[k], (int, float, np.integer, np.floating)):
            raise PipelineKeyError(f"qpos.{k}", f"expected a real number, got {type(qpos[k]).__name__}")
    root = [float(qpos[k]) for k in _NET_ROOT[:3]] + _quat_sxyz(*(float(qpos[k]) for k in _NET_ROOT[3:]))
    row: dict[str, Any] = {
        "grasp_qpos": root + [float(qpos[n]) for n in joint_names],
        "obj_pose": [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
    }
    if "scale" in values:
        row["obj_scale"] = values["scale"]
    unknown = sorted(set(values) - {"qpos", "scale", *_NET_UNREAD})
    if unknown:
        raise PipelineKeyError(
            unknown[0], "unknown key of a DexGraspNet grasp (scale, qpos, qpos_st, energies)"
        )
    return row


def pipeline_row(values: Mapping[str, Any], *, pose: str, joint_names: Sequence[str]) -> dict[str, Any]:
    r"""One grasp's values in the dataset's keys, the pose chosen.

    Parameters
    ----------
    values
        The grasp's keys as stored (a DexGraspBench dict, a DexGraspNet dict, or the dataset's
        own keys).
    pose
        ``grasp``, ``pregrasp`` or ``squeeze``: which ``<pose>_qpos`` becomes ``grasp_qpos``.
    joint_names
        The hand's joints (``hand_joints``), to read a DexGraspNet ``qpos`` by name.

    Raises
    ------
    PipelineKeyError
        The chosen pose missing, or a DexGraspNet ``qpos`` without a joint of the hand.
    """
    if isinstance(values.get("qpos"), Mapping):
        return _net_row(values, joint_names, pose)
    row = {k: v for k, v in values.items() if k not in _BENCH_UNREAD}
    chosen = f"{pose}_qpos"
    others = [f"{p}_qpos" for p in POSES if p != pose and p != "grasp"]
    if pose != "grasp":
        if chosen not in row:
            raise PipelineKeyError(chosen, f"missing: --pose {pose} ranks this pose")
        row["grasp_qpos"] = row.pop(chosen)
    for k in others:
        row.pop(k, None)
    return row
