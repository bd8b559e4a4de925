r"""The paper's grasp scenarios (section 5, Cases 1 and 2) as data, and their grasp states.

A scenario is a JSON document (``mjtvm/data/scenarios/<name>.json``, schema
``mjtvm.scenario/1``): the object (centre, radius, weight mg), the friction coefficient,
the fingers whose joints make the state, the paper's contact points with how each finger
geom reaches it, contact types by geom name, slide directions of S-points, REFS, RVDS,
geoms whose contacts are modelling artefacts (``ignored_geoms``), and per model variant
(``default``: [yaw, pitch] + [pitch, yaw] fingers; ``humanlike``: yaw + three pitches) the
finger joints, the IK start and bounds, and the ``solution`` written by
``scripts/make_scenarios.py`` (:func:`make_documents`): joint angles, IK residuals and the
achieved contacts. Loading (:func:`load_scenario`) rebuilds the model with
:func:`~mjtvm.sim.hand.hand_mjcf` and sets the stored angles; it does not rerun the IK.

Contact placement (:func:`solve_variant`). Each paper point ``p`` is projected radially onto
the sphere, ``p_s = c + R (p - c) / |p - c|``, and the geom is placed by
:func:`~mjtvm.sim.ik.geom_contact_target` (tip sphere: surfaces touching at ``p_s``; capsule: the
point ``along`` its axis at ``p_s - offset n``, axis tangent). The solution is accepted only
if the contacts MuJoCo then detects (one per body, ignored geoms aside) are exactly the
scenario's, each within 3 mm of its ``p_s``, and no link goes below the palm (z < 0).

World frame, SI units.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Mapping, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.state import state_to_dict
from ..errors import ModelError
from .grasp import detected_contacts
from .graspfile import Grasp, load_grasp
from .hand import finger_joint_names, hand_mjcf
from .ik import IkTarget, geom_contact_target, solve_ik
from .posture import FingerPosture, finger_geometry, fingertip_family, planar_fingertip, side_postures

__all__ = [
    "CONTACT_TOLERANCE",
    "SCENARIOS",
    "SCHEMA",
    "Scenario",
    "export_state",
    "finger1_tvmm_curve",
    "format_document",
    "load_scenario",
    "make_documents",
    "posture_grasp",
    "read_scenario",
    "rule_posture",
    "scenario_path",
    "solve_variant",
    "variant_model_text",
]

SCHEMA = "mjtvm.scenario/1"
SCENARIOS = ("case1", "case1-s", "case2")
CONTACT_TOLERANCE = 3e-3  # m: largest accepted distance of a contact from the paper's point
_OBJ = mujoco.mjtObj
_REQUIRED = (
    "schema", "name", "object_body", "object_position", "object_radius", "mg", "mu", "fingers",
    "contact_types", "slide_directions", "ignored_geoms", "refs", "rvds", "contacts", "variants",
)  # fmt: skip


def scenario_path(name: str) -> Path:
    """Path of the shipped scenario ``name`` (one of :data:`SCENARIOS`)."""
    if name not in SCENARIOS:
        raise ModelError(f"scenario {name!r}", f"unknown (shipped: {', '.join(SCENARIOS)})")
    return Path(str(resources.files("mjtvm.data").joinpath("scenarios").joinpath(f"{name}.json")))


def read_scenario(source: str | Path | Mapping[str, Any]) -> dict[str, Any]:
    """The scenario document of a shipped name, a JSON file path or a mapping (copied)."""
    if isinstance(source, Mapping):
        doc: Any = copy.deepcopy(dict(source))
    else:
        path = Path(source) if isinstance(source, Path) or str(source).endswith(".json") else None
        path = path or scenario_path(str(source))
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as e:
            raise ModelError(f"scenario file {str(path)!r}", f"cannot be read: {e}") from e
    if not isinstance(doc, dict) or doc.get("schema") != SCHEMA:
        raise ModelError("scenario", f"expected a JSON object with schema {SCHEMA!r}")
    missing = [k for k in _REQUIRED if k not in doc]
    if missing:
        raise ModelError(f"scenario {doc.get('name')!r}", f"missing keys: {', '.join(missing)}")
    return doc


def _variant(doc: Mapping[str, Any], variant: str) -> Mapping[str, Any]:
    if variant not in doc["variants"]:
        raise ModelError(
            f"scenario {doc['name']!r}", f"no variant {variant!r} (has: {', '.join(doc['variants'])})"
        )
    v: Mapping[str, Any] = doc["variants"][variant]
    return v


def _check_name(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str, label: str, where: str) -> None:
    if mujoco.mj_name2id(model, kind, name) < 0:
        raise ModelError(f"{label} {name!r}", f"named in the scenario's {where} but not in the model")


def _hand_options(v: Mapping[str, Any]) -> dict[str, Any]:
    """:func:`~mjtvm.sim.hand.hand_mjcf` keywords of a variant: its finger joints and optional link radii."""
    options: dict[str, Any] = {"finger_joints": v["finger_joints"]}
    for key in ("capsule_radius", "tip_radius"):
        if key in v.get("hand", {}):
            options[key] = float(v["hand"][key])
    return options


def variant_model_text(doc: Mapping[str, Any], variant: str) -> str:
    """The MJCF of a variant's hand (``mjtvm/models/paper_hand/<model>``), as the generator writes it."""
    v = _variant(doc, variant)
    return hand_mjcf(**_hand_options(v), model_name=Path(str(v["model"])).stem)


def _build(doc: Mapping[str, Any], variant: str, mg: float) -> mujoco.MjModel:
    """The variant's model, every name the scenario uses checked against it."""
    v = _variant(doc, variant)
    model = mujoco.MjModel.from_xml_string(
        hand_mjcf(
            **_hand_options(v),
            object_position=doc["object_position"],
            object_radius=float(doc["object_radius"]),
            mg=mg,
        )
    )
    _check_name(model, _OBJ.mjOBJ_BODY, doc["object_body"], "body", "object_body")
    geoms = [
        *((g, "contact_types") for g in doc["contact_types"]),
        *((g, "slide_directions") for g in doc["slide_directions"]),
        *((g, "ignored_geoms") for g in [*doc["ignored_geoms"], *v.get("ignored_geoms", [])]),
        *((c["geom"], "contacts") for c in doc["contacts"]),
    ]
    for g, where in geoms:
        _check_name(model, _OBJ.mjOBJ_GEOM, g, "geom", where)
    for where in ("start", "bounds"):
        for j in v.get(where, {}):
            _check_name(model, _OBJ.mjOBJ_JOINT, j, "joint", where)
    for j in v.get("solution", {}).get("qpos", {}):
        _check_name(model, _OBJ.mjOBJ_JOINT, j, "joint", "solution")
    return model


def _on_sphere(doc: Mapping[str, Any], point: ArrayLike) -> NDArray[np.float64]:
    """Radial projection of ``point`` onto the object sphere."""
    c, p = np.asarray(doc["object_position"], dtype=float), np.asarray(point, dtype=float)
    return c + float(doc["object_radius"]) * (p - c) / np.linalg.norm(p - c)


def _hand_joints(model: mujoco.MjModel) -> list[int]:
    scalar = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    return [j for j in range(model.njnt) if int(model.jnt_type[j]) in scalar]


def _data(model: mujoco.MjModel, doc: Mapping[str, Any], qpos: Mapping[str, float]) -> mujoco.MjData:
    data = mujoco.MjData(model)
    for name, value in qpos.items():
        data.qpos[model.joint(name).qposadr[0]] = float(value)
    ob = model.body(doc["object_body"]).id
    free = [j for j in range(model.njnt) if int(model.jnt_bodyid[j]) == ob]
    if free:
        adr = int(model.jnt_qposadr[free[0]])
        data.qpos[adr : adr + 7] = [*doc["object_position"], 1.0, 0.0, 0.0, 0.0]
    mujoco.mj_forward(model, data)
    return data


def _check_pose(model: mujoco.MjModel, data: mujoco.MjData, doc: Mapping[str, Any], variant: str) -> dict:
    """Achieved contacts vs the paper's; raises when the pose is not the scenario's."""
    ignored = {*doc["ignored_geoms"], *_variant(doc, variant).get("ignored_geoms", [])}
    found = {
        c.geom: c
        for c in detected_contacts(model, data, object_body=doc["object_body"])
        if c.geom not in ignored
    }
    wanted = {c["geom"]: c["paper"] for c in doc["contacts"]}
    for g, c in found.items():
        if g not in wanted:
            raise ModelError(f"geom {g!r}", f"touches the object (distance {c.distance:.3g} m) unexpectedly")
    out = {}
    for g, paper in wanted.items():
        if g not in found:
            raise ModelError(f"geom {g!r}", "does not touch the object (or a deeper contact hides it)")
        target = _on_sphere(doc, paper)
        error = float(np.linalg.norm(found[g].position - target))
        if error > CONTACT_TOLERANCE:
            raise ModelError(f"geom {g!r}", f"contact {1e3 * error:.2f} mm from the paper's point (> 3 mm)")
        out[g] = {
            "paper": [float(x) for x in paper],
            "on_sphere": target.tolist(),
            "achieved": found[g].position.tolist(),
            "distance": found[g].distance,
            "error_mm": 1e3 * error,
        }
    for k in range(model.ngeom):
        if int(model.geom_type[k]) == int(mujoco.mjtGeom.mjGEOM_CAPSULE):
            axis = data.geom_xmat[k].reshape(3, 3)[:, 2] * model.geom_size[k, 1]
            low = min(data.geom_xpos[k][2] + axis[2], data.geom_xpos[k][2] - axis[2])
            if low < -1e-9:
                name = mujoco.mj_id2name(model, _OBJ.mjOBJ_GEOM, k)
                raise ModelError(f"geom {name!r}", f"goes below the palm (z = {low:.4g} m)")
    return out


def _targets(model: mujoco.MjModel, doc: Mapping[str, Any]) -> list[IkTarget]:
    targets = []
    for c in doc["contacts"]:
        if int(model.geom_bodyid[model.geom(c["geom"]).id]) == 0:
            continue  # the palm: nothing to move
        targets.append(
            geom_contact_target(
                model, c["geom"], _on_sphere(doc, c["paper"]), doc["object_position"],
                along=c.get("along"), offset=c.get("offset"),
            )
        )  # fmt: skip
    return targets


def solve_variant(doc: Mapping[str, Any], variant: str, *, tolerance: float = 1e-10) -> dict[str, Any]:
    r"""Rerun the IK of one variant; return its ``solution`` section.

    Starts from the variant's ``start`` angles (0 for the others; a variant with a
    ``posture`` rule starts its finger at :func:`rule_posture`, which the IK then leaves
    unchanged, checked to 1e-9 rad), solves every finger contact at once (:func:`~mjtvm.sim.ik.solve_ik`, within the variant's ``bounds``), and
    checks the pose (module docstring).

    Returns
    -------
    dict
        ``qpos`` (joint name -> rad, every hand joint), ``ik`` (iterations, residual per
        target in m) and ``contacts`` (geom -> paper point, its projection on the sphere,
        MuJoCo's contact point, surface distance in m, error in mm).

    Raises
    ------
    ModelError
        Unknown names, an unreachable target (named, with its residual), or a pose
        that fails the checks.
    """
    v = _variant(doc, variant)
    model = _build(doc, variant, float(doc["mg"]))
    bounds = {k: (float(lo), float(hi)) for k, (lo, hi) in v.get("bounds", {}).items()}
    targets = _targets(model, doc)
    start, posture = dict(v.get("start", {})), None
    if "posture" in v:
        posture = rule_posture(model, doc, variant, targets)
        start.update(posture.angles)
    data = _data(model, doc, start)
    result = solve_ik(model, data, targets, bounds=bounds, tolerance=tolerance)
    qpos = {
        mujoco.mj_id2name(model, _OBJ.mjOBJ_JOINT, j): float(result.qpos[model.jnt_qposadr[j]])
        for j in _hand_joints(model)
    }
    contacts = _check_pose(model, _data(model, doc, qpos), doc, variant)
    residuals = {t.name: float(r) for t, r in zip(targets, result.residuals, strict=True)}
    out: dict[str, Any] = {"qpos": qpos}
    if posture is not None:
        moved = max(abs(qpos[k] - a) for k, a in posture.angles.items())
        if moved > 1e-9:
            raise ModelError(
                f"scenario {doc['name']!r}", f"the IK moved the rule's posture by {moved:.3g} rad"
            )
        out["posture"] = {"rule": v["posture"]["rule"], "finger": int(v["posture"]["finger"]),
                          "elbow": posture.elbow.tolist()}  # fmt: skip
    out["ik"] = {"iterations": result.iterations, "tolerance": tolerance, "residuals": residuals}
    out["contacts"] = contacts
    return out


def rule_posture(
    model: mujoco.MjModel, doc: Mapping[str, Any], variant: str, targets: Sequence[IkTarget] | None = None
) -> FingerPosture:
    r"""The posture the variant's ``posture`` rule gives its finger (no IK start angles).

    ``{"finger": i, "rule": "planar_fingertip"}``: :func:`~mjtvm.sim.posture.planar_fingertip`
    on the finger's tip target (the tip sphere's centre placed so that its surface touches the
    paper's point projected on the sphere): the fingertip on the point, both links in the
    vertical plane through the base (distal yaw 0), elbow up. Finger 3 in Case 1 is planar
    too (its printed points lie in the x-z plane through its base); the paper's text does not
    give finger 1's posture (``docs/paper-results.md``).
    """
    rule = _variant(doc, variant)["posture"]
    if rule.get("rule") != "planar_fingertip":
        raise ModelError(f"scenario {doc['name']!r}", f"unknown posture rule {rule.get('rule')!r}")
    finger = int(rule["finger"])
    tip = f"f{finger}_tip"
    found = [t for t in (targets if targets is not None else _targets(model, doc)) if t.name == tip]
    if not found:
        raise ModelError(f"scenario {doc['name']!r}", f"the posture rule needs a contact of geom {tip!r}")
    return planar_fingertip(finger_geometry(model, finger), found[0].position)


def make_documents(names: Sequence[str] = SCENARIOS) -> dict[str, dict[str, Any]]:
    """Every shipped scenario with each variant's ``solution`` recomputed (the generator's output)."""
    docs = {}
    for name in names:
        doc = read_scenario(name)
        for variant in doc["variants"]:
            doc["variants"][variant].pop("solution", None)
            doc["variants"][variant]["solution"] = solve_variant(doc, variant)
        docs[name] = doc
    return docs


def format_document(doc: Any, indent: int = 0) -> str:
    """JSON text; a list or object of scalars and flat lists fitting in 100 columns stays on one line."""
    text = json.dumps(doc)  # floats as repr: exact round trip
    if not isinstance(doc, (dict, list)):
        return text
    items = list(doc.values()) if isinstance(doc, dict) else doc
    flat = all(
        not isinstance(x, dict) and not any(isinstance(y, (dict, list)) for y in x)
        if isinstance(x, list)
        else not isinstance(x, dict)
        for x in items
    )
    if len(text) + indent <= 100 and flat:
        return text
    pad = " " * (indent + 1)
    if isinstance(doc, dict):
        rows = [f"{pad}{json.dumps(k)}: {format_document(v, indent + 1)}" for k, v in doc.items()]
        return "{\n" + ",\n".join(rows) + "\n" + " " * indent + "}"
    rows = [f"{pad}{format_document(x, indent + 1)}" for x in doc]
    return "[\n" + ",\n".join(rows) + "\n" + " " * indent + "]"


Scenario = Grasp  # the paper's cases are grasp files like any other (kept for old imports)


def load_scenario(
    source: str | Path | Mapping[str, Any],
    *,
    variant: str = "default",
    mg: float | None = None,
    mu: float | Mapping[str, float] | None = None,
) -> Grasp:
    r"""A paper case as a :class:`~mjtvm.sim.graspfile.Grasp`: its shipped grasp file.

    Parameters
    ----------
    source
        A shipped scenario name (:data:`SCENARIOS`; the grasp file
        :func:`grasp_file_name` of ``variant`` in ``mjtvm/models/paper_hand/``), or any grasp
        file or shipped grasp name (then ``variant`` must stay ``"default"``).
    variant
        Hand of a shipped scenario: ``"default"`` or ``"humanlike"``.
    mg, mu
        Object weight (N) and friction coefficient instead of the file's
        (:meth:`~mjtvm.sim.graspfile.Grasp.with_options`).

    Raises
    ------
    ModelError
        Unknown scenario or variant, or a grasp file that does not load.
    """
    if isinstance(source, str) and source in SCENARIOS:
        if variant not in ("default", "humanlike"):
            raise ModelError(f"scenario {source!r}", f"no variant {variant!r} (has: default, humanlike)")
        source = grasp_file_name(source, variant)[: -len(".toml")]
    elif variant != "default":
        raise ModelError("variant", f"applies to the shipped scenarios ({', '.join(SCENARIOS)}) only")
    return load_grasp(source).with_options(mg=mg, mu=mu)


def export_state(name: str | Path | Mapping[str, Any], **options: Any) -> dict[str, Any]:
    """The ``mjtvm.state/1`` document of a scenario's state (``options`` go to :func:`load_scenario`)."""
    return state_to_dict(load_scenario(name, **options).state())


def grasp_file_name(name: str, variant: str) -> str:
    """The shipped grasp file of a scenario and hand variant: ``case2.toml``, ``case2-humanlike.toml``."""
    return f"{name}.toml" if variant == "default" else f"{name}-{variant}.toml"


def grasp_document(doc: Mapping[str, Any], variant: str) -> dict[str, Any]:
    r"""The ``mjtvm.grasp/1`` document of one scenario variant at its stored IK solution.

    The grasp is the paper's hand (``mjtvm/models/paper_hand/<model>``) at the solution's
    joint angles with the object at ``object_position``; REFS = the weight ``mg`` along
    gravity; the fingers' joints in finger order; ignored geoms as ``ignore``.
    """
    v = _variant(doc, variant)
    if "solution" not in v:
        raise ModelError(
            f"scenario {doc['name']!r}", f"variant {variant!r} has no solution: run the generator"
        )
    joints = [n for i in doc["fingers"] for n in finger_joint_names(int(i), v["finger_joints"])]
    contacts = []
    for geom, kind in doc["contact_types"].items():
        entry: dict[str, Any] = {"geom": geom, "type": kind}
        if geom in doc["slide_directions"]:
            entry["slide"] = [float(x) for x in doc["slide_directions"][geom]]
        contacts.append(entry)
    out: dict[str, Any] = {
        "schema": "mjtvm.grasp/1",
        "name": grasp_file_name(str(doc["name"]), variant)[:-5],
        "description": f"{doc.get('description', '')} Hand: {variant}.".strip(),
        "source": doc.get("source", ""),
        "notes": [*doc.get("notes", []),
                  "Written by scripts/make_scenarios.py from mjtvm/data/scenarios/"
                  f"{doc['name']}.json (its IK solution); do not edit by hand."],
        "model": str(v["model"]),
        "joints": joints,
        "mu": float(doc["mu"]),
    }  # fmt: skip
    if doc["rvds"] is not None:
        out["rvds"] = [[float(x) for x in r] for r in doc["rvds"]]
    out["object"] = {"body": doc["object_body"], "position": [float(x) for x in doc["object_position"]],
                     "quaternion": [1.0, 0.0, 0.0, 0.0]}  # fmt: skip
    out["configuration"] = {"qpos": {k: float(x) for k, x in v["solution"]["qpos"].items()}}
    refs = np.array(doc["refs"], dtype=float)
    if refs.shape == (1, 6) and np.array_equal(refs[0, [0, 1, 3, 4, 5]], np.zeros(5)) and refs[0, 2] < 0:
        out["refs"] = {"mg": float(-refs[0, 2])}
    else:
        out["refs"] = {"weight": False, "wrenches": refs.tolist()}
    out["ranges"] = {"*": {"dcmotor": True}}
    out["lift"] = {
        "direction": [0.0, 0.0, 1.0],
        "bounds": {k: [float(lo), float(hi)] for k, (lo, hi) in v.get("bounds", {}).items()},
    }
    out["contacts"] = contacts
    ignored = [*doc["ignored_geoms"], *v.get("ignored_geoms", [])]
    if ignored:
        out["ignore"] = [{"geom": g} for g in ignored]
    return out


def posture_grasp(doc: Mapping[str, Any], variant: str, posture: FingerPosture, finger: int = 1) -> Grasp:
    r"""The variant's grasp with finger ``finger`` at ``posture`` instead of the stored solution.

    A ``"side"`` posture touches with link 2 (geom ``f<i>_link2``, an F-point like the tip's);
    every other joint keeps the solution's angle.
    """
    out = grasp_document(doc, variant)
    out["model"] = str(
        Path(str(resources.files("mjtvm").joinpath("models").joinpath("paper_hand"))) / out["model"]
    )
    out["configuration"]["qpos"].update(posture.angles)
    if posture.contact == "side":
        for entry in out["contacts"]:
            if entry["geom"] == f"f{finger}_tip":
                entry["geom"] = f"f{finger}_link2"
    return load_grasp(out)


def finger1_tvmm_curve(
    name: str = "case1",
    *,
    tip_angles: ArrayLike | None = None,
    alongs: ArrayLike | None = None,
) -> list[dict[str, Any]]:
    r"""Case 1's TVMM (Problem 1, scaled affine volume, 1/s^4) over finger 1's feasible postures.

    Finger 1's contact on the paper's point, every other joint at the stored solution:
    fingertip postures (:func:`~mjtvm.sim.posture.fingertip_family` at the elbow angles
    ``tip_angles``, rad; default every 2.5 deg) and contacts on link 2 at ``alongs`` (m) from
    its joint (default every 2.5 mm)
    (:func:`~mjtvm.sim.posture.side_postures`). Postures whose grasp is not the scenario's
    (another geom touching) are left out.

    Returns
    -------
    list of dict
        One row per posture: ``contact`` (``"tip"``/``"side"``), ``along`` (m),
        ``parameter`` (rad), ``angles`` (joint -> rad), ``elbow`` (m), ``dimension`` and
        ``tvmm`` (scaled affine volume, 1/s^4).
    """
    from ..polytopes.tvms import tvms

    tip_angles = np.radians(np.arange(-180.0, 180.0, 2.5)) if tip_angles is None else tip_angles
    alongs = np.arange(0.0025, 0.1, 0.0025) if alongs is None else alongs
    doc = read_scenario(name)
    model = _build(doc, "default", float(doc["mg"]))
    geo = finger_geometry(model, 1)
    (target,) = [t for t in _targets(model, doc) if t.name == "f1_tip"]
    (paper,) = [c["paper"] for c in doc["contacts"] if c["geom"] == "f1_tip"]
    point, centre = _on_sphere(doc, paper), np.asarray(doc["object_position"], dtype=float)
    postures = fingertip_family(geo, target.position, centre, tip_angles)
    for along in np.asarray(alongs, dtype=float):
        postures += side_postures(geo, point, centre, float(along)) if along > 0 else []
    rows = []
    for p in postures:
        try:
            result = tvms(posture_grasp(doc, "default", p).state())
        except ModelError:  # e.g. link 1 or the tip touching too: not this grasp
            continue
        rows.append({"contact": p.contact, "along": p.along, "parameter": p.parameter, "angles": p.angles,
                     "elbow": p.elbow.tolist(), "dimension": result.dimension,
                     "tvmm": result.affine_volume})  # fmt: skip
    return rows
