r"""The model of a grasp file: its MJCF file as an ``MjSpec`` with the object and supports the
grasp adds, compiled; names looked up with the closest one suggested (``docs/grasp-format.md``).
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import mujoco

from mjtvm.grasp.document.document import GraspError
from mjtvm.grasp.resolve.state import subtree

__all__ = [
    "build_spec",
    "collision_bits",
    "geom_labels",
    "joint_id",
    "load_model",
    "model_path_of",
    "names_of",
    "object_geoms",
    "set_object_pose",
    "suggest",
]

_OBJ = mujoco.mjtObj
_SCALAR = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
_GEOM_TYPES = {
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE,
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE,
    "ellipsoid": mujoco.mjtGeom.mjGEOM_ELLIPSOID,
    "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
    "box": mujoco.mjtGeom.mjGEOM_BOX,
    "plane": mujoco.mjtGeom.mjGEOM_PLANE,
}


def suggest(name: str, candidates: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, candidates, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def names_of(model: mujoco.MjModel, kind: mujoco.mjtObj, count: int) -> list[str]:
    return [n for i in range(count) if (n := mujoco.mj_id2name(model, kind, i))]


def model_path_of(doc: Mapping[str, Any], path: Path | None, file: str) -> Path:
    model_path = Path(doc["model"])
    if not model_path.is_absolute() and path is not None:
        model_path = path.parent / model_path
    if not model_path.is_file():
        raise GraspError(file, "model", f"no such file: {str(model_path)!r}")
    return model_path


def collision_bits(spec: mujoco.MjSpec) -> int:
    """Every contype/conaffinity bit of the model's geoms: an added geom collides with every geom
    that collides with anything (visual geoms, with both 0, stay out)."""
    bits = 0
    for g in spec.geoms:
        bits |= int(g.contype) | int(g.conaffinity)
    return bits or 1


def build_spec(doc: Mapping[str, Any], model_path: Path, file: str) -> mujoco.MjSpec:
    r"""The model file as an ``MjSpec`` with the grasp's additions: the object, when the file
    gives its ``shape`` (a body on a free joint with one geom), and the ``supports`` (world
    geoms). Keyframes get the added object's pose appended, so that they stay valid."""
    try:
        spec = mujoco.MjSpec.from_file(str(model_path))
    except ValueError as e:  # MuJoCo's XML error
        raise GraspError(
            file, "model", f"MuJoCo cannot load {str(model_path)!r}: {' '.join(str(e).split())}"
        ) from e
    bits = collision_bits(spec)
    obj = doc["object"]
    if obj["shape"] is not None:
        if spec.body(obj["body"]) is not None:
            raise GraspError(
                file,
                "object.body",
                f"{obj['body']!r} is already a body of the model: "
                "drop shape, size and mass to use it, or choose another name",
            )
        # The added body's geom and free joint take its name too: MuJoCo refuses a repeated name.
        for kind, found in (("geom", spec.geom(obj["body"])), ("joint", spec.joint(obj["body"]))):
            if found is not None:
                raise GraspError(
                    file,
                    "object.body",
                    f"{obj['body']!r} is already a {kind} of the model: "
                    "the added object's body, geom and free joint take this name; choose another",
                )
        pos = obj["position"] or [0.0, 0.0, 0.0]
        quat = obj["quaternion"] or [1.0, 0.0, 0.0, 0.0]
        size = [*obj["size"], 0.0, 0.0][:3]
        try:
            body = spec.worldbody.add_body(name=obj["body"], pos=pos, quat=quat)
            body.add_freejoint(name=obj["body"])
            body.add_geom(
                name=obj["body"],
                type=_GEOM_TYPES[obj["shape"]],
                size=size,
                mass=obj["mass"],
                contype=bits,
                conaffinity=bits,
            )
        except ValueError as e:  # MuJoCo refuses the name
            raise GraspError(
                file, "object.body", f"MuJoCo refuses {obj['body']!r}: {' '.join(str(e).split())}"
            ) from e
        for key in spec.keys:
            if len(key.qpos):
                key.qpos = [*key.qpos, *pos, *quat]
    for i, sup in enumerate(doc["supports"]):
        if spec.geom(sup["name"]) is not None:
            raise GraspError(file, f"supports[{i}].name", f"{sup['name']!r} is already a geom of the model")
        try:
            spec.worldbody.add_geom(
                name=sup["name"],
                type=_GEOM_TYPES[sup["shape"]],
                size=sup["size"],
                pos=sup["position"],
                quat=sup["quaternion"],
                contype=bits,
                conaffinity=bits,
            )
        except ValueError as e:  # MuJoCo refuses the name
            raise GraspError(
                file, f"supports[{i}].name", f"MuJoCo refuses {sup['name']!r}: {' '.join(str(e).split())}"
            ) from e
    return spec


def load_model(doc: Mapping[str, Any], path: Path | None, file: str) -> tuple[mujoco.MjModel, Path]:
    model_path = model_path_of(doc, path, file)
    spec = build_spec(doc, model_path, file)
    try:
        return spec.compile(), model_path
    except ValueError as e:  # MuJoCo's compiler error
        raise GraspError(
            file, "model", f"MuJoCo cannot compile {str(model_path)!r}: {' '.join(str(e).split())}"
        ) from e


def joint_id(model: mujoco.MjModel, name: str, file: str, field: str) -> int:
    j = mujoco.mj_name2id(model, _OBJ.mjOBJ_JOINT, name)
    if j < 0:
        raise GraspError(
            file,
            field,
            f"{name!r} is not a joint of the model{suggest(name, names_of(model, _OBJ.mjOBJ_JOINT, model.njnt))}",
        )
    if int(model.jnt_type[j]) not in _SCALAR:
        raise GraspError(file, field, f"joint {name!r} is not a hinge or slide joint")
    return int(j)


def set_object_pose(
    model: mujoco.MjModel, data: mujoco.MjData, ob: int, obj: Mapping[str, Any], file: str
) -> None:
    if obj["position"] is None and obj["quaternion"] is None:
        return
    free = [j for j in range(model.njnt) if int(model.jnt_bodyid[j]) == ob]
    if len(free) != 1 or int(model.jnt_type[free[0]]) != int(mujoco.mjtJoint.mjJNT_FREE):
        raise GraspError(
            file, "object.position", "the object's pose can be set only on a body with one free joint"
        )
    adr = int(model.jnt_qposadr[free[0]])
    if obj["position"] is not None:
        data.qpos[adr : adr + 3] = obj["position"]
    if obj["quaternion"] is not None:
        data.qpos[adr + 3 : adr + 7] = obj["quaternion"]


def object_geoms(model: mujoco.MjModel, ob: int) -> list[int]:
    inside = subtree(model, ob)
    return [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) in inside]


def geom_labels(model: mujoco.MjModel) -> list[str]:
    """Every geom's name or label (``"<body>/geom<n>"``), the candidates of a misspelt geom."""
    from mjtvm.grasp.contacts.touch import geom_label

    return [geom_label(model, g) for g in range(model.ngeom)]
