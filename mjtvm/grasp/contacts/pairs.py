r"""The geom pairs that can touch the object, and their exact distances (``mj_geomDistance``).

MuJoCo's collision pipeline reports a pair only if its broad phase and mid-phase let it
through; the mid-phase bounding volumes are built at compile time without the collision
margin that [`forward_touching()`][mjtvm.grasp.contacts.touch.forward_touching] adds, so a pair within the
tolerance can be culled there. ``mj_geomDistance`` runs the pair's narrow phase alone: the
distances below are what the contact detection is checked against and completed with.

Which pairs can touch follows MuJoCo's own filter (``engine_collision_driver``): a hand geom
and an object geom collide when ``contype``/``conaffinity`` match, their bodies are not
welded together, not parent and child (unless the parent filter is disabled or one is the
world), and not excluded by ``<exclude>``; an explicit ``<pair>`` always collides.

Frames and units: world frame, SI. Normals point into the object.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

__all__ = ["PAIRS_MEMO_SIZE", "GeomPair", "candidate_pairs", "near_pairs", "pair_distance"]

#: m: below this |distance| the segment between the witness points has no direction.
_TOUCHING = 1e-12


@dataclass(frozen=True)
class GeomPair:
    r"""A hand geom and an object geom, at their exact signed distance.

    Parameters
    ----------
    geom, object_geom
        Ids of the geom outside the object (finger, palm, table) and of the object's geom.
    distance
        Signed surface distance (m): positive apart, negative penetrating.
    position
        ``(3,)`` midpoint of the two witness points (MuJoCo's contact point), world (m).
    normal
        ``(3,)`` unit normal pointing into the object, world; ``None`` when the surfaces
        touch exactly (the witness points coincide and give no direction).
    """

    geom: int
    object_geom: int
    distance: float
    position: NDArray[np.float64]
    normal: NDArray[np.float64] | None


def _weld_parent(model: mujoco.MjModel, body: int) -> int:
    return int(model.body_weldid[int(model.body_parentid[int(model.body_weldid[body])])])


def _filtered(model: mujoco.MjModel, b1: int, b2: int) -> bool:
    """MuJoCo's body-pair filter: welded together, or parent and child (not the world)."""
    w1, w2 = int(model.body_weldid[b1]), int(model.body_weldid[b2])
    if w1 == w2:
        return True
    parent_filter = not model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_FILTERPARENT)
    return (
        parent_filter
        and w1 != 0
        and w2 != 0
        and (w1 == _weld_parent(model, b2) or w2 == _weld_parent(model, b1))
    )


#: Models whose candidate pairs are kept (the last ones asked for): a dataset compiles its
#: grasp file's model per object scale, every one with the same pairs.
PAIRS_MEMO_SIZE = 4

_PAIRS: OrderedDict[tuple[Any, ...], tuple[tuple[int, int], ...]] = OrderedDict()
_PAIRS_LOCK = threading.Lock()

# Every field the pairs are read from (the filter below): the memo's key holds their bytes.
_PAIR_FIELDS = (
    "geom_bodyid",
    "geom_contype",
    "geom_conaffinity",
    "exclude_signature",
    "body_weldid",
    "body_parentid",
    "pair_geom1",
    "pair_geom2",
)


def candidate_pairs(model: mujoco.MjModel, object_bodies: set[int]) -> list[tuple[int, int]]:
    """``(geom, object_geom)`` of every pair MuJoCo may collide between the object (the bodies
    ``object_bodies``) and the rest of the model, ordered by geom id then object geom id.

    They depend on the model's structure alone (which geoms collide, which bodies are welded
    or parent and child): kept for the last [`PAIRS_MEMO_SIZE`][mjtvm.grasp.contacts.pairs.PAIRS_MEMO_SIZE]
    models, keyed on the bytes of every field read, so a model that differs in any of them
    (or edited in place) is read anew."""
    parent_filter = bool(model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_FILTERPARENT))
    key = (
        tuple(sorted(object_bodies)),
        parent_filter,
        *(getattr(model, f).tobytes() for f in _PAIR_FIELDS),
    )
    with _PAIRS_LOCK:
        hit = _PAIRS.get(key)
        if hit is not None:
            _PAIRS.move_to_end(key)
            return list(hit)
    found = _candidate_pairs(model, object_bodies)
    with _PAIRS_LOCK:
        _PAIRS[key] = tuple(found)
        while len(_PAIRS) > PAIRS_MEMO_SIZE:
            _PAIRS.popitem(last=False)
    return found


def _candidate_pairs(model: mujoco.MjModel, object_bodies: set[int]) -> list[tuple[int, int]]:
    excluded = {int(s) for s in model.exclude_signature}
    obj = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) in object_bodies]
    pairs = set()
    for g in range(model.ngeom):
        bg = int(model.geom_bodyid[g])
        if bg in object_bodies:
            continue
        for o in obj:
            bo = int(model.geom_bodyid[o])
            match = (model.geom_contype[g] & model.geom_conaffinity[o]) or (
                model.geom_contype[o] & model.geom_conaffinity[g]
            )
            signature = (min(bg, bo) << 16) + max(bg, bo)
            if match and signature not in excluded and not _filtered(model, bg, bo):
                pairs.add((g, o))
    for g1, g2 in zip(model.pair_geom1, model.pair_geom2, strict=True):
        g1, g2 = int(g1), int(g2)
        if (int(model.geom_bodyid[g1]) in object_bodies) != (int(model.geom_bodyid[g2]) in object_bodies):
            pairs.add((g2, g1) if int(model.geom_bodyid[g1]) in object_bodies else (g1, g2))
    return sorted(pairs)


def pair_distance(
    model: mujoco.MjModel, data: mujoco.MjData, geom: int, object_geom: int, distmax: float
) -> GeomPair | None:
    r"""The pair at its ``mj_geomDistance`` (``None`` if farther than ``distmax``, m).

    ``data`` must hold the geoms' poses (after ``mj_kinematics`` or ``mj_forward``). The
    segment ``fromto`` runs from the hand geom's witness point to the object's; divided by
    the signed distance it is the unit normal from the hand geom into the object, whether the
    two are apart or penetrate (MuJoCo's contact frame for ``geom1`` = the hand geom).
    """
    fromto = np.zeros(6)
    d = float(mujoco.mj_geomDistance(model, data, geom, object_geom, distmax, fromto))
    if d >= distmax:
        return None
    segment = fromto[3:] - fromto[:3]
    normal = segment / d if abs(d) > _TOUCHING else None
    if normal is not None:
        normal = normal / np.linalg.norm(normal)
    return GeomPair(geom, object_geom, d, 0.5 * (fromto[:3] + fromto[3:]), normal)


def near_pairs(
    model: mujoco.MjModel, data: mujoco.MjData, object_bodies: set[int], within: float
) -> list[GeomPair]:
    """Every [`candidate_pairs()`][mjtvm.grasp.contacts.pairs.candidate_pairs] pair at a distance of at most ``within`` (m), in that order."""
    found = []
    for g, o in candidate_pairs(model, object_bodies):
        pair = pair_distance(model, data, g, o, within + max(within, 1e-3))
        if pair is not None and pair.distance <= within:
            found.append(pair)
    return found
