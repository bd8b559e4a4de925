r"""The generator of the paper's grasp files: each scenario variant's contacts placed by IK.

Contact placement ([`solve_variant()`][mjtvm.paper_hand.placement.solve_variant]). Each paper point ``p`` is projected radially onto
the sphere, ``p_s = c + R (p - c) / |p - c|``, and the geom is placed by
[`geom_contact_target()`][mjtvm.grasp.resolve.ik.geom_contact_target] (tip sphere: surfaces touching at ``p_s``; capsule: the
point ``along`` its axis at ``p_s - offset n``, axis tangent). The solution is accepted only
if the contacts MuJoCo then detects (one per body, ignored geoms aside) are exactly the
scenario's, each within 3 mm of its ``p_s``, and no link goes below the palm (z < 0).
`make_documents()` is what ``tools/make_scenarios.py`` writes; [`posture_grasp()`][mjtvm.paper_hand.placement.posture_grasp] and
[`finger1_tvmm_curve()`][mjtvm.paper_hand.placement.finger1_tvmm_curve] vary finger 1's posture, which the paper does not print.

World frame, SI units.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import ModelError
from mjtvm.grasp.resolve.file import load_grasp, models_root
from mjtvm.grasp.resolve.ik import IkTarget, geom_contact_target, solve_ik
from mjtvm.grasp.resolve.loaded import Grasp
from mjtvm.grasp.resolve.state import detected_contacts
from mjtvm.paper_hand.hand import hand_mjcf
from mjtvm.paper_hand.posture import (
    FingerPosture,
    finger_geometry,
    fingertip_family,
    planar_fingertip,
    side_postures,
)
from mjtvm.paper_hand.scenario import SCENARIOS, grasp_document, read_scenario, scenario_variant

__all__ = [
    "CONTACT_TOLERANCE",
    "finger1_tvmm_curve",
    "make_documents",
    "posture_grasp",
    "rule_posture",
    "solve_variant",
    "variant_model_text",
]

_OBJ = mujoco.mjtObj
CONTACT_TOLERANCE = 3e-3  # m: largest accepted distance of a contact from the paper's point


def _check_name(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str, label: str, where: str) -> None:
    if mujoco.mj_name2id(model, kind, name) < 0:
        raise ModelError(f"{label} {name!r}", f"named in the scenario's {where} but not in the model")


def _hand_options(v: Mapping[str, Any]) -> dict[str, Any]:
    """[`hand_mjcf()`][mjtvm.paper_hand.hand.hand_mjcf] keywords of a variant: its finger joints and optional link radii."""
    options: dict[str, Any] = {"finger_joints": v["finger_joints"]}
    for key in ("capsule_radius", "tip_radius"):
        if key in v.get("hand", {}):
            options[key] = float(v["hand"][key])
    return options


def variant_model_text(doc: Mapping[str, Any], variant: str) -> str:
    """The MJCF of a variant's hand (``models/paper_hand/<model>``), as the generator writes it."""
    v = scenario_variant(doc, variant)
    return hand_mjcf(**_hand_options(v), model_name=Path(str(v["model"])).stem)


def _build(doc: Mapping[str, Any], variant: str, mg: float) -> mujoco.MjModel:
    """The variant's model, every name the scenario uses checked against it."""
    v = scenario_variant(doc, variant)
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
    ignored = {*doc["ignored_geoms"], *scenario_variant(doc, variant).get("ignored_geoms", [])}
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
                model,
                c["geom"],
                _on_sphere(doc, c["paper"]),
                doc["object_position"],
                along=c.get("along"),
                offset=c.get("offset"),
            )
        )
    return targets


def solve_variant(doc: Mapping[str, Any], variant: str, *, tolerance: float = 1e-10) -> dict[str, Any]:
    r"""Rerun the IK of one variant; return its ``solution`` section.

    Starts from the variant's ``start`` angles (0 for the others; a variant with a
    ``posture`` rule starts its finger at [`rule_posture()`][mjtvm.paper_hand.placement.rule_posture], which the IK then leaves
    unchanged, checked to 1e-9 rad), solves every finger contact at once (`solve_ik()`, within the variant's ``bounds``), and
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
    v = scenario_variant(doc, variant)
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
        out["posture"] = {
            "rule": v["posture"]["rule"],
            "finger": int(v["posture"]["finger"]),
            "elbow": posture.elbow.tolist(),
        }
    out["ik"] = {"iterations": result.iterations, "tolerance": tolerance, "residuals": residuals}
    out["contacts"] = contacts
    return out


def rule_posture(
    model: mujoco.MjModel, doc: Mapping[str, Any], variant: str, targets: Sequence[IkTarget] | None = None
) -> FingerPosture:
    r"""The posture the variant's ``posture`` rule gives its finger (no IK start angles).

    ``{"finger": i, "rule": "planar_fingertip"}``: [`planar_fingertip()`][mjtvm.paper_hand.posture.planar_fingertip]
    on the finger's tip target (the tip sphere's centre placed so that its surface touches the
    paper's point projected on the sphere): the fingertip on the point, both links in the
    vertical plane through the base (distal yaw 0), elbow up. Finger 3 in Case 1 is planar
    too (its printed points lie in the x-z plane through its base); the paper's text does not
    give finger 1's posture (``docs/paper-results.md``).
    """
    rule = scenario_variant(doc, variant)["posture"]
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


def posture_grasp(doc: Mapping[str, Any], variant: str, posture: FingerPosture, finger: int = 1) -> Grasp:
    r"""The variant's grasp with finger ``finger`` at ``posture`` instead of the stored solution.

    A ``"side"`` posture touches with link 2 (geom ``f<i>_link2``, an F-point like the tip's);
    every other joint keeps the solution's angle.
    """
    out = grasp_document(doc, variant)
    out["model"] = str(models_root() / "paper_hand" / out["model"])
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
    fingertip postures ([`fingertip_family()`][mjtvm.paper_hand.posture.fingertip_family] at the elbow angles
    ``tip_angles``, rad; default every 2.5 deg) and contacts on link 2 at ``alongs`` (m) from
    its joint (default every 2.5 mm)
    ([`side_postures()`][mjtvm.paper_hand.posture.side_postures]). Postures whose grasp is not the scenario's
    (another geom touching) are left out.

    Returns
    -------
    list of dict
        One row per posture: ``contact`` (``"tip"``/``"side"``), ``along`` (m),
        ``parameter`` (rad), ``angles`` (joint -> rad), ``elbow`` (m), ``dimension`` and
        ``tvmm`` (scaled affine volume, 1/s^4).
    """
    from mjtvm.polytopes.tvms import tvms

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
        rows.append(
            {
                "contact": p.contact,
                "along": p.along,
                "parameter": p.parameter,
                "angles": p.angles,
                "elbow": p.elbow.tolist(),
                "dimension": result.dimension,
                "tvmm": result.affine_volume,
            }
        )
    return rows
