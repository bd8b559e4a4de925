r"""A grasp of any MJCF hand, from a ``mjtvm.grasp/1`` file (``docs/grasp-format.md``).

[`load_grasp()`][mjtvm.grasp.resolve.file.load_grasp] reads a grasp file (`mjtvm.grasp.document.document`), loads the model it names,
sets the configuration (a keyframe, joint values, or IK targets brought onto the object's
surface), resolves the contact selections (geom name or label, body, geom id) against the
model, types by the file's ``contact_rules`` the touching geoms no entry selects
([`mjtvm.grasp.resolve.rules`][mjtvm.grasp.resolve.rules]) and finds each joint's operation range
(`mjtvm.grasp.actuation.ranges`), or, when the model's actuators or equality constraints
couple the joints, the transmission ([`mjtvm.grasp.actuation.transmission`][mjtvm.grasp.actuation.transmission]) and each
actuator's range. [`state()`][mjtvm.grasp.resolve.loaded.Grasp.state]
then gives the [`GraspState`][mjtvm.model.state.GraspState] of
`grasp_state()`.

*Contacts that touch.* Geoms placed exactly touching are often reported by MuJoCo only once
they penetrate; a grasp file's ``contact_tolerance`` (default 0.1 mm) counts a geom within
that distance of the object as touching: MuJoCo's collision runs with that margin on the
object's geoms for detection only (`grasp_state()`). Every selection
must touch (else an error gives the nearest distance, from ``mj_geomDistance``) and every
touching geom must be selected or ignored; [`contact_report()`][mjtvm.grasp.resolve.loaded.Grasp.contact_report] lists found vs
expected.

World frame, SI units.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any

import mujoco
import numpy as np

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.ranges import RangesMemo, actuator_ranges, joint_ranges
from mjtvm.grasp.actuation.transmission import (
    ModelTransmission,
    check_closed,
    coupled_joints,
    is_independent,
    model_transmission,
)
from mjtvm.grasp.document.checks import GraspError, NoContactError, key_of
from mjtvm.grasp.document.document import read_grasp_document
from mjtvm.grasp.resolve.configure import configured_data
from mjtvm.grasp.resolve.loaded import Grasp, document_refs
from mjtvm.grasp.resolve.model import (
    build_spec,
    geom_labels,
    joint_id,
    load_model,
    names_of,
    object_geoms,
    suggest,
)
from mjtvm.grasp.resolve.rules import RuleMatch, expand_rules, nearest_distance, touching_geoms
from mjtvm.grasp.resolve.state import (
    geom_id,
    geom_label,
    subtree,
)
from mjtvm.grasp.resolve.variants import with_hand
from mjtvm.model.friction import cone_margin
from mjtvm.model.state import GraspState

__all__ = [
    "Grasp",
    "build_spec",
    "export_state",
    "grasp_from_model",
    "load_grasp",
    "models_root",
    "shipped_grasps",
]

_OBJ = mujoco.mjtObj
_SCALAR = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))


# ------------------------------------------------------------------ loading
def models_root() -> Path:
    """The folder of the shipped hands and grasp files: the installed package ``mjtvm.models``,
    or the checkout's ``models/`` beside ``mjtvm/`` when mjtvm is imported from a source tree
    (``pyproject.toml`` maps the top-level folder into the installed package only, so a test
    run from the repository, which imports the checkout's ``mjtvm``, has no such package)."""
    try:
        return Path(str(resources.files("mjtvm.models")))
    except ModuleNotFoundError:
        return Path(__file__).resolve().parents[3] / "models"


def shipped_grasps() -> dict[str, Path]:
    """Name -> path of every grasp file shipped in ``models/<hand>/`` ([`models_root()`][mjtvm.grasp.resolve.file.models_root])."""
    return {p.stem: p for p in sorted(models_root().glob("*/*.toml"))}


def _resolve(source: str | Path | Mapping[str, Any]) -> str | Path | Mapping[str, Any]:
    """A shipped grasp's name becomes its path; paths and mappings pass."""
    if isinstance(source, str) and not source.endswith((".toml", ".json")) and "/" not in source:
        shipped = shipped_grasps()
        if source not in shipped:
            raise GraspError(
                source, "", f"no such grasp file, and not a shipped grasp (shipped: {', '.join(shipped)})"
            )
        return shipped[source]
    return source


def _select(
    model: mujoco.MjModel, sel: Mapping[str, Any], ob: int, file: str, field: str
) -> tuple[str, list[int]]:
    """The geoms of one selection (``geom``: name or label; ``body``: all its geoms; ``geom_id``)."""
    kind, target = sel["select"], sel["target"]
    if kind == "geom":
        try:
            ids = [geom_id(model, target)]
        except ModelError as e:
            raise GraspError(
                file,
                f"{field}.geom",
                f"{target!r} is not a geom of the model{suggest(target, geom_labels(model))}",
            ) from e
    elif kind == "body":
        b = mujoco.mj_name2id(model, _OBJ.mjOBJ_BODY, target)
        if b < 0:
            raise GraspError(
                file,
                f"{field}.body",
                f"{target!r} is not a body of the model"
                f"{suggest(target, names_of(model, _OBJ.mjOBJ_BODY, model.nbody))}",
            )
        ids = [
            g
            for g in range(int(model.body_geomadr[b]), int(model.body_geomadr[b] + model.body_geomnum[b]))
            if model.geom_contype[g] or model.geom_conaffinity[g]  # visual geoms never touch
        ]
        if not ids:
            raise GraspError(file, f"{field}.body", f"body {target!r} has no geom that collides")
    else:
        if not 0 <= int(target) < model.ngeom:
            raise GraspError(
                file, f"{field}.geom_id", f"expected a geom id in [0, {model.ngeom}), got {target}"
            )
        ids = [int(target)]
    inside = subtree(model, ob)
    for g in ids:
        if int(model.geom_bodyid[g]) in inside:
            raise GraspError(file, field, f"geom {geom_label(model, g)!r} belongs to the object")
    return f"{kind} {target!r}", ids


def _cone(model: mujoco.MjModel, cone: str) -> str:
    """The grasp file's ``cone``, ``"model"`` read from the model's ``opt.cone``."""
    if cone != "model":
        return cone
    return "pyramidal" if int(model.opt.cone) == int(mujoco.mjtCone.mjCONE_PYRAMIDAL) else "elliptic"


def _default_joints(model: mujoco.MjModel, geoms: Sequence[int]) -> tuple[str, ...]:
    """The hinge and slide joints on the chains from the world to the contact geoms' bodies."""
    chain: set[int] = set()
    for g in geoms:
        b = int(model.geom_bodyid[g])
        while b > 0:
            chain.add(b)
            b = int(model.body_parentid[b])
    return tuple(
        mujoco.mj_id2name(model, _OBJ.mjOBJ_JOINT, j)
        for j in range(model.njnt)
        if int(model.jnt_type[j]) in _SCALAR and int(model.jnt_bodyid[j]) in chain
    )


def _drive(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    doc: Mapping[str, Any],
    joints: tuple[str, ...],
    path: Path | None,
    file: str,
    memo: RangesMemo | None = None,
) -> tuple[ModelTransmission | None, dict[str, Any], dict[str, Any]]:
    """The transmission (``None`` for the paper's independent joints) and the operation ranges
    and motors: per joint without a transmission, per actuator with one (``memo``: the
    caller's `mjtvm.grasp.actuation.ranges.RangesMemo`)."""
    ids = [int(model.joint(n).id) for n in joints]
    losses = doc["joint_losses"] == "fold"
    base = path.parent if path else None
    try:
        transmission = model_transmission(model, data, ids)
    except ModelError as e:
        raise GraspError(file, "joints", str(e)) from e
    try:
        check_closed(transmission)
    except ModelError as e:
        raise GraspError(
            file,
            "configuration",
            f"{e}; or configure it by IK, which keeps the equalities closed",
        ) from e
    if is_independent(model, transmission, ids):
        ranges, motors = joint_ranges(
            model, joints, doc["ranges"], base=base, file=file, losses=losses, memo=memo
        )
        return None, ranges, motors
    if not transmission.actuator_names:
        raise GraspError(file, "joints", "no actuator drives any of the joints")
    dofs = tuple(int(model.jnt_dofadr[j]) for j in ids)
    ranges, motors = actuator_ranges(
        model,
        transmission.actuator_names,
        transmission.moment,
        dofs,
        doc["ranges"],
        base=base,
        file=file,
        losses=losses,
        memo=memo,
    )
    if not losses:  # "ignore": the motors' ranges as they are, no damping in the balance either
        transmission = replace(transmission, joint_damping=np.zeros(len(joints)))
    return transmission, ranges, motors


def load_grasp(source: str | Path | Mapping[str, Any], *, hand: str = "default") -> Grasp:
    r"""Read a grasp file (TOML or JSON), a shipped grasp by name, or a document; build the grasp.

    A mapping's ``model`` path is taken relative to the working directory. ``hand``: the hand
    of one of the paper's grasps ([`with_hand()`][mjtvm.grasp.resolve.variants.with_hand]:
    ``case2`` + ``"humanlike"`` is ``case2-humanlike``); ``"default"`` for any other grasp.

    Raises
    ------
    GraspError
        Any field that breaks the format or does not fit the model (unknown body, geom,
        site, joint, keyframe or actuator, with the closest name; a joint, or with coupled
        joints an actuator, without an operation range, with how to give one; an unreachable
        IK target, with its residual; an equality the configuration violates, or one that
        ties a state joint to a joint the ``joints`` list leaves out).
    ModelError
        A ``hand`` the grasp does not have.
    """
    doc, path = read_grasp_document(_resolve(with_hand(source, hand)))
    file = str(path) if path is not None else "grasp"
    model, model_path = load_model(doc, path, file)
    return grasp_from_model(doc, path, model, model_path)


def grasp_from_model(
    doc: Mapping[str, Any],
    path: Path | None,
    model: mujoco.MjModel,
    model_path: Path,
    *,
    memo: RangesMemo | None = None,
) -> Grasp:
    r"""The grasp of a normalised document (`read_grasp_document()`)
    on a compiled model: what [`load_grasp()`][mjtvm.grasp.resolve.file.load_grasp] does after compiling the model.

    A batch (``mjtvm rank``) compiles each (object, scale) once and builds every grasp of a
    dataset on it, each from the file's document with its own ``configuration`` and ``object``
    pose. ``model`` is the document's model ([`build_spec()`][mjtvm.grasp.resolve.model.build_spec]
    compiled, possibly edited); a mocap base's pose is written into it
    ([`hold_mocap_poses()`][mjtvm.grasp.resolve.base.hold_mocap_poses]). ``memo``: a
    `mjtvm.grasp.actuation.ranges.RangesMemo` kept across the grasps of one
    document, so that the operation ranges, which depend on the configuration only through
    the actuators' moments, are read once per distinct moment and model fields.

    Raises
    ------
    GraspError
        As [`load_grasp()`][mjtvm.grasp.resolve.file.load_grasp], for everything but the model file.
    """
    file = str(path) if path is not None else "grasp"
    ob = mujoco.mj_name2id(model, _OBJ.mjOBJ_BODY, doc["object"]["body"])
    if ob <= 0:
        name = doc["object"]["body"]
        raise GraspError(
            file,
            "object.body",
            f"{name!r} is not a body of the model (other than the world)"
            f"{suggest(name, names_of(model, _OBJ.mjOBJ_BODY, model.nbody))}",
        )
    if not object_geoms(model, ob):
        raise GraspError(file, "object.body", f"body {doc['object']['body']!r} has no geom")
    data = configured_data(model, doc, ob, file)
    types: dict[str, str] = {}
    selections, mu, slides, geoms, preloads = [], {}, {}, [], {}
    ranges_mu: dict[str, tuple[float, float]] = {}  # geom label -> its friction interval
    for i, entry in enumerate(doc["contacts"]):
        what, ids = _select(model, entry, ob, file, f"contacts[{i}]")
        labels = tuple(geom_label(model, g) for g in ids)
        for g, label in zip(ids, labels, strict=True):
            if label in types:
                raise GraspError(
                    file, f"contacts[{i}]", f"geom {label!r} is already selected by another contact"
                )
            types[label] = entry["type"]
            coefficient = entry.get("mu", doc["mu"])
            if coefficient is not None:
                mu[label] = float(coefficient)
            elif entry["type"] in ("F", "S"):
                raise GraspError(
                    file,
                    f"contacts[{i}].mu",
                    f"the {entry['type']} contact {what} needs a "
                    "friction coefficient: set mu at the top or in the contact",
                )
            interval = entry.get("mu_range", doc["mu_range"] if "mu" not in entry else None)
            if interval is not None and entry["type"] in ("F", "S"):
                if not interval[0] <= mu[label] <= interval[1]:
                    raise GraspError(
                        file, f"contacts[{i}].mu_range", f"expected [mu_lo, mu_hi] around mu ({mu[label]!r})"
                    )
                ranges_mu[label] = interval
            if entry.get("preload"):
                preloads[label] = float(entry["preload"])
            if "slide" in entry:
                s = np.array(entry["slide"], dtype=float)
                slides[label] = tuple(float(x) for x in s / np.linalg.norm(s))
            geoms.append(g)
        selections.append((what, labels))
    ignored = []
    for i, sel in enumerate(doc["ignore"]):
        _, ids = _select(model, sel, ob, file, f"ignore[{i}]")
        ignored += [geom_label(model, g) for g in ids if geom_label(model, g) not in types]
    rules: tuple[RuleMatch, ...] = ()
    if doc["contact_rules"]:
        touching = touching_geoms(model, data, doc["object"]["body"], doc["contact_tolerance"])
        expansion = expand_rules(
            model,
            doc["contact_rules"],
            touching,
            taken={*types, *ignored},
            object_body=ob,
            mu=doc["mu"],
            file=file,
        )
        types.update(expansion.types)
        mu.update(expansion.mu)
        if doc["mu_range"] is not None:  # the rules that take the top-level mu take its interval
            for rule, match in zip(doc["contact_rules"], expansion.matches, strict=True):
                if rule["mu"] is None and match.type in ("F", "S"):
                    ranges_mu.update(dict.fromkeys(match.labels, doc["mu_range"]))
        ignored += expansion.ignored
        geoms += [geom_id(model, label) for label in expansion.types]
        rules = expansion.matches
    if doc["joints"] is not None:
        for k, name in enumerate(doc["joints"]):
            joint_id(model, name, file, f"joints[{k}]")
        joints = tuple(doc["joints"])
    else:
        joints = _default_joints(model, [g for g in geoms if int(model.geom_bodyid[g]) > 0])
        if not geoms:  # no rule matched a touching geom: the grasp does not touch the object
            d = nearest_distance(model, data, doc["object"]["body"])
            far = "more than 100 mm" if d is None else f"{1e3 * d:.3g} mm"
            raise NoContactError(
                file,
                "contact_rules",
                f"no contact: no geom touches the object: nearest distance {far} > "
                f"contact_tolerance {1e3 * doc['contact_tolerance']:.3g} mm",
                nearest=d,
            )
        if not joints:
            raise GraspError(file, "contacts", "no hinge or slide joint moves any contact geom")
        joints = tuple(
            mujoco.mj_id2name(model, _OBJ.mjOBJ_JOINT, j)
            for j in coupled_joints(model, data, [int(model.joint(n).id) for n in joints])
        )
    transmission, ranges, motors = _drive(model, data, doc, joints, path, file, memo)
    rvds = None if doc["rvds"] is None else np.array(doc["rvds"], dtype=float)
    if rvds is not None:
        rvds.setflags(write=False)
    lift = doc["lift"]
    bounds = dict(lift["bounds"]) if lift is not None else {}
    for name in bounds:
        joint_id(model, name, file, f"lift.bounds.{key_of(name)}")
    return Grasp(
        name=doc["name"],
        path=path,
        model_path=model_path,
        model=model,
        data=data,
        object_body=doc["object"]["body"],
        joints=joints,
        contact_types=MappingProxyType(types),
        selections=tuple(selections),
        mu=MappingProxyType(mu),
        mu_ranges=MappingProxyType(ranges_mu),
        friction_margin=cone_margin(_cone(model, doc["cone"]), doc["friction_margin"]),
        cone=_cone(model, doc["cone"]),
        slide_directions=MappingProxyType(slides),
        refs=document_refs(model, data, doc, doc["object"]["body"], file),
        rvds=rvds,
        ignored_geoms=tuple(ignored),
        operation_ranges=MappingProxyType(ranges),
        motors=MappingProxyType(motors),
        transmission=transmission,
        contact_tolerance=float(doc["contact_tolerance"]),
        friction_edges=int(doc["friction_edges"]),
        slip=str(doc["slip"]),
        lift=None if lift is None else MappingProxyType(lift),
        ik_bounds=MappingProxyType(bounds),
        document=MappingProxyType(doc),
        preloads=MappingProxyType(preloads),
        rule_matches=rules,
    )


def export_state(source: str | Path | Mapping[str, Any]) -> GraspState:
    r"""The grasp state of a grasp file, a shipped grasp by name, or a document.

    What ``mjtvm export-state`` prints: [`state()`][mjtvm.grasp.resolve.loaded.Grasp.state] of
    [`load_grasp()`][mjtvm.grasp.resolve.file.load_grasp]; [`state_to_dict()`][mjtvm.formats.state_file.state_to_dict] gives its ``mjtvm.state/1`` document.

    Raises
    ------
    GraspError
        As [`load_grasp()`][mjtvm.grasp.resolve.file.load_grasp]; or a selection that does not touch, a touching geom nobody
        selected, or an S contact without a slide direction.
    """
    return load_grasp(source).state()
