r"""What a loaded grasp's contacts look like before anything is solved: every geom near the
object ([`contact_rows()`][mjtvm.grasp.contacts.report.contact_rows], the table of ``mjtvm show``), penetration beyond the file's
``max_penetration`` refused (`check_penetration()`) and smaller penetration or an IK target
that is not the geom that touches reported ([`contact_warnings()`][mjtvm.grasp.contacts.report.contact_warnings]).

Distances are exact (``mj_geomDistance``, [`mjtvm.grasp.contacts.pairs`][mjtvm.grasp.contacts.pairs]); the contacts the
state keeps are [`detected_contacts()`][mjtvm.grasp.contacts.touch.detected_contacts]' (one per finger body, the
deepest). World frame, SI units.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.grasp.contacts.memo import contacts_once
from mjtvm.grasp.contacts.pairs import near_pairs
from mjtvm.grasp.contacts.touch import (
    DetectedContact,
    geom_id,
    geom_label,
    precise_collision,
    subtree,
)
from mjtvm.grasp.document.checks import GraspError

__all__ = [
    "NEAR_TOLERANCES",
    "REPORTED_PENETRATION",
    "ContactRow",
    "LoadedGrasp",
    "TypedRule",
    "check_penetration",
    "contact_rows",
    "contact_warnings",
    "kept_contacts",
]

#: How far [`contact_rows()`][mjtvm.grasp.contacts.report.contact_rows] looks by default, in contact tolerances (at least 1 mm): far
#: enough to show the geom a user meant to touch and the distance still to close.
NEAR_TOLERANCES = 10.0

#: m: the shallowest penetration [`contact_warnings()`][mjtvm.grasp.contacts.report.contact_warnings] reports. Below a micrometre it is the
#: placement's round-off (the IK stops at about 1e-9 m, the collision at 1e-12 m; the shipped
#: IK grasps penetrate by up to 1.3e-8 m), not a finger inside the object.
REPORTED_PENETRATION = 1e-6


class TypedRule(Protocol):
    """What the report reads of a contact rule's match
    ([`RuleMatch`][mjtvm.grasp.resolve.rules.RuleMatch])."""

    @property
    def field(self) -> str:
        """The rule's field, e.g. ``"contact_rules[0]"``."""
        ...

    @property
    def type(self) -> str:
        """``"F"``, ``"L"``, ``"D"`` or ``"ignore"``."""
        ...

    @property
    def labels(self) -> tuple[str, ...]:
        """The touching geoms it typed."""
        ...


class LoadedGrasp(Protocol):
    """What the report reads of a loaded grasp ([`Grasp`][mjtvm.grasp.resolve.loaded.Grasp], which
    satisfies it): the report sits below the loader, so it names the attributes, not the class."""

    @property
    def model(self) -> mujoco.MjModel:
        """The compiled model."""
        ...

    @property
    def data(self) -> mujoco.MjData:
        """``mjData`` at the configuration."""
        ...

    @property
    def object_body(self) -> str:
        """The object's body."""
        ...

    @property
    def contact_tolerance(self) -> float:
        """m: a geom within this distance of the object touches it."""
        ...

    @property
    def contact_types(self) -> Mapping[str, str]:
        """Geom label -> contact type."""
        ...

    @property
    def selections(self) -> Sequence[tuple[str, Sequence[str]]]:
        """Per ``contacts`` entry: its description and the labels it selects."""
        ...

    @property
    def rule_matches(self) -> Sequence[TypedRule]:
        """Per ``contact_rules`` entry: the touching geoms it typed."""
        ...

    @property
    def ignored_geoms(self) -> Sequence[str]:
        """Labels whose contacts with the object are dropped."""
        ...

    @property
    def document(self) -> Mapping[str, Any]:
        """The normalised grasp document."""
        ...

    @property
    def file(self) -> str:
        """The grasp file, for messages."""
        ...


@dataclass(frozen=True)
class ContactRow:
    r"""One hand geom and one object geom near each other.

    Parameters
    ----------
    geom, body
        The geom outside the object (label, `geom_label()`) and its body's name.
    object_geom
        The object's geom (label).
    distance
        Signed surface distance (m), exact (``mj_geomDistance``); negative: penetration.
    position
        ``(3,)`` contact point (m, world): the state's contact when selected, else the midpoint
        of the witness points.
    normal
        ``(3,)`` unit normal into the object, world; ``None`` when the surfaces touch exactly
        and the pair is not the state's contact.
    type
        The file's type for the geom (``"F"``, ``"L"``, ``"S"``, ``"D"``), ``"ignore"``, or ``None``.
    selected
        Whether this pair is a contact of the grasp state.
    why
        Why not (empty when selected): ``"beyond contact_tolerance"``, ``"ignored"``, ``"a deeper
        contact of its body is kept"`` or ``"no contact selects it"``.
    """

    geom: str
    body: str
    object_geom: str
    distance: float
    position: NDArray[np.float64]
    normal: NDArray[np.float64] | None
    type: str | None
    selected: bool
    why: str


def kept_contacts(grasp: LoadedGrasp) -> list[DetectedContact]:
    """The contacts the grasp state is built from (before the ignored are dropped)."""
    return contacts_once(
        grasp.model,
        grasp.data,
        object_body=grasp.object_body,
        one_per_body=True,
        tolerance=grasp.contact_tolerance,
    )


def _max_penetration(grasp: LoadedGrasp) -> float:
    return float(grasp.document.get("max_penetration", 1e-3))


def _field_of(grasp: LoadedGrasp, label: str) -> str | None:
    """The field that types the geom ``label``: ``contacts[i]``, or ``contact_rules[j]`` for a
    geom a rule typed; None for an ignored or untyped geom."""
    i = next((i for i, (_, labels) in enumerate(grasp.selections) if label in labels), None)
    if i is not None:
        return f"contacts[{i}]"
    return next((m.field for m in grasp.rule_matches if m.type != "ignore" and label in m.labels), None)


def check_penetration(grasp: LoadedGrasp) -> None:
    """No contact of the state (selected, or typed by a rule) is deeper inside the object than
    ``max_penetration``.

    Raises
    ------
    GraspError
        ``contacts[i]`` or ``contact_rules[j]``: naming the geom, the object's geom and the depth.
    """
    limit = _max_penetration(grasp)
    for c in kept_contacts(grasp):
        field = _field_of(grasp, c.geom)
        if field is not None and -c.distance > limit:
            raise GraspError(
                grasp.file,
                field,
                f"geom {c.geom!r} is {-1e3 * c.distance:.3g} mm inside the object's geom "
                f"{c.object_geom!r} > max_penetration {1e3 * limit:.3g} mm: move the finger out "
                "(or raise max_penetration)",
            )


def contact_warnings(grasp: LoadedGrasp) -> list[str]:
    """One line per cause: the selected contacts that penetrate an object geom (deeper than
    [`REPORTED_PENETRATION`][mjtvm.grasp.contacts.report.REPORTED_PENETRATION], within ``max_penetration``; one line per object geom,
    counting them), each IK target geom that does not touch the object (naming the geom of its
    body that does) and each pair of hand geoms that overlap (however many contact points
    MuJoCo gives the pair)."""
    limit = _max_penetration(grasp)
    deep: dict[str, list[tuple[str, str, float]]] = {}  # object geom -> (field, geom, depth)
    for c in kept_contacts(grasp):
        field = _field_of(grasp, c.geom)
        if field is not None and -c.distance > REPORTED_PENETRATION:
            deep.setdefault(c.object_geom, []).append((field, c.geom, -c.distance))
    out = []
    for object_geom, found in deep.items():
        if len(found) == 1:
            field, geom, depth = found[0]
            out.append(
                f"{field}: geom {geom!r} is {1e3 * depth:.3g} mm inside the object's geom "
                f"{object_geom!r} (max_penetration {1e3 * limit:.3g} mm)"
            )
            continue
        listed = ", ".join(f"{f} {g!r} {1e3 * d:.3g} mm" for f, g, d in found[:_LISTED])
        more = f" and {len(found) - _LISTED} more" if len(found) > _LISTED else ""
        out.append(
            f"{len(found)} contacts are inside the object's geom {object_geom!r}, by up to "
            f"{1e3 * max(d for _, _, d in found):.3g} mm (max_penetration {1e3 * limit:.3g} mm): "
            f"{listed}{more}"
        )
    return out + _ik_warnings(grasp) + _self_overlaps(grasp)


_LISTED = 5
"""Contacts a grouped warning names before "and N more"."""


def _self_overlaps(grasp: LoadedGrasp) -> list[str]:
    """One line per pair of hand geoms (neither the object's nor the world's) that overlap
    deeper than [`REPORTED_PENETRATION`][mjtvm.grasp.contacts.report.REPORTED_PENETRATION] at the configuration: a contact no LP sees, whose
    force the physics check would feel. MuJoCo's several contact points of one pair (boxes,
    meshes) are one line: the deepest, counting them."""
    model = grasp.model
    inside = subtree(model, model.body(grasp.object_body).id)
    data = mujoco.MjData(model)
    data.qpos[:] = grasp.data.qpos
    data.mocap_pos[:], data.mocap_quat[:] = grasp.data.mocap_pos, grasp.data.mocap_quat
    mujoco.mj_forward(model, data)
    pairs: dict[tuple[int, int], list[float]] = {}
    for c in data.contact[: data.ncon]:
        bodies = (int(model.geom_bodyid[c.geom1]), int(model.geom_bodyid[c.geom2]))
        if c.dist < -REPORTED_PENETRATION and not any(b in inside or b == 0 for b in bodies):
            pairs.setdefault((int(c.geom1), int(c.geom2)), []).append(-float(c.dist))
    out = []
    for (g1, g2), depths in pairs.items():
        points = f" ({len(depths)} contact points)" if len(depths) > 1 else ""
        out.append(
            f"hand geoms {geom_label(model, g1)!r} and {geom_label(model, g2)!r} "
            f"overlap by {_mm(max(depths))} mm{points}: a contact of the hand with itself, which no LP sees"
        )
    return out


def _mm(d: float) -> str:
    """``d`` (m) in mm, 3 significant digits, to the nanometre (no -0, no 1e-14)."""
    return f"{round(1e3 * d, 6) + 0.0:.3g}"


def _ik_warnings(grasp: LoadedGrasp) -> list[str]:
    config = grasp.document["configuration"]
    if "ik" not in config:
        return []
    model, tol = grasp.model, grasp.contact_tolerance
    inside = subtree(model, model.body(grasp.object_body).id)
    with precise_collision(model):
        near = near_pairs(model, grasp.data, inside, 1.0)
    nearest: dict[int, float] = {}
    for p in near:
        nearest[p.geom] = min(nearest.get(p.geom, np.inf), p.distance)
    out = []
    for i, t in enumerate(config["ik"]["targets"]):
        if "geom" not in t:
            continue
        g = geom_id(model, t["geom"])
        d = nearest.get(g, np.inf)
        if d <= tol:
            continue
        body = int(model.geom_bodyid[g])
        others = [
            f"{geom_label(model, h)!r} ({_mm(e)} mm)"
            for h, e in sorted(nearest.items())
            if h != g and int(model.geom_bodyid[h]) == body and e <= tol
        ]
        far = "more than 1 m" if not np.isfinite(d) else f"{_mm(d)} mm"
        where = (
            f"; geom {', '.join(others)} of its body touches it instead: the contact is not the IK target's"
            if others
            else f" (contact_tolerance {1e3 * tol:.3g} mm)"
        )
        out.append(
            f"configuration.ik.targets[{i}]: the IK target geom {geom_label(model, g)!r} is {far} "
            f"from the object{where}"
        )
    return out


def contact_rows(grasp: LoadedGrasp, within: float | None = None) -> list[ContactRow]:
    r"""Every geom pair (hand geom, object geom) that may collide within ``within`` (m; default
    [`NEAR_TOLERANCES`][mjtvm.grasp.contacts.report.NEAR_TOLERANCES] contact tolerances, at least 1 mm), ordered by hand geom id.

    A pair is ``selected`` when it is a contact of the grasp state: within
    ``contact_tolerance``, the deepest of its body, typed by the file and not ignored.
    """
    model, tol = grasp.model, grasp.contact_tolerance
    within = max(NEAR_TOLERANCES * tol, 1e-3) if within is None else within
    inside = subtree(model, model.body(grasp.object_body).id)
    kept = {(c.geom, c.object_geom): c for c in kept_contacts(grasp)}
    with precise_collision(model):
        pairs = near_pairs(model, grasp.data, inside, max(within, tol))
    ignored = set(grasp.ignored_geoms)
    rows = []
    for p in pairs:
        label, obj = geom_label(model, p.geom), geom_label(model, p.object_geom)
        ctype = "ignore" if label in ignored else grasp.contact_types.get(label)
        contact = kept.get((label, obj))
        if contact is not None and ctype not in (None, "ignore"):
            why = ""
        elif p.distance > tol and contact is None:
            why = "beyond contact_tolerance"
        elif ctype == "ignore":
            why = "ignored"
        elif contact is None:
            why = "a deeper contact of its body is kept"
        else:
            why = "no contact selects it"
        body = int(model.geom_bodyid[p.geom])
        rows.append(
            ContactRow(
                geom=label,
                body=mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or f"body#{body}",
                object_geom=obj,
                distance=p.distance,
                position=p.position if contact is None else contact.position,
                normal=p.normal if contact is None else contact.normal,
                type=ctype,
                selected=not why,
                why=why,
            )
        )
    return [r for r in rows if r.distance <= within or r.selected]
