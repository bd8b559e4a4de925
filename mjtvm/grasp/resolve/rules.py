r"""Contact rules: the ``contact_rules`` of a ``mjtvm.grasp/1`` file (``docs/grasp-format.md``).

An enveloping grasp touches the object with many links; listing each in ``contacts`` is
tedious and the natural first file (every link a sticking F-point) locks the object. A rule
types every touching geom whose label (``geom``) or body name (``body``) matches a glob
pattern (`fnmatch.fnmatchcase()`): ``F``, ``L``, ``D``, or ``ignore`` (dropped, as an
``ignore`` entry). So three lines type a 16-link hand::

    contact_rules = [
      { body = "*distal*", type = "F" },
      { body = "palm", type = "ignore" },
      { body = "*", type = "L" },
    ]

Decisions (documented in ``docs/grasp-format.md``):

* the rules apply to the geoms touching the object at the configuration (as
  [`check_contacts()`][mjtvm.grasp.resolve.loaded.Grasp.check_contacts] finds them) that no ``contacts`` or
  ``ignore`` entry selects: explicit entries override the rules; among the rules, in file
  order, the first that matches wins;
* a pattern that matches no geom (or body) of the model outside the object is an error (a
  typo cannot be right for any configuration); a rule that types no touching geom at this
  configuration is not: the contact report (``export-state`` on stderr) shows it as "not
  found", since one set of rules serves many configurations;
* no ``S`` rule: a slide direction belongs to one contact (list it in ``contacts``);
* an ``F`` rule needs a friction coefficient, its own ``mu`` or the file's.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from mjtvm.grasp.contacts.memo import contacts_once
from mjtvm.grasp.contacts.pairs import near_pairs
from mjtvm.grasp.contacts.touch import geom_label, subtree
from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.document.sections import RULE_TYPES, check_contact_rules
from mjtvm.grasp.resolve.model import suggest

# The rules' document check lives with the other section checks (it needs no model); its
# names are re-exported here, where the rules' callers have always found them.
__all__ = [
    "RULE_TYPES",
    "RuleExpansion",
    "RuleMatch",
    "check_contact_rules",
    "expand_rules",
    "nearest_distance",
    "touching_geoms",
]


@dataclass(frozen=True)
class RuleMatch:
    """What one rule typed.

    Attributes
    ----------
    field
        The rule's field, e.g. ``"contact_rules[0]"``.
    description
        The rule as written, e.g. ``"body '*distal*'"``.
    type
        ``"F"``, ``"L"``, ``"D"`` or ``"ignore"``.
    labels
        The touching geoms it typed (labels, `geom_label()`),
        possibly none.
    """

    field: str
    description: str
    type: str
    labels: tuple[str, ...]


@dataclass(frozen=True)
class RuleExpansion:
    """The rules applied to the touching geoms.

    Attributes
    ----------
    types
        Geom label -> ``"F"``, ``"L"`` or ``"D"`` of every touching geom a typing rule took.
    mu
        Geom label -> friction coefficient (the rule's, else the file's) where one is known.
    ignored
        The touching geoms an ``ignore`` rule took.
    matches
        Per rule, in file order.
    """

    types: Mapping[str, str]
    mu: Mapping[str, float]
    ignored: tuple[str, ...]
    matches: tuple[RuleMatch, ...]


def touching_geoms(
    model: mujoco.MjModel, data: mujoco.MjData, object_body: str, tolerance: float
) -> dict[str, float]:
    """Label -> distance (m) of every geom touching the object within ``tolerance``: the
    deepest contact of each body, as the grasp state sees them (``data`` is not modified)."""
    found = contacts_once(model, data, object_body=object_body, one_per_body=True, tolerance=tolerance)
    out: dict[str, float] = {}
    for c in found:
        out[c.geom] = min(out.get(c.geom, np.inf), c.distance)
    return out


def nearest_distance(
    model: mujoco.MjModel, data: mujoco.MjData, object_body: str, within: float = 0.1
) -> float | None:
    """m: the smallest signed distance (``mj_geomDistance``) between a geom outside the object
    and the object's geoms, ``None`` when none is within ``within`` (m); negative: penetration."""
    pairs = near_pairs(model, data, subtree(model, model.body(object_body).id), within)
    return min((p.distance for p in pairs), default=None)


def _names(model: mujoco.MjModel, g: int) -> dict[str, str]:
    body = int(model.geom_bodyid[g])
    return {
        "geom": geom_label(model, g),
        "body": mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or f"body#{body}",
    }


def expand_rules(
    model: mujoco.MjModel,
    rules: Sequence[Mapping[str, Any]],
    touching: Collection[str],
    *,
    taken: Collection[str],
    object_body: int,
    mu: float | None,
    file: str,
) -> RuleExpansion:
    r"""Type the touching geoms that ``taken`` (explicit contacts and ignores) leaves.

    Parameters
    ----------
    model
        The compiled model.
    rules
        The normalised ``contact_rules`` ([`check_contact_rules()`][mjtvm.grasp.resolve.rules.check_contact_rules]).
    touching
        Labels of the geoms touching the object ([`touching_geoms()`][mjtvm.grasp.resolve.rules.touching_geoms]).
    taken
        Labels selected by ``contacts`` or ``ignore``: the rules leave them.
    object_body
        The object's body id (its subtree's geoms are never typed).
    mu
        The file's friction coefficient, or None.
    file
        The grasp file, for messages.

    Raises
    ------
    GraspError
        A pattern matching no geom (or body) of the model outside the object, with the
        closest name; an F rule without a friction coefficient.
    """
    inside = subtree(model, object_body)
    hand = {
        label: names
        for g in range(model.ngeom)
        if int(model.geom_bodyid[g]) not in inside and (model.geom_contype[g] or model.geom_conaffinity[g])
        for names in [_names(model, g)]
        for label in [names["geom"]]
    }
    for i, rule in enumerate(rules):
        field = f"contact_rules[{i}]"
        select, pattern = rule["select"], rule["pattern"]
        if not any(fnmatch.fnmatchcase(n[select], pattern) for n in hand.values()):
            candidates = sorted({n[select] for n in hand.values()})
            raise GraspError(
                file,
                f"{field}.{select}",
                f"{pattern!r} matches no {select} of the model that can touch the object"
                f"{suggest(pattern, candidates)}",
            )
        if rule["type"] == "F" and rule["mu"] is None and mu is None:
            raise GraspError(
                file,
                f"{field}.mu",
                f"the F rule {select} {pattern!r} needs a friction coefficient: set mu at the top or in the rule",
            )
    typed: dict[int, list[str]] = {i: [] for i in range(len(rules))}
    for label in touching:
        if label in taken or label not in hand:
            continue
        for i, rule in enumerate(rules):
            if fnmatch.fnmatchcase(hand[label][rule["select"]], rule["pattern"]):
                typed[i].append(label)
                break
    types: dict[str, str] = {}
    coefficients: dict[str, float] = {}
    ignored: list[str] = []
    matches: list[RuleMatch] = []
    for i, rule in enumerate(rules):
        labels = tuple(typed[i])
        matches.append(
            RuleMatch(f"contact_rules[{i}]", f"{rule['select']} {rule['pattern']!r}", rule["type"], labels)
        )
        if rule["type"] == "ignore":
            ignored += labels
            continue
        coefficient = rule["mu"] if rule["mu"] is not None else mu
        for label in labels:
            types[label] = rule["type"]
            if coefficient is not None:
                coefficients[label] = float(coefficient)
    return RuleExpansion(types, coefficients, tuple(ignored), tuple(matches))
