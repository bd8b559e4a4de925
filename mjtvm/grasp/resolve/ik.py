r"""Inverse kinematics: finger points at target positions on a sphere (damped least squares).

An [`IkTarget`][mjtvm.grasp.resolve.ik.IkTarget] asks that a point fixed to a finger body reach a world position and,
optionally, that a link axis through it be tangent to a sphere there, so that the link's
surface touches the sphere at that point instead of cutting into it.
[`geom_contact_target()`][mjtvm.grasp.resolve.ik.geom_contact_target] builds the target that makes a fingertip sphere or a link
capsule touch the object at a given contact point. `solve_ik()` moves the chosen joints
(Levenberg-Marquardt: damped least squares on ``mj_jac``) within their joint ranges.

Frames and units: world frame unless "body frame" is said; m and rad.

Why not ``mink`` (measured against mink 1.3.0 with daqp): on the lift's IK corrections, same
targets, start and tolerance 1e-10 m, this module's damped least squares converged in every
case, mink did not: Case 2 (43 corrections sampled along the lift): LM median 2 iterations
(max 50, at the reach limit), 1.4-2.1 ms, residual <= 5.4e-11 m in 43/43; mink median 2
(max 100), 4.3 ms, 42/43 (4.0e-6 m left at the reach limit). Programmatic box grasp (51
corrections): LM median 2 (max 3), 0.7-0.9 ms, 51/51; mink median 4 (max 8), 1.5-1.9 ms,
51/51. mink places frames (bodies, geoms, sites), not arbitrary body points, so the lift's
witness-point targets need a retargeted body frame; per-call joint bounds need a model copy
with narrowed ranges (its ``ConfigurationLimit`` is a velocity bound with a gain, and the
object's free joint needs a ``DofFreezingTask``). It would add mink, qpsolvers and daqp (about
5 MB). Kept: this module.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.transmission import equality_residual
from mjtvm.grasp.resolve.state import model_id

__all__ = ["IkResult", "IkTarget", "body_label", "geom_contact_target", "ik_residual", "solve_ik"]

_OBJ = mujoco.mjtObj


def _vec3(value: ArrayLike, what: str) -> NDArray[np.float64]:
    v = np.array(value, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ModelError(what, f"expected 3 finite numbers, got {value!r}")
    v.setflags(write=False)
    return v


@dataclass(frozen=True, eq=False)
class IkTarget:
    r"""One finger point to place.

    Parameters
    ----------
    name
        Label used in results and error messages (e.g. the geom's name).
    body
        The finger body carrying the point.
    point
        ``(3,)`` the point in the body frame (m).
    position
        ``(3,)`` its target in the world frame (m): residual ``x - position`` with
        ``x = x_b + R_b point``.
    tangent_axis
        ``(3,)`` optional unit direction in the body frame (a link axis through ``point``).
        With ``centre``, adds the residual $a \cdot (c - x)$ (m), $a = R_b$
        ``tangent_axis``: zero when ``x`` is the point of the axis nearest the sphere
        centre $c$, i.e. the axis is tangent to the sphere's concentric sphere
        through ``x`` and a capsule around it touches the object at one point.
    centre
        ``(3,)`` the sphere centre (m); required with ``tangent_axis``.
    """

    name: str
    body: str
    point: NDArray[np.float64]
    position: NDArray[np.float64]
    tangent_axis: NDArray[np.float64] | None = None
    centre: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "point", _vec3(self.point, f"target {self.name!r} point"))
        object.__setattr__(self, "position", _vec3(self.position, f"target {self.name!r} position"))
        if (self.tangent_axis is None) != (self.centre is None):
            raise ModelError(f"target {self.name!r}", "tangent_axis and centre go together")
        if self.tangent_axis is not None and self.centre is not None:
            axis = _vec3(self.tangent_axis, f"target {self.name!r} tangent_axis")
            if abs(np.linalg.norm(axis) - 1.0) > 1e-9:
                raise ModelError(f"target {self.name!r}", "tangent_axis must be a unit vector")
            object.__setattr__(self, "tangent_axis", axis)
            object.__setattr__(self, "centre", _vec3(self.centre, f"target {self.name!r} centre"))

    @property
    def rows(self) -> int:
        """Residual rows: 3 (position), 4 with the tangency row."""
        return 3 if self.tangent_axis is None else 4


@dataclass(frozen=True, eq=False)
class IkResult:
    r"""Outcome of `solve_ik()`.

    Attributes
    ----------
    qpos
        ``(nq,)`` the full configuration (joints not solved for keep their start values).
    joints
        Names of the joints moved (model order, or as given).
    residuals
        ``(T,)`` per target, the norm of its residual rows (m).
    iterations
        Iterations run.
    converged
        Every residual at or below the tolerance.
    """

    qpos: NDArray[np.float64]
    joints: tuple[str, ...]
    residuals: NDArray[np.float64]
    iterations: int
    converged: bool


def geom_contact_target(
    model: mujoco.MjModel,
    geom: str,
    contact: ArrayLike,
    centre: ArrayLike,
    *,
    along: float | None = None,
    offset: float | None = None,
    tangent: bool = True,
) -> IkTarget:
    r"""The target that puts the surface of finger geom ``geom`` on ``contact``.

    ``n = (centre - contact) / |centre - contact|`` is the normal into the object.

    * Sphere geom (a fingertip): its centre goes to ``contact - offset n``, i.e. the tip
      centre offset by ``offset`` toward the object reaches the contact.
    * Capsule geom (a link): the point of its axis at distance ``along`` from the axis
      end nearest the body origin (the link's joint end) goes to ``contact - offset n``;
      with ``tangent`` the axis is kept perpendicular to ``n`` there (see
      [`IkTarget`][mjtvm.grasp.resolve.ik.IkTarget]), so the capsule touches the sphere at ``contact`` only.

    Parameters
    ----------
    model
        Compiled model.
    geom
        Name of a sphere or capsule geom on a finger body.
    contact, centre
        ``(3,)`` the contact point and the object sphere's centre (m), world frame.
    along
        Capsules only: distance along the axis (m), within ``[0, length]``.
    offset
        How far the surface point lies from the placed point along ``n`` (m); default
        the geom's radius (surfaces touching). ``0`` places the axis (or tip centre) on
        the contact: the thin-link idealisation, penetrating by the radius.
    tangent
        Capsules only: add the tangency row.

    Raises
    ------
    ModelError
        Unknown geom, a geom of another type, a missing or out-of-range ``along``, or
        ``contact`` at the centre.
    """
    g = model_id(model, _OBJ.mjOBJ_GEOM, geom, "geom")
    gtype = int(model.geom_type[g])
    body = mujoco.mj_id2name(model, _OBJ.mjOBJ_BODY, int(model.geom_bodyid[g]))
    p, c = _vec3(contact, f"geom {geom!r} contact"), _vec3(centre, "centre")
    dist = float(np.linalg.norm(c - p))
    if dist == 0.0:
        raise ModelError(f"geom {geom!r}", "contact point at the sphere centre: no normal")
    n = (c - p) / dist
    radius = float(model.geom_size[g, 0])
    shift = radius if offset is None else float(offset)
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, model.geom_quat[g])
    pos = np.array(model.geom_pos[g], dtype=float)
    if gtype == int(mujoco.mjtGeom.mjGEOM_SPHERE):
        return IkTarget(geom, body, pos, p - shift * n)
    if gtype != int(mujoco.mjtGeom.mjGEOM_CAPSULE):
        raise ModelError(f"geom {geom!r}", "expected a sphere (fingertip) or capsule (link) geom")
    half = float(model.geom_size[g, 1])
    if along is None or not 0.0 <= along <= 2 * half:
        raise ModelError(
            f"geom {geom!r}", f"a capsule target needs 0 <= along <= {2 * half:g} m, got {along}"
        )
    axis = rot.reshape(3, 3)[:, 2]
    if np.linalg.norm(pos + half * axis) < np.linalg.norm(pos - half * axis):
        axis = -axis  # point from the end nearest the body origin (the joint) to the other
    point = pos + (float(along) - half) * axis
    if not tangent:
        return IkTarget(geom, body, point, p - shift * n)
    return IkTarget(geom, body, point, p - shift * n, tangent_axis=axis, centre=c)


def body_label(model: mujoco.MjModel, body: int) -> str:
    """A body's name, or ``"body#<id>"`` when unnamed (as `geom_label()`)."""
    return str(mujoco.mj_id2name(model, _OBJ.mjOBJ_BODY, int(body)) or f"body#{int(body)}")


def _body_id(model: mujoco.MjModel, label: str) -> int:
    if label.startswith("body#") and label[5:].isdigit() and 0 < int(label[5:]) < model.nbody:
        if not mujoco.mj_id2name(model, _OBJ.mjOBJ_BODY, int(label[5:])):
            return int(label[5:])
    return model_id(model, _OBJ.mjOBJ_BODY, label, "body")


def _bodies(model: mujoco.MjModel, targets: Sequence[IkTarget]) -> list[int]:
    return [_body_id(model, t.body) for t in targets]


def ik_residual(
    model: mujoco.MjModel, data: mujoco.MjData, targets: Sequence[IkTarget], dofs: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Residual rows and their Jacobian at ``data.qpos`` (runs ``mj_kinematics`` and ``mj_comPos``).

    Position rows $e = x - x^*$ with Jacobian ``mj_jac``'s $J_p$; tangency row
    $e = a \cdot (c - x)$ with $\partial e / \partial q_k =
    (\omega_k \times a) \cdot (c - x) - a \cdot J_{p,k}$, $\omega_k$ the rotational
    Jacobian column (``mj_jac``'s $J_r$).

    Parameters
    ----------
    dofs
        ``(K,)`` the dof indices (columns) to differentiate with respect to.

    Returns
    -------
    e, J
        ``(R,)`` residual (m) and ``(R, K)`` Jacobian (m/rad), targets in order.
    """
    cols = np.asarray(dofs, dtype=int)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    rows_e, rows_j = [], []
    for t, b in zip(targets, _bodies(model, targets), strict=True):
        rot = data.xmat[b].reshape(3, 3)
        x = data.xpos[b] + rot @ t.point
        mujoco.mj_jac(model, data, jacp, jacr, x, b)
        rows_e.append(x - t.position)
        rows_j.append(jacp[:, cols].copy())
        if t.tangent_axis is not None and t.centre is not None:
            a, lever = rot @ t.tangent_axis, t.centre - x
            rows_e.append(np.array([a @ lever]))
            rows_j.append((np.cross(jacr[:, cols].T, a) @ lever - a @ jacp[:, cols])[None, :])
    return np.concatenate(rows_e), np.vstack(rows_j)


def _per_target(e: NDArray[np.float64], targets: Sequence[IkTarget]) -> NDArray[np.float64]:
    out, k = [], 0
    for t in targets:
        out.append(float(np.linalg.norm(e[k : k + t.rows])))
        k += t.rows
    return np.array(out)


def _chain_joints(model: mujoco.MjModel, bodies: list[int]) -> list[int]:
    chain: set[int] = set()
    for b in bodies:
        while b > 0:
            chain.add(b)
            b = int(model.body_parentid[b])
    return [j for j in range(model.njnt) if int(model.jnt_bodyid[j]) in chain]


def _ik_joints(model: mujoco.MjModel, targets: Sequence[IkTarget], joints: Sequence[str] | None) -> list[int]:
    """The hinge and slide joints `solve_ik()` moves (checked; default: the targets' chains)."""
    scalar = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    if joints is None:
        ids = [j for j in _chain_joints(model, _bodies(model, targets)) if int(model.jnt_type[j]) in scalar]
    else:
        ids = [model_id(model, _OBJ.mjOBJ_JOINT, name, "joint") for name in joints]
        for j, name in zip(ids, joints, strict=True):
            if int(model.jnt_type[j]) not in scalar:
                raise ModelError(f"joint {name!r}", "is not a hinge or slide joint")
    _bodies(model, targets)
    return ids


def _joint_bounds(
    model: mujoco.MjModel,
    ids: Sequence[int],
    names: Sequence[str],
    bounds: Mapping[str, tuple[float, float]] | None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The joints' ranges (infinite where unlimited) intersected with ``bounds``."""
    lo = np.array([model.jnt_range[j, 0] if model.jnt_limited[j] else -np.inf for j in ids])
    hi = np.array([model.jnt_range[j, 1] if model.jnt_limited[j] else np.inf for j in ids])
    for name, (b_lo, b_hi) in (bounds or {}).items():
        if name not in names:
            model_id(model, _OBJ.mjOBJ_JOINT, name, "joint")
            raise ModelError(f"joint {name!r}", "has a bound but is not among the joints solved for")
        k = list(names).index(name)
        lo[k], hi[k] = max(lo[k], float(b_lo)), min(hi[k], float(b_hi))
        if not lo[k] <= hi[k]:
            raise ModelError(f"joint {name!r}", f"empty range [{lo[k]}, {hi[k]}] after its bound")
    return lo, hi


def _damped_step(
    jac: NDArray[np.float64],
    e: NDArray[np.float64],
    q: NDArray[np.float64],
    box: tuple[NDArray[np.float64], NDArray[np.float64]],
    mu: float,
) -> NDArray[np.float64]:
    r"""One Levenberg-Marquardt step $(J^T J + \mu I)\,\delta q = -J^T e$, joints at a
    bound of ``box = (lo, hi)`` it would push beyond frozen (projected gradient), capped at
    0.5 rad per joint."""
    lo, hi = box
    free = np.ones(len(q), dtype=bool)
    for _ in range(len(q) + 1):
        jf = jac[:, free]
        step = np.zeros(len(q))
        step[free] = np.linalg.solve(jf.T @ jf + mu * np.eye(int(free.sum())), -jf.T @ e)
        blocked = free & (((q <= lo) & (step < 0)) | ((q >= hi) & (step > 0)))
        if not blocked.any():
            break
        free &= ~blocked
    return step * min(1.0, 0.5 / max(float(np.abs(step).max()), 1e-300))


def solve_ik(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    targets: Sequence[IkTarget],
    *,
    joints: Sequence[str] | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    tolerance: float = 1e-10,
    max_iterations: int = 500,
    strict: bool = True,
    scratch: mujoco.MjData | None = None,
) -> IkResult:
    r"""Place every target: minimise $\tfrac12 |e(q)|^2$ over the chosen joints.

    Long only through its signature and parameter documentation (one keyword per option);
    the body is a short sequence of the named steps below it in this module.

    Levenberg-Marquardt: $(J^T J + \mu I)\,\delta q = -J^T e$ on the free joints,
    $\mu$ divided by 3 after a step that lowers $|e|$ and multiplied by 10
    otherwise; steps are capped at 0.5 rad per joint and clipped to the joint ranges; a
    joint at a bound that the step would push beyond it is frozen for that step (projected
    gradient). Over-determined but consistent targets (e.g. a link lying on the palm *and*
    tangent to the sphere) converge like square ones; with redundant joints the result is
    the one the damped steps reach from the start configuration ``data.qpos``.

    Parameters
    ----------
    model, data
        The model and the start configuration (``data`` is not modified).
    targets
        What to place.
    joints
        Hinge or slide joints to move; default every joint of the bodies carrying the
        targets and of their ancestors (not free or ball joints).
    bounds
        Joint name -> (low, high) rad, intersected with the joint's range.
    tolerance
        Largest accepted residual per target (m).
    max_iterations
        Iteration budget.
    strict
        Raise when not converged (default); otherwise return with ``converged=False``.
    scratch
        An ``mjData`` of ``model`` to work in (overwritten with ``data`` first) instead of a
        new copy: allocating one costs 0.3 ms, copying into one 5 us (the lift's corrections).

    Raises
    ------
    ModelError
        Unknown body or joint, a joint that is not a hinge or slide, an empty or inverted
        bound, or (``strict``) a target whose residual stays above ``tolerance``: the error
        names the worst target and its residual.
    """
    if not targets:
        raise ModelError("targets", "expected at least one IK target")
    ids = _ik_joints(model, targets, joints)
    names = tuple(mujoco.mj_id2name(model, _OBJ.mjOBJ_JOINT, j) for j in ids)
    adr = np.array([int(model.jnt_qposadr[j]) for j in ids], dtype=int)
    dofs = np.array([int(model.jnt_dofadr[j]) for j in ids], dtype=int)
    lo, hi = _joint_bounds(model, ids, names, bounds)

    if scratch is None:
        work = copy.copy(data)
    else:
        work = scratch
        mujoco.mj_copyData(work, model, data)
    q = np.clip(np.array(work.qpos[adr], dtype=float), lo, hi)

    # Active equalities on the moved joints (a linkage) are kept closed: their residuals are
    # further rows of the least squares, held to the same tolerance as the targets.
    closed = bool(model.neq) and len(equality_residual(model, work, dofs)[0]) > 0

    def evaluate(qv: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        work.qpos[adr] = qv
        e, jac = ik_residual(model, work, targets, dofs)
        if not closed:
            return e, jac
        r, jr = equality_residual(model, work, dofs)
        return np.concatenate([e, r]), np.vstack([jac, jr])

    def worst(e: NDArray[np.float64]) -> float:
        rows = sum(t.rows for t in targets)
        return max(float(np.max(_per_target(e, targets))), float(np.max(np.abs(e[rows:]), initial=0.0)))

    e, jac = evaluate(q)
    mu, it = 1e-6, 0
    while it < max_iterations and worst(e) > tolerance:
        it += 1
        trial = np.clip(q + _damped_step(jac, e, q, (lo, hi), mu), lo, hi)
        e_trial, jac_trial = evaluate(trial)
        if e_trial @ e_trial < e @ e:
            q, e, jac, mu = trial, e_trial, jac_trial, max(mu / 3.0, 1e-15)
        else:
            mu *= 10.0
            if mu > 1e8:  # no descent left: a local minimum above the tolerance
                break
    work.qpos[adr] = q
    residuals = _per_target(e, targets)
    converged = worst(e) <= tolerance
    if strict and not converged:
        if np.max(residuals) <= tolerance:
            raise ModelError(
                "equality constraints",
                f"not closed: residual {worst(e):.3g} above the tolerance {tolerance:.3g} "
                f"after {it} iterations",
            )
        w = int(np.argmax(residuals))
        raise ModelError(
            f"IK target {targets[w].name!r}",
            f"unreachable: residual {residuals[w]:.3g} m above the tolerance {tolerance:.3g} m "
            f"after {it} iterations",
        )
    qpos = np.array(work.qpos, dtype=float)
    qpos.setflags(write=False)
    residuals.setflags(write=False)
    return IkResult(qpos=qpos, joints=names, residuals=residuals, iterations=it, converged=converged)
