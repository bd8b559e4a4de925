r"""Which geoms touch the object, as MuJoCo reports them: labels for unnamed geoms, contact
detection within a distance tolerance (exact: every pair within it, checked against
``mj_geomDistance``, [`mjtvm.grasp.contacts.pairs`][mjtvm.grasp.contacts.pairs]), MuJoCo's iterative collision run to a tight
tolerance, exact normals where it would give approximate ones, and MuJoCo's round-off removed.

Frames and units: world frame, SI. Normals point into the object.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError
from mjtvm.grasp.contacts.normals import needs_exact_normal, object_normal
from mjtvm.grasp.contacts.pairs import GeomPair, near_pairs

__all__ = [
    "CCD_TOLERANCE",
    "ROUND_OFF_REL",
    "DetectedContact",
    "ancestors",
    "detected_contacts",
    "forward_touching",
    "geom_id",
    "geom_label",
    "model_id",
    "precise_collision",
    "subtree",
    "without_round_off",
]

_OBJ = mujoco.mjtObj
_G = mujoco.mjtGeom
_PRIMITIVES = {
    int(t)
    for t in (_G.mjGEOM_SPHERE, _G.mjGEOM_CAPSULE, _G.mjGEOM_ELLIPSOID, _G.mjGEOM_CYLINDER, _G.mjGEOM_BOX)
}


#: m: the convergence tolerance of MuJoCo's iterative collision when a grasp is read.
CCD_TOLERANCE = 1e-12

#: MuJoCo's round-off of an exact zero, relative to the largest entry of the same array.
ROUND_OFF_REL = 1e-15


def without_round_off(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """A copy of ``x`` with the entries at most [`ROUND_OFF_REL`][mjtvm.grasp.contacts.touch.ROUND_OFF_REL] times its largest set to 0.

    MuJoCo computes contact normals and ``mj_jac`` columns (cross products of joint axes and
    lever arms) in double precision; an exact zero comes out as ~1e-17 beside entries ~0.1.
    Such round-off, passed on, sits in the LPs beside O(1) entries of its row and column,
    where the equilibration (`mjtvm.lp.solvers.equilibrate()`) cannot tell it from data: on
    the generated 8-finger hand it made Problem 1 9x slower and put a TVMS vertex 3e-8
    (relative) outside. Entries of a genuinely small scale keep theirs: the cut is relative.
    """
    out = np.array(x, dtype=float)
    out[np.abs(out) <= ROUND_OFF_REL * np.max(np.abs(out), initial=0.0)] = 0.0
    return out


@dataclass(frozen=True)
class DetectedContact:
    r"""One contact between the object and another geom, as MuJoCo reports it.

    Parameters
    ----------
    geom
        Label of the geom touching the object (finger link, fingertip or palm): its name, or
        ``"<body>/geom<n>"`` when unnamed (`geom_label()`).
    body
        Id of that geom's body.
    position
        ``(3,)`` MuJoCo's contact point (midway between the two surfaces), world frame (m).
    normal
        ``(3,)`` unit normal pointing into the object, world frame.
    distance
        Signed distance between the surfaces (m); negative when they penetrate.
    object_geom
        Label of the object's geom it touches (`geom_label()`).
    """

    geom: str
    body: int
    position: NDArray[np.float64]
    normal: NDArray[np.float64]
    distance: float
    object_geom: str = ""


def model_id(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str, label: str) -> int:
    i = mujoco.mj_name2id(model, kind, name)
    if i < 0:
        raise ModelError(f"{label} {name!r}", "not in the model")
    return int(i)


def geom_label(model: mujoco.MjModel, geom: int) -> str:
    """A geom's name, or ``"<body>/geom<n>"`` for an unnamed geom (the n-th geom of its body).

    Public MJCF hands leave their collision geoms unnamed; the label keys them in contact
    types, state files and messages. It is stable under edits of other bodies, unlike the id.
    An unnamed body is ``"body#<id>"``.
    """
    name = mujoco.mj_id2name(model, _OBJ.mjOBJ_GEOM, int(geom))
    if name:
        return str(name)
    body = int(model.geom_bodyid[geom])
    body_name = mujoco.mj_id2name(model, _OBJ.mjOBJ_BODY, body) or f"body#{body}"
    return f"{body_name}/geom{int(geom) - int(model.body_geomadr[body])}"


def geom_id(model: mujoco.MjModel, label: str, what: str = "geom") -> int:
    """The id of the geom with this name or `geom_label()`; ModelError naming ``what`` if none."""
    i = mujoco.mj_name2id(model, _OBJ.mjOBJ_GEOM, label)
    if i >= 0:
        return int(i)
    body_name, sep, rest = label.rpartition("/geom")
    if sep and rest.isdigit():
        body = mujoco.mj_name2id(model, _OBJ.mjOBJ_BODY, body_name)
        if body < 0 and body_name.startswith("body#") and body_name[5:].isdigit():
            body = int(body_name[5:])
        if 0 <= body < model.nbody and int(rest) < int(model.body_geomnum[body]):
            return int(model.body_geomadr[body]) + int(rest)
    raise ModelError(f"{what} {label!r}", "not in the model")


def subtree(model: mujoco.MjModel, root: int) -> set[int]:
    """Ids of the body ``root`` and every body below it."""
    bodies = {root}
    for b in range(root + 1, model.nbody):  # parents precede children in mjModel
        if int(model.body_parentid[b]) in bodies:
            bodies.add(b)
    return bodies


def ancestors(model: mujoco.MjModel, body: int) -> set[int]:
    chain = {body}
    while body > 0:
        body = int(model.body_parentid[body])
        chain.add(body)
    return chain


def forward_touching(model: mujoco.MjModel, data: mujoco.MjData, object_body: int, tolerance: float) -> None:
    r"""``mj_forward`` with the object's geoms given a collision margin of ``tolerance`` (m)
    and MuJoCo's mid-phase off.

    MuJoCo reports a contact once the distance is below the larger margin of the pair (0
    by default), so geoms placed exactly touching may be missed; with the margin, a geom
    within ``tolerance`` of the object is in ``data.contact`` (with its true distance). The
    mid-phase culls with bounding volumes built at compile time without that margin (a pair
    1.94 mm apart was missed at a 2 mm tolerance), so it is disabled: every pair the broad
    phase passes reaches the narrow phase. What still escapes (an explicit ``<pair>``, whose
    margin is its own) [`detected_contacts()`][mjtvm.grasp.contacts.touch.detected_contacts] adds from ``mj_geomDistance``. Margins and
    flags are restored afterwards: they serve detection only, the model is unchanged.
    """
    geoms = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) in subtree(model, object_body)]
    saved = model.geom_margin[geoms].copy()
    flags = int(model.opt.disableflags)
    try:
        model.geom_margin[geoms] = np.maximum(saved, tolerance)
        model.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_MIDPHASE)
        with precise_collision(model):
            mujoco.mj_forward(model, data)
    finally:
        model.geom_margin[geoms] = saved
        model.opt.disableflags = flags


@contextlib.contextmanager
def precise_collision(model: mujoco.MjModel) -> Iterator[None]:
    r"""MuJoCo's iterative convex collision (GJK/EPA: box, cylinder, ellipsoid pairs) run to
    [`CCD_TOLERANCE`][mjtvm.grasp.contacts.touch.CCD_TOLERANCE] instead of the simulation's 1e-6 m, then restored.

    Where a flat face or edge meets a curved surface, the distance grows only quadratically
    along the tangency, so a 1e-6 m tolerance leaves the contact point uncertain by about
    $\sqrt{2 R \cdot 10^{-6}}$ (0.24 mm on a 3 cm cylinder; its normal 3e-3 off);
    1e-12 m makes that 0.25 um. Closed-form pairs (spheres, capsules, planes) are unaffected.
    """
    saved = (float(model.opt.ccd_tolerance), int(model.opt.ccd_iterations))
    try:
        model.opt.ccd_tolerance, model.opt.ccd_iterations = CCD_TOLERANCE, max(saved[1], 1000)
        yield
    finally:
        model.opt.ccd_tolerance, model.opt.ccd_iterations = saved


def detected_contacts(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    *,
    object_body: str = "object",
    one_per_body: bool = True,
    tolerance: float | None = None,
) -> list[DetectedContact]:
    r"""Contacts between ``object_body`` (and its subtree) and every other geom in ``data.contact``.

    Reads ``data`` as it is (call ``mj_forward`` first), unless ``tolerance`` is given. MuJoCo's
    contact frame normal points from ``geom1`` to ``geom2``; it is flipped when the object is
    ``geom1``. For pairs MuJoCo collides iteratively (an ellipsoid, or a cylinder with a
    capsule, cylinder or box) the normal is the object's exact surface normal at the contact
    point instead ([`mjtvm.grasp.contacts.normals`][mjtvm.grasp.contacts.normals]).

    Parameters
    ----------
    tolerance
        Detect anew with [`forward_touching()`][mjtvm.grasp.contacts.touch.forward_touching] (``data`` is updated) and keep the contacts
        at a distance of at most ``tolerance`` (m); a pair that MuJoCo's pipeline still did
        not report while ``mj_geomDistance`` puts it within ``tolerance`` is added with its
        witness points' midpoint and direction ([`pair_distance()`][mjtvm.grasp.contacts.pairs.pair_distance]),
        so the contacts are exactly the pairs within ``tolerance``. ``None``: the contacts
        MuJoCo reports.
    one_per_body
        Keep only the deepest contact of each body other than the world body. A convex link
        (a capsule with its fingertip sphere) touches a convex object at one point; when the
        two penetrate, MuJoCo may report one contact per geom of the link, all artefacts of
        the penetration but the deepest. Set ``False`` for non-convex links.

    Returns
    -------
    list of DetectedContact
        Ordered by geom id, then by MuJoCo's contact order.

    Raises
    ------
    ModelError
        Unknown body.
    """
    ob = model_id(model, _OBJ.mjOBJ_BODY, object_body, "body")
    inside = subtree(model, ob)
    if tolerance is not None:
        forward_touching(model, data, ob, tolerance)
    found: list[tuple[int, int, DetectedContact, int]] = []
    near = None
    if tolerance is not None:
        with precise_collision(model):
            near = {(p.geom, p.object_geom): p for p in near_pairs(model, data, inside, tolerance)}
    for i in range(data.ncon):
        c = data.contact[i]
        if tolerance is not None and float(c.dist) > tolerance:
            continue  # within the model's own margin, not within the tolerance
        g1, g2 = int(c.geom1), int(c.geom2)
        in1, in2 = int(model.geom_bodyid[g1]) in inside, int(model.geom_bodyid[g2]) in inside
        if in1 == in2:
            continue
        other = g1 if in2 else g2
        name = geom_label(model, other)
        normal = without_round_off(np.array(c.frame[:3], dtype=float) * (1.0 if in2 else -1.0))
        obj_geom = g2 if in2 else g1
        if near is not None and (other, obj_geom) not in near:
            continue  # within the tolerance by MuJoCo's contact, not by the pair's exact distance
        if needs_exact_normal(model, obj_geom, other):  # GJK/EPA normals: the object's exact one
            exact = object_normal(model, data, obj_geom, np.array(c.pos, dtype=float))
            normal = normal if exact is None else without_round_off(-exact)
        contact = DetectedContact(
            geom=name,
            body=int(model.geom_bodyid[other]),
            position=np.array(c.pos, dtype=float),
            normal=normal / np.linalg.norm(normal),
            distance=float(c.dist),
            object_geom=geom_label(model, obj_geom),
        )
        found.append((other, i, contact, obj_geom))
    if near is not None:
        found += _missed_pairs(model, data, near, {(e[0], e[3]) for e in found})
    if one_per_body:
        deepest: dict[int, tuple[int, int, DetectedContact, int]] = {}
        kept = []
        for entry in found:
            body = entry[2].body
            if body == 0:
                kept.append(entry)
            elif body not in deepest or entry[2].distance < deepest[body][2].distance:
                deepest[body] = entry
        found = kept + list(deepest.values())
    return [entry[2] for entry in sorted(found, key=lambda e: (e[0], e[1]))]


def _missed_pairs(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    near: dict[tuple[int, int], GeomPair],
    reported: set[tuple[int, int]],
) -> list[tuple[int, int, DetectedContact, int]]:
    """The ``near`` pairs that ``data.contact`` lacks (none of its contacts of the pair within
    the tolerance), as contacts after MuJoCo's (index ``ncon + k``), with the normal
    convention of [`detected_contacts()`][mjtvm.grasp.contacts.touch.detected_contacts]."""
    out: list[tuple[int, int, DetectedContact, int]] = []
    for pair in near.values():
        if (pair.geom, pair.object_geom) in reported:
            continue
        contact = DetectedContact(
            geom=geom_label(model, pair.geom),
            body=int(model.geom_bodyid[pair.geom]),
            position=pair.position,
            normal=_pair_normal(model, data, pair),
            distance=pair.distance,
            object_geom=geom_label(model, pair.object_geom),
        )
        out.append((pair.geom, int(data.ncon) + len(out), contact, pair.object_geom))
    return out


def _pair_normal(model: mujoco.MjModel, data: mujoco.MjData, pair: GeomPair) -> NDArray[np.float64]:
    """The pair's normal into the object: the object's exact one where [`detected_contacts()`][mjtvm.grasp.contacts.touch.detected_contacts]
    would take it, else the witness points' direction."""
    exact = None
    if needs_exact_normal(model, pair.object_geom, pair.geom) or pair.normal is None:
        if int(model.geom_type[pair.object_geom]) in _PRIMITIVES:
            exact = object_normal(model, data, pair.object_geom, pair.position)
    if exact is not None:
        normal = -exact
    elif pair.normal is not None:
        normal = pair.normal
    else:
        raise ModelError(
            f"geom {geom_label(model, pair.geom)!r}",
            f"touches the object's geom {geom_label(model, pair.object_geom)!r} exactly on an edge or "
            "a mesh, where the contact normal is undefined: move it by a micrometre",
        )
    normal = without_round_off(normal)
    return normal / np.linalg.norm(normal)
