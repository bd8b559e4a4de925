r"""The scripted lift of Case 2 (paper section 5, Fig. 7-8): grasp states along a +z translation.

The object (its free joint) translates along :math:`e_z` from the scenario's initial state
(world frame, m, rad). F-points (fingers 1 and 3) stay fixed on the object: their finger
contact points translate with it. Every finger moves by the paper's minimum-norm joint motion
:math:`\dot q = J_c^+ G_c^T \dot r`, :math:`\dot r = e_z`, where :math:`J_c, G_c` hold the
constraint rows: the three rows of an F-point (eq. 7), the normal row :math:`n^T` of an L- or
S-point (eq. 8; fingers 2 and 4). :math:`J_c` is block diagonal, so per finger
:math:`\dot q_i = J_i^+ e_z` (F; this also resolves the fourth joint) or
:math:`\dot q_i = J_{n,i}^T (n^T e_z) / |J_{n,i}|^2`, :math:`J_{n,i} = n^T J_i` (L/S), with
:math:`G^T e_z = e_z` for a translation. The motion is integrated (explicit Euler, steps of at
most ``max_step``); after every step one IK correction (:func:`~mjtvm.sim.ik.solve_ik`, within the
variant's bounds) puts each F fingertip back on its translated point and each L/S fingertip
back on the sphere (radial projection). *Drift*: the IK residual before the correction that
produced a state; *residual*: after it. Finger contacts must be fingertip spheres.

The lift ends at the *reach limit*, the largest z where the correction converges within
``tolerance`` for every finger and the pose is admissible (no other geom touches the object,
no link below the palm): marching with ``max_step``, then bisecting the failing step to
``limit_tolerance``. The N states are evenly spaced in z on the marched path (the marched
state below each, plus one partial step).

Slide directions :math:`\hat p_{C_s}` of the S-points, from the same motion:

* ``"physical"`` (default): :math:`T^T T (G^T e_z - J \dot q)`, the object's contact-point
  velocity relative to the finger's, i.e. the slip the motion produces (eq. 13 with
  :math:`\rho > 0`): kinetic friction (eq. 16-17) resists the lift;
* ``"literal"``: the paper's printed :math:`A_s [(J_c^+ G_c^T)^T\ I]^T e_z =
  T^T T (J \dot q - G^T e_z)`, the reverse: friction helps the lift.

A state's contacts are the geoms touching the object (MuJoCo distance <= :data:`TOUCH_TOL`):
the base D-point (the palm) exists only while the object rests on it.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, replace
from typing import Any, Literal

import mujoco
import numpy as np
from numpy.typing import NDArray

from ..core.state import GraspState
from ..errors import ModelError, StateError
from .grasp import detected_contacts, grasp_state
from .ik import IkTarget, geom_contact_target, ik_residual, solve_ik
from .scenario import Scenario, load_scenario

__all__ = ["READINGS", "TOUCH_TOL", "VARIANTS", "Lift", "lift_state", "scripted_lift", "slide_directions"]

Reading = Literal["physical", "literal"]
Variant = Literal["L", "S"]
READINGS: tuple[Reading, ...] = ("physical", "literal")
VARIANTS: tuple[Variant, ...] = ("L", "S")
TOUCH_TOL = 1e-6  # m: a geom within this distance of the object touches it
_EZ = np.array([0.0, 0.0, 1.0])
_Path = list[tuple[float, mujoco.MjData, dict[str, Any]]]


@dataclass(frozen=True, eq=False)
class Lift:
    r"""A scripted lift: N states of the hand and the object (world frame, m, rad).

    Attributes
    ----------
    scenario
        The scenario at its initial state (model, joints, RVDS, document).
    z, qpos
        ``(N,)`` object centre height per state, evenly spaced; ``(N, nq)`` MuJoCo configuration.
    joints
        The M state joints (the scenario's), the column order of ``rates``.
    geoms, roles
        The G finger contact geoms and their roles, ``"F"`` (fixed on the object) or ``"N"``
        (normal row only: an L- or S-point).
    points
        ``(N, G, 3)`` contact point of each geom (on the tip, toward the object centre).
    rates
        ``(N, M)`` minimum-norm joint motion per unit lift :math:`J_c^+ G_c^T e_z` (rad/m).
    slips
        ``(N, G, 3)`` physical slip :math:`T^T T (G^T e_z - J \dot q)` of each N-geom per unit
        lift (m/m, not normalised; zero rows for F-geoms).
    drift, residual
        ``(N, G)`` IK target residual before and after the correction that produced the state
        (m); the drift is 0 at the initial state.
    base, base_contact
        The base geoms (world body, e.g. ``"palm"``) and ``(N,)`` whether one touches the
        object (the D-point exists).
    touching
        Per state, every geom touching the object.
    limit
        Why the lift ends there (the first failing finger and its residual, or the height).
    max_step, tolerance, marched
        Integration step (m), IK tolerance (m), and the number of steps marched.
    """

    scenario: Scenario
    z: NDArray[np.float64]
    qpos: NDArray[np.float64]
    joints: tuple[str, ...]
    geoms: tuple[str, ...]
    roles: tuple[str, ...]
    points: NDArray[np.float64]
    rates: NDArray[np.float64]
    slips: NDArray[np.float64]
    drift: NDArray[np.float64]
    residual: NDArray[np.float64]
    base: tuple[str, ...]
    base_contact: NDArray[np.bool_]
    touching: tuple[tuple[str, ...], ...]
    limit: str
    max_step: float
    tolerance: float
    marched: int

    @property
    def num_states(self) -> int:
        """N."""
        return int(self.z.shape[0])


@dataclass(frozen=True, eq=False)
class _Finger:
    geom: str
    role: str  # "F" or "N"
    geom_id: int
    body: int
    shift: float  # tip centre to contact point along n (m)
    offset: float | None
    dofs: NDArray[np.int64]  # the finger's columns in the model's nv
    cols: NDArray[np.int64]  # the same in the lift's joints
    rel: NDArray[np.float64]  # contact point minus object centre at the start (m)


class _Marcher:
    """The predictor-corrector of one lift (module docstring)."""

    def __init__(self, sc: Scenario, *, tolerance: float, max_iterations: int) -> None:
        self.sc, self.model, self.tol, self.max_it = sc, sc.model, tolerance, max_iterations
        model = sc.model
        self.bounds = {k: (float(a), float(b)) for k, (a, b) in sc.ik_bounds.items()}
        ob = model.body(sc.object_body).id
        free = [j for j in range(model.njnt) if int(model.jnt_bodyid[j]) == ob]
        if len(free) != 1 or int(model.jnt_type[free[0]]) != int(mujoco.mjtJoint.mjJNT_FREE):
            raise ModelError(f"body {sc.object_body!r}", "the lift needs the object on one free joint")
        og = int(model.body_geomadr[ob])
        self.zadr, self.radius = int(model.jnt_qposadr[free[0]]) + 2, float(model.geom_size[og, 0])
        start = {c.geom: c for c in detected_contacts(model, sc.data, object_body=sc.object_body)}
        self.centre_xy = np.array(sc.data.xpos[ob][:2], dtype=float)
        fingers, base = [], []
        for name, kind in sc.contact_types.items():
            g = model.geom(name).id
            body = int(model.geom_bodyid[g])
            if body == 0:
                base.append(name)
                continue
            shape = "tip" if int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_SPHERE) else "link"
            if shape != "tip" or kind not in ("F", "L", "S"):
                raise ModelError(
                    f"geom {name!r}", f"the lift moves F, L or S fingertips, not a {kind} {shape}"
                )
            if name not in start:
                raise ModelError(f"geom {name!r}", "does not touch the object in the initial state")
            chain, b = set[int](), body
            while b > 0:
                chain, b = chain | {b}, int(model.body_parentid[b])
            joints = [j for j in sc.joints if int(model.joint(j).bodyid[0]) in chain]
            off = None
            fingers.append(_Finger(
                name, "F" if kind == "F" else "N", g, body,
                float(model.geom_size[g, 0]) if off is None else float(off), off,
                np.array([int(model.joint(j).dofadr[0]) for j in joints], dtype=int),
                np.array([sc.joints.index(j) for j in joints], dtype=int),
                start[name].position - np.array(sc.data.xpos[ob]),
            ))  # fmt: skip
        self.fingers, self.base = tuple(fingers), tuple(base)
        self.joint_names = tuple(sc.joints[k] for f in fingers for k in f.cols)
        self.qadr = np.array([int(model.joint(j).qposadr[0]) for j in self.joint_names], dtype=int)
        self.qcols = np.concatenate([f.cols for f in fingers])
        self.contact_geoms = {f.geom for f in fingers} | set(base) | set(sc.ignored_geoms)

    def centre(self, z: float) -> NDArray[np.float64]:
        return np.array([*self.centre_xy, z])

    def kinematics(self, data: mujoco.MjData, z: float) -> tuple[NDArray[np.float64], ...]:
        """Contact points (G, 3), rates (M,) and physical slips (G, 3) at ``data``."""
        model, c, g = self.model, self.centre(z), len(self.fingers)
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        points, slips = np.zeros((g, 3)), np.zeros((g, 3))
        rates, jacp = np.zeros(len(self.sc.joints)), np.zeros((3, model.nv))
        for k, f in enumerate(self.fingers):
            tip = np.array(data.geom_xpos[f.geom_id])
            n = (c - tip) / np.linalg.norm(c - tip)
            points[k] = tip + f.shift * n
            mujoco.mj_jac(model, data, jacp, None, points[k], f.body)
            jac = jacp[:, f.dofs]
            if f.role == "F":  # J^+ G^T e_z: all three rows (eq. 7)
                qd = np.linalg.pinv(jac) @ _EZ
            else:  # J_n^+ n^T G^T e_z: the normal row only (eq. 8)
                jn = n @ jac
                if float(jn @ jn) < 1e-12:
                    raise ModelError(f"geom {f.geom!r}", f"singular normal row at z = {z:.6g} m")
                qd = jn * float(n @ _EZ) / float(jn @ jn)
                rel = _EZ - jac @ qd  # the object's contact-point velocity relative to the finger's
                slips[k] = rel - (rel @ n) * n
            rates[f.cols] = qd
        return points, rates, slips

    def targets(self, data: mujoco.MjData, z: float) -> list[IkTarget]:
        """The IK targets at height ``z`` (``data``: the predicted pose, kinematics done)."""
        c, out = self.centre(z), []
        for f in self.fingers:
            tip = np.array(data.geom_xpos[f.geom_id])
            p = c + f.rel if f.role == "F" else c + self.radius * (tip - c) / np.linalg.norm(tip - c)
            out.append(geom_contact_target(self.model, f.geom, p, c, offset=f.offset))
        return out

    def drift(self, data: mujoco.MjData, targets: list[IkTarget]) -> NDArray[np.float64]:
        return np.array([np.linalg.norm(ik_residual(self.model, data, [t], [])[0]) for t in targets])

    def step(self, data: mujoco.MjData, z: float, dz: float) -> tuple[mujoco.MjData, dict[str, Any]]:
        """One predictor-corrector step from ``z`` to ``z + dz``; ``info["ok"]`` False when it fails."""
        rates = self.kinematics(data, z)[1]
        work = copy.copy(data)
        work.qpos[self.qadr] += dz * rates[self.qcols]
        work.qpos[self.zadr] = z + dz
        mujoco.mj_kinematics(self.model, work)
        targets = self.targets(work, z + dz)
        drift = self.drift(work, targets)
        res = solve_ik(self.model, work, targets, joints=self.joint_names, bounds=self.bounds,
                       tolerance=self.tol, max_iterations=self.max_it, strict=False)  # fmt: skip
        work.qpos[:] = res.qpos
        info: dict[str, Any] = {"drift": drift, "residual": np.array(res.residuals), "ok": res.converged}
        if not res.converged:
            w = int(np.argmax(res.residuals))
            info["why"] = (f"IK of {targets[w].name!r} does not converge at z = {z + dz:.6f} m "
                           f"(residual {res.residuals[w]:.3g} m > {self.tol:.3g} m)")  # fmt: skip
        elif why := self.inadmissible(work):
            info["ok"], info["why"] = False, f"{why} at z = {z + dz:.6f} m"
        return work, info

    def touching(self, data: mujoco.MjData) -> list[tuple[str, float]]:
        mujoco.mj_forward(self.model, data)
        found = detected_contacts(self.model, data, object_body=self.sc.object_body, one_per_body=False)
        return [(c.geom, c.distance) for c in found if c.distance <= TOUCH_TOL]

    def inadmissible(self, data: mujoco.MjData) -> str | None:
        """Why the pose is not admissible (another geom touching the object, a link below the palm)."""
        model = self.model
        for geom, dist in self.touching(data):
            if geom not in self.contact_geoms:
                return f"geom {geom!r} touches the object (distance {dist:.3g} m)"
        for k in range(model.ngeom):
            if int(model.geom_type[k]) == int(mujoco.mjtGeom.mjGEOM_CAPSULE):
                axis = data.geom_xmat[k].reshape(3, 3)[:, 2] * model.geom_size[k, 1]
                if float(data.geom_xpos[k][2] - abs(axis[2])) < -TOUCH_TOL:
                    return f"link {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, k)!r} below the palm"
        return None


def scripted_lift(
    scenario: str | Scenario = "case2",
    *,
    variant: str = "default",
    num_states: int = 30,
    height: float | None = None,
    max_step: float = 1e-3,
    tolerance: float = 1e-10,
    limit_tolerance: float = 1e-5,
    max_iterations: int = 100,
) -> Lift:
    r"""Lift the scenario's object along +z (module docstring) and sample ``num_states`` states.

    Parameters
    ----------
    scenario, variant
        A shipped scenario name and hand variant (``"default"``, ``"humanlike"``), or a
        loaded :class:`~mjtvm.sim.scenario.Scenario` at its initial state.
    num_states
        N >= 2, evenly spaced in z from the initial height to the end of the lift.
    height
        Lift by this much (m) instead of up to the reach limit; must be within reach.
    max_step, tolerance, limit_tolerance, max_iterations
        Largest integration step in z, IK tolerance per target, bisection width of the
        reach limit (m); IK iteration budget per correction.

    Raises
    ------
    StateError
        Bad options.
    ModelError
        A scenario the lift cannot move, an initial state not admissible, or a ``height``
        beyond reach (naming the failing finger).
    """
    if isinstance(num_states, bool) or not isinstance(num_states, int) or num_states < 2:
        raise StateError("num_states", f"expected an integer >= 2, got {num_states!r}")
    for name, value in (("max_step", max_step), ("tolerance", tolerance), ("limit_tolerance", limit_tolerance),
                        ("height", 1.0 if height is None else height)):  # fmt: skip
        if not (math.isfinite(value) and value > 0):
            raise StateError(name, f"expected a positive length (m), got {value!r}")
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario, variant=variant)
    m = _Marcher(sc, tolerance=tolerance, max_iterations=max_iterations)
    z0, data = float(sc.data.qpos[m.zadr]), copy.copy(sc.data)
    if why := m.inadmissible(data):
        raise ModelError(f"scenario {sc.name!r}", f"initial state not admissible: {why}")
    res0 = m.drift(data, m.targets(data, z0))
    path: _Path = [(z0, data, {"drift": np.zeros(len(m.fingers)), "residual": res0})]
    goal, limit = (math.inf if height is None else z0 + height), f"requested height {height} m"
    while path[-1][0] < goal:
        z, d, _ = path[-1]
        dz = min(max_step, goal - z)
        nxt, info = m.step(d, z, dz)
        if info["ok"]:
            path.append((z + dz, nxt, info))
            continue
        if height is not None:
            raise ModelError(f"height {height:g} m", f"beyond reach: {info['why']}")
        limit, lo, hi, best = info["why"], 0.0, dz, None
        while hi - lo > limit_tolerance:  # bisect the failing step
            mid = 0.5 * (lo + hi)
            trial, tinfo = m.step(d, z, mid)
            if tinfo["ok"]:
                lo, best = mid, (z + mid, trial, tinfo)
            else:
                hi, limit = mid, tinfo["why"]
        path += [best] if best is not None else []
        limit = f"reach limit: {limit}"
        break
    if len(path) < 2:
        raise ModelError(f"scenario {sc.name!r}", f"the object cannot be lifted: {limit}")
    return _sample(m, path, num_states, limit=limit, max_step=max_step, tolerance=tolerance)


def _sample(m: _Marcher, path: _Path, n: int, **meta: Any) -> Lift:
    """``n`` states evenly spaced in z along the marched ``path`` (one partial step from below)."""
    zs = np.array([p[0] for p in path])
    grid, g, sc = np.linspace(zs[0], zs[-1], n), len(m.fingers), m.sc
    qpos = np.zeros((n, sc.model.nq))
    points, slips = np.zeros((n, g, 3)), np.zeros((n, g, 3))
    rates, drift, residual = np.zeros((n, len(sc.joints))), np.zeros((n, g)), np.zeros((n, g))
    touching = []
    for i, z in enumerate(grid):
        zk, data, info = path[min(int(np.searchsorted(zs, z, side="right")) - 1, len(path) - 1)]
        if z - zk <= 1e-12:
            grid[i] = z = zk
        elif not (step := m.step(data, zk, float(z - zk)))[1]["ok"]:
            raise ModelError("lift", f"a state between two reached states failed: {step[1]['why']}")
        else:
            data, info = step
        qpos[i] = data.qpos
        points[i], rates[i], slips[i] = m.kinematics(copy.copy(data), float(z))
        drift[i], residual[i] = info["drift"], info["residual"]
        touching.append(tuple(dict.fromkeys(geom for geom, _ in m.touching(copy.copy(data)))))
    base_contact = np.array([any(b in t for b in m.base) for t in touching])
    for a in (grid, qpos, points, rates, slips, drift, residual, base_contact):
        a.setflags(write=False)
    return Lift(
        scenario=sc, z=grid, qpos=qpos, joints=sc.joints, geoms=tuple(f.geom for f in m.fingers),
        roles=tuple(f.role for f in m.fingers), points=points, rates=rates,
        slips=slips, drift=drift, residual=residual, base=m.base, base_contact=base_contact,
        touching=tuple(touching), marched=len(path) - 1, **meta,
    )  # fmt: skip


def _index(lift: Lift, index: int) -> int:
    n = lift.num_states
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < n:
        raise StateError("index", f"expected a state index in [0, {n}), got {index!r}")
    return int(index)


def slide_directions(lift: Lift, index: int, *, reading: Reading = "physical") -> dict[str, NDArray]:
    r"""Unit slide direction :math:`\hat p_{C_s}` of each L/S geom at state ``index`` (module doc).

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
    mu: float = 0.3,
    mg: float = 1.0,
    base: GraspState | None = None,
) -> GraspState:
    r"""The grasp state (:func:`~mjtvm.sim.grasp.grasp_state`, space 3) of state ``index`` of the lift.

    Contacts: the touching finger geoms (F-geoms ``"F"``; L/S geoms of type ``variant``, with
    the slide directions of ``reading`` when ``"S"``) and, while it touches, the base as a
    D-point. REFS ``[[0, 0, -mg, 0, 0, 0]]`` (N; N m about the centre); RVDS: the scenario's
    (eq. 37); ``mu`` for every F and S contact. ``base``, a state of the same index, skips
    MuJoCo: its contacts are retyped (cheap, for sweeps).

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
    for name, value in (("mu", mu), ("mg", mg)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
            raise StateError(name, f"expected a finite number >= 0, got {value!r}")
    roles = dict(zip(lift.geoms, lift.roles, strict=True))
    slides = slide_directions(lift, i, reading=reading)
    if base is None:
        data = mujoco.MjData(sc.model)
        data.qpos[:] = lift.qpos[i]
        types = {g: "D" for g in (*lift.base, *sc.ignored_geoms)} | {g: "L" for g in roles}
        base = grasp_state(sc.model, data, contact_types=types, mu=1.0, rvds=sc.rvds, refs=np.zeros((1, 6)),
                           object_body=sc.object_body, joints=sc.joints)  # fmt: skip
    contacts = []
    for c in base.contacts:
        geom = c.name.split("#")[0]
        if geom not in lift.touching[i] or geom in sc.ignored_geoms:
            continue
        if geom not in roles and geom not in lift.base:
            raise ModelError(f"geom {geom!r}", f"touches the object at state {i}: no contact of the lift")
        kind = "D" if geom not in roles else "F" if roles[geom] == "F" else variant
        contacts.append(replace(c, type=kind, mu=None if kind == "D" else float(mu),  # type: ignore[arg-type]
                                slide_direction=slides[geom] if kind == "S" else None))  # fmt: skip
    return base.with_(contacts=tuple(contacts), refs=np.array([[0.0, 0.0, -float(mg), 0.0, 0.0, 0.0]]))
