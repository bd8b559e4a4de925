r"""A loaded grasp ([`Grasp`][mjtvm.grasp.resolve.loaded.Grasp]): a hand, an object and a grasp configuration in MuJoCo,
with each contact's type and friction and each joint's operation range; [`Grasp.state()`][mjtvm.grasp.resolve.loaded.Grasp.state]
gives its [`GraspState`][mjtvm.model.state.GraspState] (`grasp_state()`).

[`load_grasp()`][mjtvm.grasp.resolve.file.load_grasp] builds it from a grasp file. *Contacts that touch.*
Geoms placed exactly touching are often reported by MuJoCo only once they penetrate; a grasp
file's ``contact_tolerance`` (default 0.1 mm) counts a geom within that distance of the object
as touching: MuJoCo's collision runs with that margin on the object's geoms for detection only.
Every selection must touch (else an error gives the nearest distance, from ``mj_geomDistance``)
and every touching geom must be selected or ignored; [`Grasp.contact_report()`][mjtvm.grasp.resolve.loaded.Grasp.contact_report] lists found
vs expected.

World frame, SI units.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.grasp.actuation.transmission import ModelTransmission
from mjtvm.grasp.contacts.report import check_penetration
from mjtvm.grasp.document.checks import GraspError, NoContactError
from mjtvm.grasp.resolve.model import (
    build_spec,
)
from mjtvm.grasp.resolve.rules import RuleMatch, touching_geoms
from mjtvm.grasp.resolve.state import (
    geom_id,
    grasp_state,
    limit_options,
    object_weight,
    subtree,
)
from mjtvm.model.contacts import Contact
from mjtvm.model.friction import cone_margin
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState

__all__ = ["Grasp"]

_OBJ = mujoco.mjtObj
_SCALAR = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))


@dataclass(frozen=True, eq=False)
class Grasp:
    r"""A hand, an object and a grasp configuration, ready for `state()`.

    Attributes
    ----------
    name
        The grasp's name (the file's stem by default).
    path, model_path
        The grasp file and the MJCF file (``None`` for a grasp given as a mapping with an
        absolute model path: ``path`` only).
    model, data
        The compiled model and ``mjData`` at the configuration, after ``mj_forward``.
    object_body
        The object's body (its subtree is the object).
    joints
        The state's joints, in model order unless the file lists them.
    contact_types
        Geom label (`geom_label()`) -> ``"F"``, ``"L"``, ``"S"`` or
        ``"D"``, every geom of every selection and every touching geom a rule typed.
    selections
        Per ``contacts`` entry of the file: its description and the labels it selects.
    mu, slide_directions
        Geom label -> friction coefficient (F and S contacts) and -> ``(3,)`` slide direction.
    refs, rvds
        ``(K, 6)`` REFS [N; N m about the object's origin]; ``(R, 6)`` RVDS or ``None``.
    ignored_geoms
        Labels whose contacts with the object are dropped.
    operation_ranges
        Joint name -> operation range at the joint.
    motors
        Joint name -> `DCMotor` from a datasheet, ``None`` when the
        model's ``<dcmotor>`` drives the joint, or why there is no motor model (a string).
    contact_tolerance
        m: a geom within this distance of the object touches it.
    friction_edges, slip
        As in ``mjtvm.state/1``.
    lift
        The file's ``lift`` table (normalised), or ``None``.
    ik_bounds
        Joint name -> (low, high) for the lift's IK (the file's ``lift.bounds``).
    document
        The normalised grasp document.
    preloads
        Geom label -> minimum normal force (N) of its contact (a ``contacts`` entry's
        ``preload``; ``mjtvm.state/1``'s contact ``preload``).
    transmission
        How the model's actuators and equality constraints drive the joints
        ([`mjtvm.grasp.actuation.transmission`][mjtvm.grasp.actuation.transmission]), or ``None`` for the paper's independent joints
        (each joint its own actuator, no equality). With a transmission, ``operation_ranges``
        and ``motors`` are keyed by actuator name, in the actuator's units.
    mu_ranges
        Geom label -> friction interval ``(mu_lo, mu_hi)`` of its F or S contact (the file's
        ``mu_range``, top-level or per contact): the states' contact ``mu_range``.
    friction_margin
        The states' ``friction_margin``: the file's ``friction_margin`` delta on its ``cone``,
        $1 - (1 - \delta) c$ (`cone_margin()`; 0 by default).
    cone
        The MuJoCo cone of that margin: ``"elliptic"`` or ``"pyramidal"`` (the file's ``cone``,
        ``"model"`` read from the model's ``opt.cone``).
    rule_matches
        Per ``contact_rules`` entry: the touching geoms it typed ([`mjtvm.grasp.resolve.rules`][mjtvm.grasp.resolve.rules]);
        those geoms are in ``contact_types`` (or ``ignored_geoms``), not in ``selections``.
    """

    name: str
    path: Path | None
    model_path: Path
    model: mujoco.MjModel
    data: mujoco.MjData
    object_body: str
    joints: tuple[str, ...]
    contact_types: Mapping[str, str]
    selections: tuple[tuple[str, tuple[str, ...]], ...]
    mu: Mapping[str, float]
    slide_directions: Mapping[str, tuple[float, ...]]
    refs: NDArray[np.float64]
    rvds: NDArray[np.float64] | None
    ignored_geoms: tuple[str, ...]
    operation_ranges: Mapping[str, OperationRange]
    motors: Mapping[str, DCMotor | str | None]
    contact_tolerance: float
    friction_edges: int
    slip: str
    lift: Mapping[str, Any] | None
    ik_bounds: Mapping[str, tuple[float, float]]
    document: Mapping[str, Any]
    preloads: Mapping[str, float] = field(default_factory=lambda: MappingProxyType({}))
    transmission: ModelTransmission | None = None
    rule_matches: tuple[RuleMatch, ...] = ()
    mu_ranges: Mapping[str, tuple[float, float]] = field(default_factory=lambda: MappingProxyType({}))
    friction_margin: float = 0.0
    cone: str = "elliptic"

    def with_options(
        self,
        *,
        mg: float | None = None,
        mu: float | Mapping[str, float] | None = None,
        friction_margin: float | None = None,
    ) -> Grasp:
        r"""The grasp with another object weight and/or friction.

        ``mg`` (N): the REFS become the object's weight of magnitude ``mg`` (along gravity,
        through the object's centre of mass) plus each of the file's wrenches; the file's REFS
        must include the weight. ``mu``: one coefficient for every contact, or geom label ->
        coefficient updating the file's (the file's ``mu_range`` intervals must hold it).
        ``friction_margin``: the margin $\delta$ instead of the file's, on the grasp's
        ``cone`` (`cone_margin()`).
        """
        margin = self.friction_margin if friction_margin is None else cone_margin(self.cone, friction_margin)
        refs = self.refs if mg is None else self.weight_refs(mg)
        friction = self.mu
        if mu is not None:
            friction = MappingProxyType(
                {g: float(mu) for g in self.contact_types}
                if not isinstance(mu, Mapping)
                else {**self.mu, **mu}
            )
        return replace(self, refs=refs, mu=friction, friction_margin=margin)

    @property
    def default_mu(self) -> float | None:
        """The one coefficient the contacts share (``None`` if they differ: a contact's own ``mu``
        overriding the file's), else the file's ``mu``. The physics check simulates one
        coefficient: with it, its LP is solve's."""
        values = set(self.mu.values())
        if len(values) == 1:
            return values.pop()
        return float(self.document["mu"]) if not values and self.document["mu"] is not None else None

    @property
    def weight_mg(self) -> float | None:
        """|weight| (N) when the REFS are the object's weight alone, else ``None``."""
        spec = self.document["refs"]
        if not spec["weight"] or any(any(w) for w in spec["wrenches"]):
            return None
        return float(np.linalg.norm(self.refs[0, :3]))

    def weight_refs(self, mg: float) -> NDArray[np.float64]:
        """``(K, 6)`` the REFS with the weight's magnitude set to ``mg`` (N), as `with_options()`
        makes them (without building a new grasp: the lift's states call this for every point)."""
        if not self.document["refs"]["weight"]:
            raise GraspError(self.file, "refs", "has no weight (weight = false): mg cannot replace it")
        spec = {**self.document["refs"], "mg": float(mg)}
        return document_refs(self.model, self.data, {"refs": spec}, self.object_body, self.file)

    def spec(self) -> mujoco.MjSpec:
        """A fresh ``MjSpec`` of the model file with the grasp's additions (object, supports), e.g.
        to attach motors (`mjtvm.physics`) before compiling; ``spec().compile()`` equals ``model``."""
        return build_spec(self.document, self.model_path, self.file)

    @property
    def file(self) -> str:
        return str(self.path) if self.path is not None else "grasp"

    def contact_report(self) -> list[dict[str, Any]]:
        r"""Found vs expected, one row per ``contacts`` entry, per ``contact_rules`` entry and per
        touching geom nobody selected.

        Each row: ``selection`` (as written), ``type``, ``found`` (labels touching the
        object within ``contact_tolerance``), ``distance`` (m, the smallest surface distance
        of the selection's geoms, from ``mj_geomDistance`` up to 0.1 m; ``None`` beyond).
        """
        touching = self._touching()
        rows = []
        for (what, labels), entry in zip(self.selections, self.document["contacts"], strict=True):
            rows.append(
                {
                    "selection": what,
                    "type": entry["type"],
                    "found": [g for g in labels if g in touching],
                    "distance": self._nearest(labels),
                }
            )
        for match in self.rule_matches:
            rows.append(
                {
                    "selection": f"{match.field} {match.description}",
                    "type": match.type,
                    "found": list(match.labels),
                    "distance": min((touching[g] for g in match.labels if g in touching), default=None),
                }
            )
        known = set(self.contact_types) | set(self.ignored_geoms)
        for g, dist in touching.items():
            if g not in known:
                rows.append({"selection": None, "type": None, "found": [g], "distance": dist})
        return rows

    def check_contacts(self) -> None:
        """Every selection touches the object, every touching geom is selected or ignored, and
        no selected contact is deeper inside the object than the file's ``max_penetration``
        (`check_penetration()`).

        Raises
        ------
        GraspError
            Naming the first selection that does not touch (with its nearest distance and the
            tolerance), the first touching geom that no selection names, or the first contact
            too deep (with its geom, the object's geom and the depth).
        """
        tol = self.contact_tolerance
        touching = self._touching()  # the nearest distances are computed only for a message
        for i, (what, labels) in enumerate(self.selections):
            if not any(g in touching for g in labels):
                d = self._nearest(labels)
                far = "more than 100 mm" if d is None else f"{1e3 * d:.3g} mm"
                raise NoContactError(
                    self.file,
                    f"contacts[{i}]",
                    f"{what} does not touch the object: nearest distance {far} > "
                    f"contact_tolerance {1e3 * tol:.3g} mm",
                    nearest=d,
                )
        known = set(self.contact_types) | set(self.ignored_geoms)  # selections and rules
        for g, dist in touching.items():
            if g not in known:
                raise GraspError(
                    self.file,
                    "contacts",
                    f"geom {g!r} touches the object (distance {1e3 * dist:.3g} mm) but no "
                    "contact selects it: add it to contacts with a type, to ignore, or to contact_rules",
                )
        check_penetration(self)

    def state(
        self,
        *,
        contact_types: Mapping[str, str] | None = None,
        slide_directions: Mapping[str, ArrayLike] | None = None,
        refs: ArrayLike | None = None,
        rvds: ArrayLike | None = None,
        mu: float | Mapping[str, float] | None = None,
        preloads: Mapping[str, float] | None = None,
        **options: Any,
    ) -> GraspState:
        r"""The grasp state (`grasp_state()`) with the ignored contacts dropped.

        ``contact_types`` and ``slide_directions`` update the grasp's (geom labels); ``refs``,
        ``rvds`` and ``mu`` replace them; ``preloads`` (geom label -> N) updates the file's
        contact preloads; further keywords go to
        `grasp_state()`.

        Raises
        ------
        GraspError
            A selection that does not touch, a touching geom nobody selected, a contact deeper
            than ``max_penetration``, or an S contact without a slide direction.
        """
        self.check_contacts()
        types = {**{g: "D" for g in self.ignored_geoms}, **self.contact_types, **(contact_types or {})}
        slides = {**self.slide_directions, **(slide_directions or {})}
        for i, (what, labels) in enumerate(self.selections):
            if any(types.get(g) == "S" and g not in slides for g in labels):
                raise GraspError(self.file, f"contacts[{i}].slide", f"required for the S contact {what}")
        options = {
            "friction_edges": self.friction_edges,
            "slip": self.slip,
            "joint_damping": self.document["joint_losses"] == "fold",
            "joint_limits": limit_options(self.document["joint_limits"]),
            **options,
        }
        # The transmission read when the grasp was loaded, at this same configuration; with
        # its damping zeroed ("ignore") only where the state's balance takes no damping either.
        if self.document["joint_losses"] == "fold" or not options["joint_damping"]:
            options.setdefault("transmission", self.transmission)
        state = grasp_state(
            self.model,
            self.data,
            contact_types=types,
            mu=self.mu if mu is None else mu,
            refs=self.refs if refs is None else refs,
            rvds=self.rvds if rvds is None else rvds,
            slide_directions=slides,
            object_body=self.object_body,
            joints=self.joints,
            operation_ranges=self.operation_ranges,
            contact_tolerance=self.contact_tolerance,
            **options,
        )
        ignored = set(self.ignored_geoms)
        pre = {**self.preloads, **(preloads or {})}
        kept = tuple(
            replace(c, preload=float(pre[c.name.split("#")[0]])) if pre.get(c.name.split("#")[0]) else c
            for c in state.contacts
            if c.name.split("#")[0] not in ignored
        )
        kept = with_mu_ranges(kept, self.mu_ranges)
        unchanged = len(kept) == len(state.contacts) and all(a is b for a, b in zip(kept, state.contacts))
        if unchanged and self.friction_margin == state.friction_margin:
            return state  # nothing dropped or replaced: the same state, not validated twice
        return state.with_(contacts=kept, friction_margin=self.friction_margin)

    def _touching(self) -> dict[str, float]:
        return touching_geoms(self.model, self.data, self.object_body, self.contact_tolerance)

    def _nearest(self, labels: Sequence[str]) -> float | None:
        """Smallest surface distance (m) between the labels' geoms and the object's, up to 0.1 m."""
        inside = subtree(self.model, self.model.body(self.object_body).id)
        obj = [g for g in range(self.model.ngeom) if int(self.model.geom_bodyid[g]) in inside]
        best, fromto = None, np.zeros(6)
        for label in labels:
            g = geom_id(self.model, label)
            for o in obj:
                d = float(mujoco.mj_geomDistance(self.model, self.data, g, o, 0.1, fromto))
                if d < 0.1 and (best is None or d < best):
                    best = d
        return best


def with_mu_ranges(
    contacts: Sequence[Contact], ranges: Mapping[str, tuple[float, float]]
) -> tuple[Contact, ...]:
    """``contacts`` with the friction interval of their geom (name up to ``#``) where ``ranges``
    has one and the contact has friction (F or S)."""
    return tuple(
        replace(c, mu_range=ranges[c.name.split("#")[0]])
        if c.type in ("F", "S") and c.name.split("#")[0] in ranges
        else c
        for c in contacts
    )


def document_refs(
    model: mujoco.MjModel, data: mujoco.MjData, doc: Mapping[str, Any], obj: str, file: str
) -> NDArray[np.float64]:
    """REFS vertices of a document's ``refs``: (weight +) each wrench (eq. 25-26's required
    external wrenches).

    Parameters
    ----------
    model, data
        The compiled model and ``mjData`` at the configuration.
    doc
        A mapping with the normalised ``refs`` table (``weight``, ``mg``, ``wrenches``).
    obj
        The object's body.
    file
        The grasp file, for messages.

    Returns
    -------
    NDArray
        ``(K, 6)`` read-only REFS [N; N m about the object's origin].

    Raises
    ------
    GraspError
        ``refs.mg`` given for an object without weight in the model.
    """
    spec = doc["refs"]
    weight = np.zeros(6)
    if spec["weight"]:
        weight = object_weight(model, data, object_body=obj)
        force = float(np.linalg.norm(weight[:3]))
        if spec["mg"] is not None and force == 0.0:
            raise GraspError(file, "refs.mg", "the object has no weight in the model to scale")
        if spec["mg"] is not None:  # the unit vector times mg: exactly [0, 0, -mg] for gravity along -z
            weight = np.concatenate([weight[:3] / force, weight[3:] / force]) * spec["mg"]
    refs = np.array([weight + np.array(w) for w in spec["wrenches"]])
    refs.setflags(write=False)
    return refs
