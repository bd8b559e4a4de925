r"""The grasps of a dataset on one grasp file (``mjtvm rank``; ``docs/datasets.md``).

[`BatchModels`][mjtvm.grasp.resolve.batch.BatchModels] compiles the grasp file's model per (object file, scale), keeps the
`MODEL_CACHE_SIZE` most recently used, and
[`BatchModels.grasp()`][mjtvm.grasp.resolve.batch.BatchModels.grasp] builds one [`Grasp`][mjtvm.grasp.resolve.loaded.Grasp] per
[`DatasetGrasp`][mjtvm.grasp.document.dataset.DatasetGrasp] by
[`grasp_from_model()`][mjtvm.grasp.resolve.file.grasp_from_model]: the file's document (contacts, rules, ranges,
REFS, RVDS) with the dataset's configuration in place of the file's.

*The root pose.* ``grasp_qpos`` starts with the pose of the hand's root body in the world: the
file's ``configuration.base.body`` when it names one, else the one body under the world that is
neither the object nor a support. A root on a free joint takes the pose in its ``qpos``; a
root fixed to the world is made a mocap body (``MjSpec``, before compiling) so that it can be
posed ([`set_base_pose()`][mjtvm.grasp.resolve.base.set_base_pose]): the hand keeps its kinematics, only
where it stands changes, and gravity stays the world's.

*The object's scale* multiplies the object's geom sizes and positions, its meshes' scale and
its child bodies' positions; a geom's explicit mass is multiplied by the cube of the scale
(the same density), a mass from density follows from the scaled volume.

World frame, SI units.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from mjtvm.grasp.actuation.ranges import RangesMemo
from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.document.dataset import ROOT_SIZE, DatasetGrasp
from mjtvm.grasp.document.document import read_grasp_document
from mjtvm.grasp.resolve.file import grasp_from_model, shipped_grasps
from mjtvm.grasp.resolve.loaded import Grasp
from mjtvm.grasp.resolve.model import build_spec, model_path_of
from mjtvm.grasp.resolve.objects import com_position, folder_object, shift_frame, subtree_mass

__all__ = ["BatchModels", "hand_joints"]

_OBJ = mujoco.mjtObj
_JNT = mujoco.mjtJoint
_SCALAR = (int(_JNT.mjJNT_HINGE), int(_JNT.mjJNT_SLIDE))


def _subtree(model: mujoco.MjModel, body: int) -> set[int]:
    inside = {body}
    for b in range(body + 1, model.nbody):
        if int(model.body_parentid[b]) in inside:
            inside.add(b)
    return inside


def hand_joints(model: mujoco.MjModel, object_body: str) -> tuple[str, ...]:
    """The hinge and slide joints outside the object's subtree, in model order: the joints of
    ``grasp_qpos`` after its root pose."""
    inside = _subtree(model, int(model.body(object_body).id))
    return tuple(
        model.joint(j).name
        for j in range(model.njnt)
        if int(model.jnt_type[j]) in _SCALAR and int(model.jnt_bodyid[j]) not in inside
    )


def _root_body(spec: mujoco.MjSpec, doc: Mapping[str, Any], file: str) -> str:
    base = doc["configuration"].get("base")
    if base is not None:
        return str(base["body"])
    others = [b.name for b in spec.worldbody.bodies if b.name != doc["object"]["body"]]
    if len(others) != 1:
        raise GraspError(
            file,
            "configuration.base.body",
            f"grasp_qpos's root pose needs the hand's root body: the world has {len(others)} bodies "
            f"besides the object ({', '.join(map(repr, others)) or 'none'}); name it in configuration.base",
        )
    return str(others[0])


def _scale_object(spec: mujoco.MjSpec, name: str, scale: float) -> None:
    top = spec.body(name)
    scaled_meshes: set[str] = set()
    todo = [top]
    while todo:
        body = todo.pop()
        if body is not top:
            body.pos = np.asarray(body.pos) * scale
        if body.explicitinertial:
            body.mass *= scale**3
            body.inertia = np.asarray(body.inertia) * scale**5
            body.ipos = np.asarray(body.ipos) * scale
        for g in body.geoms:
            g.pos = np.asarray(g.pos) * scale
            if g.type == mujoco.mjtGeom.mjGEOM_MESH:
                if g.meshname not in scaled_meshes:
                    mesh = spec.mesh(g.meshname)
                    mesh.scale = np.asarray(mesh.scale) * scale
                    scaled_meshes.add(g.meshname)
            else:
                g.size = np.asarray(g.size) * scale
            if not np.isnan(g.mass):
                g.mass *= scale**3
        todo.extend(body.bodies)


def _replace_object(
    spec: mujoco.MjSpec, name: str, obj_path: str, file: str, other: mujoco.MjSpec | None = None
) -> None:
    """Put the first body of ``obj_path``'s world (or of ``other``, built from it), named
    ``name``, in place of the file's object."""
    try:
        other = other or mujoco.MjSpec.from_file(obj_path)
    except ValueError as e:
        raise GraspError(
            file, "obj_path", f"MuJoCo cannot load {obj_path!r}: {' '.join(str(e).split())}"
        ) from e
    bodies = list(other.worldbody.bodies)
    if not bodies:
        raise GraspError(file, "obj_path", f"{obj_path!r} has no body under its world")
    old = spec.body(name)
    pos, quat = np.array(old.pos), np.array(old.quat)
    spec.delete(old)
    frame = spec.worldbody.add_frame(pos=pos, quat=quat)
    body = bodies[0]
    body.name = name
    for j in body.joints:  # the object's free joint keeps the grasp file's name: set_object_pose finds it
        if j.type == _JNT.mjJNT_FREE:
            j.name = name
    frame.attach_body(body, "obj/", "")
    attached = spec.body(f"obj/{name}")
    if attached is not None:
        attached.name = name


#: Compiled models a `BatchModels` keeps, least recently used out: a dataset of many object
#: files or scales (a scale per grasp is common) recompiles instead of growing without
#: bound (about 0.3 MiB per Shadow-hand model), and a dataset grouped by object reuses each.
MODEL_CACHE_SIZE = 16

#: Every this many models dropped from a cache, the C heap's freed pages go back to the
#: system (glibc's ``malloc_trim``): a compile per grasp otherwise leaves the freed models'
#: memory fragmented, and the resident set of a 1,600-grasp ranking grew by 6.6 MiB past its
#: first 400 grasps with it kept (1.8 MiB with it returned; the Python heap flat either way).
TRIM_EVERY = 32


def _release_freed_memory() -> None:
    """Return the C heap's free pages to the system where glibc is the allocator (else nothing)."""
    global _TRIM
    if _TRIM is None:
        try:
            import ctypes
            import ctypes.util

            _TRIM = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").malloc_trim
        except (OSError, AttributeError):  # not glibc (macOS, Windows, musl): nothing to trim
            _TRIM = False
    if _TRIM:
        _TRIM(0)


_TRIM: Any = None


class BatchModels:
    """The grasp file's model, compiled per (object file, scale, posed root) and kept for the
    `MODEL_CACHE_SIZE` most recently used of them, and the grasps of the dataset built on it.

    Parameters
    ----------
    doc, path
        The normalised grasp document and its file
        (`read_grasp_document()`).
    cache_size
        Compiled models kept (>= 1).
    """

    def __init__(
        self, doc: Mapping[str, Any], path: Path | None, *, cache_size: int = MODEL_CACHE_SIZE
    ) -> None:
        self.doc, self.path = doc, path
        self.file = str(path) if path is not None else "grasp"
        self.model_path = model_path_of(doc, path, self.file)
        self.cache_size = max(1, int(cache_size))
        self._spec: mujoco.MjSpec | None = None  # the grasp file's model, as parsed
        # key -> (compiled model, its posable root body's name or None), oldest first
        self._models: OrderedDict[tuple[str | None, float, bool], tuple[mujoco.MjModel, str | None]] = (
            OrderedDict()
        )
        # (object file, scale) -> the centre of mass offset and its model (--com-frame), oldest first
        self._com: dict[tuple[str | None, float], np.ndarray] = {}
        self._com_models: OrderedDict[tuple[str | None, float], mujoco.MjModel] = OrderedDict()
        self._dropped = 0  # models dropped from the caches (TRIM_EVERY)
        self._ranges: RangesMemo = RangesMemo()  # the grasps' operation ranges (grasp_from_model)

    @classmethod
    def from_file(cls, source: str | Path) -> BatchModels:
        """The batch models of a grasp file, or of a shipped grasp by name.

        Raises
        ------
        GraspError
            The file does not read or breaks the format.
        """
        doc, path = read_grasp_document(shipped_grasps().get(str(source), source))
        return cls(doc, path)

    def model(self, obj_path: str | None = None, scale: float = 1.0, *, root: bool = False) -> mujoco.MjModel:
        """The compiled model for an object file and scale; ``root``: with a posable root body.

        Raises
        ------
        GraspError
            The model, the object file or the root body.
        """
        return self._compiled(obj_path, scale, root)[0]

    def spec(self, entry: DatasetGrasp) -> mujoco.MjSpec:
        """A fresh ``MjSpec`` of the model the entry's grasp is built on (its object file and
        scale, its posed root, its centre-of-mass frame): compiled, it has the grasp's model's
        bodies, geoms and meshes, e.g. to attach motors (``mjtvm.physics``) before compiling.

        Raises
        ------
        GraspError
            As [`model()`][mjtvm.grasp.resolve.batch.BatchModels.model].
        """
        root = entry.root is not None
        spec, _ = self._edited_spec(entry.obj_path, entry.obj_scale, root)
        if entry.com_frame:  # as _com_model: the frame moved to the centre of mass
            name = self.doc["object"]["body"]
            model = self.model(entry.obj_path, entry.obj_scale, root=root)
            shift_frame(spec, name, np.array(model.body_ipos[int(model.body(name).id)]))
        return spec

    def _compiled(self, obj_path: str | None, scale: float, root: bool) -> tuple[mujoco.MjModel, str | None]:
        """The cache's entry of a key (compiled on a miss; the oldest entry dropped when full)."""
        key = (obj_path, float(scale), root)
        if key in self._models:
            self._models.move_to_end(key)
        else:
            spec, body = self._edited_spec(obj_path, scale, root)
            self._models[key] = (self._compile(spec), body)
            while len(self._models) > self.cache_size:
                self._models.popitem(last=False)
                self._dropped += 1
                if self._dropped % TRIM_EVERY == 0:
                    _release_freed_memory()
        return self._models[key]

    def _edited_spec(
        self, obj_path: str | None, scale: float, root: bool
    ) -> tuple[mujoco.MjSpec, str | None]:
        """A copy of the grasp file's model (parsed once) with the object file in place of the
        object and scaled; ``root``: with its root body posable (a mocap body unless it has a
        free joint). Returns the spec and the root body's name (None without ``root``)."""
        if self._spec is None:  # parsed once: every compile edits its own copy
            self._spec = build_spec(self.doc, self.model_path, self.file)
        spec = self._spec.copy()
        name = self.doc["object"]["body"]
        folder = obj_path is not None and Path(obj_path).is_dir()
        if obj_path is not None:
            other = None
            if folder:  # scaled as it is built, at the grasp file's object mass
                mass = subtree_mass(self.model(), name)
                other = folder_object(obj_path, mass=mass, scale=scale, file=self.file)
            _replace_object(spec, name, obj_path, self.file, other)
        if scale != 1.0 and not folder:
            _scale_object(spec, name, scale)
        if not root:
            return spec, None
        body = _root_body(spec, self.doc, self.file)
        found = spec.body(body)
        if found is None:
            raise GraspError(self.file, "configuration.base.body", f"{body!r} is not a body of the model")
        if found.parent.name == spec.worldbody.name and not any(
            j.type == _JNT.mjJNT_FREE for j in found.joints
        ):
            found.mocap = True
        return spec, body

    def _compile(self, spec: mujoco.MjSpec) -> mujoco.MjModel:
        try:
            return spec.compile()
        except ValueError as e:
            raise GraspError(self.file, "model", f"MuJoCo cannot compile: {' '.join(str(e).split())}") from e

    def grasp(self, entry: DatasetGrasp, *, max_penetration: float | None = None) -> Grasp:
        """The grasp of one dataset entry (the file's document at the entry's configuration;
        ``max_penetration``, m, in place of the file's when given: ``math.inf`` refuses no
        penetration).

        Raises
        ------
        GraspError
            As [`grasp_from_model()`][mjtvm.grasp.resolve.file.grasp_from_model], or a ``qpos`` whose joints
            cannot be named (an unnamed or ball joint).
        """
        root = entry.root is not None
        key = (entry.obj_path, float(entry.obj_scale), root)
        model, root_body = self._compiled(entry.obj_path, entry.obj_scale, root)
        if entry.com_frame:
            model = self._com_model(entry, model)
        obj = dict(self.doc["object"])
        config: dict[str, Any]
        if entry.qpos is not None:
            config = {"qpos": _named_qpos(model, entry, self.file)}
            ob = int(model.body(obj["body"]).id)
            free = [j for j in range(model.njnt) if int(model.jnt_bodyid[j]) == ob]
            if len(free) == 1 and int(model.jnt_type[free[0]]) == int(_JNT.mjJNT_FREE):
                adr = int(model.jnt_qposadr[free[0]])
                obj["position"] = [float(x) for x in entry.qpos[adr : adr + 3]]
                obj["quaternion"] = [float(x) for x in entry.qpos[adr + 3 : adr + 7]]
        else:
            assert entry.root is not None and entry.joints is not None
            names = hand_joints(model, obj["body"])
            config = {
                "qpos": {n: float(v) for n, v in zip(names, entry.joints, strict=True)},
                "base": {
                    "body": root_body,
                    "position": [float(x) for x in entry.root[:3]],
                    "quaternion": [float(x) for x in entry.root[3:ROOT_SIZE]],
                },
            }
        if entry.obj_pose is not None:
            obj["position"] = [float(x) for x in entry.obj_pose[:3]]
            obj["quaternion"] = [float(x) for x in entry.obj_pose[3:]]
        if entry.com_frame:  # the same object, posed by its old frame: the new origin is at p + R c
            if obj.get("position") is None:
                raise GraspError(
                    entry.source,
                    f"grasp {entry.index}: obj_pose",
                    "the centre-of-mass frame needs the object's pose",
                )
            obj["position"] = com_position(obj, self._com[key[:2]])
        doc = {**self.doc, "configuration": config, "object": obj}
        if max_penetration is not None:
            doc["max_penetration"] = float(max_penetration)
        return grasp_from_model(doc, self.path, model, self.model_path, memo=self._ranges)

    def _com_model(self, entry: DatasetGrasp, model: mujoco.MjModel) -> mujoco.MjModel:
        """The entry's model with the object's frame at its centre of mass (compiled once)."""
        name = self.doc["object"]["body"]
        key = (entry.obj_path, float(entry.obj_scale))
        if key not in self._com_models:
            offset = np.array(model.body_ipos[int(model.body(name).id)])
            spec, _ = self._edited_spec(entry.obj_path, entry.obj_scale, entry.root is not None)
            shift_frame(spec, name, offset)
            self._com_models[key] = self._compile(spec)
            self._com[key] = offset
            while len(self._com_models) > self.cache_size:  # bounded as the plain models
                dropped, _ = self._com_models.popitem(last=False)
                self._com.pop(dropped, None)
                self._dropped += 1
                if self._dropped % TRIM_EVERY == 0:
                    _release_freed_memory()
        self._com_models.move_to_end(key)
        return self._com_models[key]


def _named_qpos(model: mujoco.MjModel, entry: DatasetGrasp, file: str) -> dict[str, Any]:
    assert entry.qpos is not None
    values: dict[str, Any] = {}
    for j in range(model.njnt):
        name, kind, adr = model.joint(j).name, int(model.jnt_type[j]), int(model.jnt_qposadr[j])
        if kind == int(_JNT.mjJNT_BALL) or not name:
            raise GraspError(
                file,
                f"grasp {entry.index}: qpos",
                f"joint {j} is {'a ball joint' if name else 'unnamed'}: use grasp_qpos",
            )
        values[name] = (
            [float(x) for x in entry.qpos[adr : adr + 7]]
            if kind == int(_JNT.mjJNT_FREE)
            else float(entry.qpos[adr])
        )
    return values
