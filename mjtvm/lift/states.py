r"""The grasp states of a scripted lift ([`Lift`][mjtvm.lift.trajectory.Lift]): each state's
contacts retyped as the lift's variant asks, and the S-points' slide directions.

Slide directions $\hat p_{C_s}$ of the S-points, from the lift's motion ([`mjtvm.lift.trajectory`][mjtvm.lift.trajectory]):

* ``"physical"`` (default): $T^T T (G^T \dot r - J \dot q)$, the object's contact-point
  velocity relative to the finger's, i.e. the slip the motion produces (eq. 13 with
  $\rho > 0$): kinetic friction (eq. 16-17) resists the motion;
* ``"literal"``: the paper's printed $A_s [(J_c^+ G_c^T)^T\ I]^T \dot r =
  T^T T (J \dot q - G^T \dot r)$, the reverse: friction helps it.

A state's contacts are the lift's finger and support geoms within the grasp's contact
tolerance of the object (`start_tolerance()`: the grasp file's
``contact_tolerance``, at least `TOUCH_TOL`), the contacts
``mjtvm solve`` finds on the grasp itself: a D-point (e.g. the palm under the object)
exists only while it is that near. With the grasp's slip mode and contact preloads, state 0
of a lift at the grasp's own configuration is the grasp's state (``Grasp.state``) with its
contacts retyped as the variant asks.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Literal

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError, StateError
from mjtvm.grasp.resolve.loaded import with_mu_ranges
from mjtvm.grasp.resolve.state import detected_contacts, grasp_state, limit_options
from mjtvm.lift.march import start_tolerance
from mjtvm.lift.trajectory import Lift
from mjtvm.model.state import GraspState

__all__ = ["READINGS", "VARIANTS", "Reading", "Variant", "lift_state", "slide_directions"]

Reading = Literal["physical", "literal"]
Variant = Literal["L", "S"]
READINGS: tuple[Reading, ...] = ("physical", "literal")
VARIANTS: tuple[Variant, ...] = ("L", "S")


def _index(lift: Lift, index: int) -> int:
    n = lift.num_states
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < n:
        raise StateError("index", f"expected a state index in [0, {n}), got {index!r}")
    return int(index)


def slide_directions(lift: Lift, index: int, *, reading: Reading = "physical") -> dict[str, NDArray]:
    r"""Unit slide direction $\hat p_{C_s}$ of each L/S geom at state ``index`` (module doc).

    Raises
    ------
    StateError
        Unknown reading or bad index.
    ModelError
        A slip too small to give a direction (below 1e-9 m/m).
    """
    if reading not in READINGS:
        raise StateError("reading", f"expected one of {', '.join(READINGS)}, got {reading!r}")
    sign, out = (1.0 if reading == "physical" else -1.0), {}
    for g, role, s in zip(lift.geoms, lift.roles, lift.slips[_index(lift, index)], strict=True):
        if role == "N":
            if float(np.linalg.norm(s)) < 1e-9:
                raise ModelError(f"geom {g!r}", f"no slip at state {index}: the slide direction is undefined")
            out[g] = sign * s / np.linalg.norm(s)
    return out


def lift_state(
    lift: Lift,
    index: int,
    *,
    variant: Variant = "L",
    reading: Reading = "physical",
    mu: float | None = None,
    mg: float | None = None,
    base: GraspState | None = None,
) -> GraspState:
    r"""The grasp state (`grasp_state()`, space 3) of state ``index`` of the lift.

    Contacts: the touching finger geoms (F-geoms ``"F"``; L/S geoms of type ``variant``, with
    the slide directions of ``reading`` when ``"S"``) and, while they touch, the support
    geoms as D-points. REFS: the grasp's weight at magnitude ``mg`` (N; N m about the object's
    origin; ``[[0, 0, -mg, 0, 0, 0]]`` for the paper's sphere) plus the grasp's extra wrenches,
    or the grasp's own ``refs`` when ``mg`` is ``None``; RVDS: the grasp's (eq. 37 for Case 2);
    friction ``mu`` for every F and S contact, or the grasp's ``mu`` (and its ``mu_range``
    intervals) when ``None``; the grasp's ``friction_margin`` (0 for a scenario without one). ``base``,
    a state of the same index, skips MuJoCo: its contacts are retyped (cheap, for sweeps).

    Raises
    ------
    StateError
        Bad options or index.
    ModelError
        A geom other than the lift's contacts touching the object.
    """
    i, sc = _index(lift, index), lift.scenario
    if variant not in VARIANTS:
        raise StateError("variant", f"expected one of {', '.join(VARIANTS)}, got {variant!r}")
    if reading not in READINGS:
        raise StateError("reading", f"expected one of {', '.join(READINGS)}, got {reading!r}")
    for name, value in (("mu", mu), ("mg", mg)):
        if value is not None and not (
            isinstance(value, (int, float)) and math.isfinite(value) and value >= 0
        ):
            raise StateError(name, f"expected a finite number >= 0, got {value!r}")
    roles = dict(zip(lift.geoms, lift.roles, strict=True))
    slides = slide_directions(lift, i, reading=reading) if variant == "S" else {}
    # the grasp's own contact tolerance, as Grasp.state (solve) detects contacts: a finger the
    # file accepts at a gap below it is a contact here too
    tol = start_tolerance(sc)
    if base is None:
        data = mujoco.MjData(sc.model)
        data.qpos[:] = lift.qpos[i]
        # geoms within MuJoCo's margin but not touching need a type too; they are dropped below
        near = {
            c.geom: "D" for c in detected_contacts(sc.model, data, object_body=sc.object_body, tolerance=tol)
        }
        types = near | {g: "D" for g in (*lift.base, *sc.ignored_geoms)} | {g: "L" for g in roles}
        base = grasp_state(
            sc.model,
            data,
            contact_types=types,
            mu=1.0,
            rvds=sc.rvds,
            refs=np.zeros((1, 6)),
            object_body=sc.object_body,
            joints=sc.joints,
            operation_ranges=getattr(sc, "operation_ranges", None),
            friction_edges=getattr(sc, "friction_edges", 16),
            contact_tolerance=tol,
            slip=getattr(sc, "slip", "per_contact"),
            # a grasp file's joint_losses = "ignore" leaves a transmission's damping out too
            joint_damping=getattr(sc, "document", {}).get("joint_losses", "fold") == "fold",
            # the grasp file's joint_limits (mjtvm.model.limits): false, or its tolerance and horizon
            joint_limits=limit_options(getattr(sc, "document", {}).get("joint_limits")),
        )
    friction = sc.mu if mu is None else float(mu)
    contacts = []
    preloads = getattr(sc, "preloads", {})  # the grasp file's contact preloads (N), as Grasp.state
    for c in base.contacts:
        geom = c.name.split("#")[0]
        if geom in sc.ignored_geoms:
            continue
        if geom not in roles and geom not in lift.base:
            if geom in lift.touching[i]:
                raise ModelError(f"geom {geom!r}", f"touches the object at state {i}: no contact of the lift")
            continue  # within the tolerance but not touching: no contact of the lift
        kind = "D" if geom not in roles else "F" if roles[geom] == "F" else variant
        coefficient = friction.get(geom) if isinstance(friction, Mapping) else friction
        if kind in ("F", "S") and coefficient is None:
            raise ModelError(f"geom {geom!r}", f"its {kind} contact needs a friction coefficient in mu")
        contacts.append(
            replace(
                c,
                type=kind,
                mu=None if kind == "D" else float(coefficient),  # type: ignore[arg-type]
                slide_direction=slides[geom] if kind == "S" else None,
                preload=float(preloads.get(geom, 0.0)) if kind != "D" else 0.0,
            )
        )
    if mg is None:
        refs = np.array(sc.refs, dtype=float)
    elif hasattr(sc, "weight_refs"):  # a grasp: its weight (along gravity, through its centre of mass) at mg
        refs = np.array(sc.weight_refs(float(mg)), dtype=float)
    else:
        refs = np.array([[0.0, 0.0, -float(mg), 0.0, 0.0, 0.0]])
    margin = float(getattr(sc, "friction_margin", 0.0))
    if mu is None and getattr(sc, "mu_ranges", None):
        return base.with_(contacts=with_mu_ranges(contacts, sc.mu_ranges), refs=refs, friction_margin=margin)
    return base.with_(contacts=tuple(contacts), refs=refs, friction_margin=margin)
