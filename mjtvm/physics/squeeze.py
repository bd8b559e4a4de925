r"""The squeeze: the hold test's drive, a grasp's witness at rest pressing harder from inside.

DexGraspBench holds a grasp by position-servoing the hand to a ``squeeze_qpos`` beyond the grasp
(BODex makes it ``2 grasp_qpos - pregrasp_qpos``: the fingers closed on by as much again), so
its servo presses the fingers into the object with ``K (squeeze_qpos - q)`` and resists a push
with the stiffness K. The same two parts, in this project's physics (``docs/physics-check.md``,
"The hold test (DexGraspBench)"):

* **The squeeze torques** ([`squeeze_witness()`][mjtvm.physics.squeeze.squeeze_witness]): the
  constraints of Problem 2 at alpha = 0 (eq. 31 by `assemble()`: the statics of eq. 19-20 with
  the weight, the friction pyramids' generators ``lambda_e >= 0``, the operation ranges) with
  every joint at rest (``qd = 0``: the ranges' torques at zero speed) and a friction margin
  (every generator of a finger contact at least ``margin`` x its contact's mean generator: the
  force stays off the pyramid's faces), solved by two LPs: (1) the largest least normal force
  t over the finger contacts (F, L, S), (2) the largest sum of their normal forces with each
  still at least t. The margin is the first of `FRICTION_MARGINS` (0.25, 0.1, 0) the state
  allows. The drive ([`squeeze_drive()`][mjtvm.physics.squeeze.squeeze_drive]) applies the share
  `SQUEEZE_SHARE` (0.5) of it beyond the central witness at alpha = 0 (the least forces that
  balance the weight): ``tau = tau_w + 0.5 (tau_sq - tau_w)``, a convex combination of two
  solutions of the same constraints, so inside the pyramids and the operation ranges, with half
  of each motor's range beyond the weight's left to resist the push. ``tau_sq - tau_w`` are
  the joint torques ``J_c^T f_int`` of internal forces (``G f_int = 0``).
* **The position loop** ([`Servo`][mjtvm.physics.squeeze.Servo], `SERVO_GAIN`): each
  ``<dcmotor>``'s speed setpoint is ``kp (l_0 - l)`` (``l`` its actuator length, ``l_0`` at the
  held configuration), so the motor's torque is ``tau + k_v kp (l_0 - l) - k_v l'``: a
  stiffness ``k_v gear^2 kp`` at the joint beside the motor's own damping ``k_v gear^2``,
  through the motor's voltage clamp and torque saturation (MuJoCo's ``<dcmotor>``).
  ``kp = 10 1/s`` (a 100 ms time constant, 400 steps of the rollouts' 0.25 ms) gives the
  Shadow's finger motors (``k_v gear^2 = 0.5 N m s``) the stiffness of the benchmark's
  servos, ``kp = 5 N m/rad``. Measured on the shipped Shadow example (the 29 grasps with a witness,
  2026-12-03): with the squeeze, kp = 10, 30, 100 hold 14, 15, 8; kp = 0 (a damper) 1; the
  loop at kp = 10 without the squeeze (share 0) 0; share 1 at kp = 10 8.
* **Torsional friction** (`TORSIONAL_FRICTION`, [`with_torsion()`][mjtvm.physics.squeeze.with_torsion]):
  the benchmark's contacts have ``condim = 4`` with torsional friction 0.02 m; the hold test's
  frictional point contacts get the same (the rollouts' keep ``condim`` 3), else a sphere
  pinched at points spins about the fingers' axis unresisted.

Together the squeeze and the loop are the benchmark's servo decomposed at the held
configuration q0, ``K (q_sq - q) = K (q_sq - q0) + K (q0 - q)``, with the squeeze pose
``q_sq = q0 + K^-1 (tau - tau_w)`` set by the friction pyramids and the motors' ranges rather
than by a joint offset.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from typing import Any

import mujoco
import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.optimize import linprog

from mjtvm.errors import ParamError, SolverError
from mjtvm.model.state import GraspState
from mjtvm.physics.witness import Drive, WitnessProblem, witness_drive
from mjtvm.problem2.assembly import Assembly, assemble

__all__ = [
    "FRICTION_MARGINS",
    "SERVO_GAIN",
    "SQUEEZE_SHARE",
    "TORSIONAL_FRICTION",
    "Servo",
    "squeeze_at_rest",
    "squeeze_drive",
    "squeeze_witness",
    "with_position_loop",
    "with_torsion",
]

_F64 = NDArray[np.float64]

SQUEEZE_SHARE = 0.5
"""The share of the squeeze beyond the weight's torques that the drive applies (module docstring)."""
FRICTION_MARGINS = (0.25, 0.1, 0.0)
"""Each pyramid generator carries at least this share of its contact's mean generator: the first
that the state allows (module docstring)."""
TORSIONAL_FRICTION = 0.02
"""m: the torsional friction of the frictional point contacts in the hold test (DexGraspBench's
``miu_coef: [0.6, 0.02]`` with ``condim = 4``, ``src/util/hand_util.py`` ``_set_friction``)."""
SERVO_GAIN = 10.0
"""1/s: the position loop's speed gain kp (speed setpoint ``kp (l_0 - l)``, module docstring)."""


def squeeze_witness(
    state: GraspState,
    k: int = 0,
    *,
    margin: float = FRICTION_MARGINS[0],
    assembly: Assembly | None = None,
    motion: tuple[_F64, _F64, _F64] | None = None,
) -> dict[str, Any]:
    r"""The squeeze at rest of REFS ``k`` (module docstring): two LPs over eq. (31) at alpha = 0.

    Returns ``torques`` (``(A,)`` actuator forces, or ``(M,)`` joint torques), ``forces``
    (``(L, d)`` on the object), ``least`` (N: the first LP's least normal force over the
    finger contacts) and ``total`` (N: the second's sum of their normal forces). ``assembly``:
    ``assemble(state, horizon=True)`` when the caller has it already.

    ``motion``: the squeeze at a given motion instead of at rest, ``(qd, rho, offset)``: the
    ``(M,)`` joint speeds and slip speeds fixed to a witness's, and ``(m,)`` the alpha
    column times alpha (the twist's and the horizon rows' coefficients,
    [`central_witness()`][mjtvm.physics.witness.central_witness]) moved to the row bounds. The
    rows on the motion alone (kinematics, joint limits, travel horizon) are the witness's,
    satisfied by it: they are left out, so the LPs choose forces and torques only, the torques
    within the operation ranges at the given speeds
    ([`squeezed_drive()`][mjtvm.physics.hold_drive.squeezed_drive]).

    Raises
    ------
    SolverError
        An LP has no solution (the weight cannot be held at rest) or is unbounded.
    """
    asm = assemble(state, horizon=True) if assembly is None else assembly
    n = asm.num_variables
    lo, hi = asm.statics_bounds(state.refs[k])
    cl, cu = asm.col_lower.copy(), asm.col_upper.copy()
    given = (np.zeros(state.num_joints), np.zeros(asm.blocks["rho"].stop - asm.blocks["rho"].start))
    if motion is not None:
        given = (np.asarray(motion[0], float), np.asarray(motion[1], float))
        lo, hi = lo - motion[2], hi - motion[2]
    for name, value in zip(("qd", "rho"), given, strict=True):  # at rest: the ranges' torques at 0 speed
        cl[asm.blocks[name]] = value
        cu[asm.blocks[name]] = value
    lam0 = asm.blocks["lam[0]"].start
    normal_rows, margin_rows = [], []
    for c, g, s in zip(state.contacts, asm.generators, asm.generator_slices, strict=True):
        if c.type == "D" or s.stop == s.start:
            continue
        row = np.zeros(n + 1)
        row[lam0 + s.start : lam0 + s.stop] = np.asarray(c.normal, float) @ g  # eq. (22): f = E lam
        normal_rows.append(row)
        ne = s.stop - s.start
        for e in range(ne if ne > 1 else 0):  # lam_e >= margin x the mean generator
            r = np.zeros(n + 1)
            r[lam0 + s.start : lam0 + s.stop] = margin / ne
            r[lam0 + s.start + e] -= 1.0
            margin_rows.append(r)
    if not normal_rows:
        raise SolverError("highs", f"REFS {k}: no finger contact to squeeze with")
    a = sp.hstack([asm.A.tocsr(), sp.csr_matrix((asm.A.shape[0], 1))], format="csr")
    if motion is not None:  # the rows on the fixed motion alone: the witness's (docstring)
        free = np.r_[cl != cu, True]
        on_free = np.asarray(abs(a[:, np.flatnonzero(free)]).sum(axis=1)).ravel() > 0
        lo, hi = np.where(on_free, lo, -np.inf), np.where(on_free, hi, np.inf)
    eq = np.isfinite(lo) & (lo == hi)
    up, dn = np.isfinite(hi) & ~eq, np.isfinite(lo) & ~eq
    nr = np.array(normal_rows)
    base_ub = sp.vstack(
        [a[up], -a[dn], sp.csr_matrix(np.array(margin_rows).reshape(-1, n + 1))], format="csr"
    )
    base_b = np.concatenate([hi[up], -lo[dn], np.zeros(len(margin_rows))])
    bounds = [
        (l if np.isfinite(l) else None, u if np.isfinite(u) else None)
        for l, u in zip(np.r_[cl, 0.0], np.r_[cu, np.inf], strict=True)
    ]
    # 1: the largest least normal force t (t <= every finger's normal force)
    t_rows = -nr.copy()
    t_rows[:, n] = 1.0
    c1 = np.zeros(n + 1)
    c1[n] = -1.0
    r1 = _lp(
        c1,
        sp.vstack([base_ub, sp.csr_matrix(t_rows)]),
        np.r_[base_b, np.zeros(len(nr))],
        a[eq],
        hi[eq],
        bounds,
        k,
    )
    least = float(r1[n])
    # 2: the largest sum of the normal forces, each finger still pressing with at least t
    bounds[n] = (0.0, 0.0)
    r2 = _lp(
        -nr.sum(axis=0),
        sp.vstack([base_ub, sp.csr_matrix(-nr)]),
        np.r_[base_b, -least * (1 - 1e-6) * np.ones(len(nr))],
        a[eq],
        hi[eq],
        bounds,
        k,
    )
    x = r2[:n]
    return {
        "torques": x[asm.blocks["tau[0]"]],
        "forces": asm.forces(x),
        "least": least,
        "total": float(nr[:, :n].sum(axis=0) @ x),
    }


def squeeze_at_rest(
    state: GraspState,
    k: int = 0,
    *,
    assembly: Assembly | None = None,
    motion: tuple[_F64, _F64, _F64] | None = None,
) -> dict[str, Any]:
    """[`squeeze_witness()`][mjtvm.physics.squeeze.squeeze_witness] at the first margin of
    `FRICTION_MARGINS` the state allows, with ``margin`` in the result (one ``assembly`` for
    every margin tried; ``motion`` as there: at a witness's motion rather than at rest).

    Raises
    ------
    SolverError
        Not even margin 0 is feasible.
    """
    asm = assemble(state, horizon=True) if assembly is None else assembly
    for m in FRICTION_MARGINS[:-1]:
        try:
            return {**squeeze_witness(state, k, margin=m, assembly=asm, motion=motion), "margin": m}
        except SolverError:
            continue
    last = FRICTION_MARGINS[-1]
    return {**squeeze_witness(state, k, margin=last, assembly=asm, motion=motion), "margin": last}


def _lp(c: _F64, a_ub: Any, b_ub: _F64, a_eq: Any, b_eq: _F64, bounds: list[Any], k: int) -> _F64:
    """HiGHS on ``min c x``; the solution, or a `SolverError` naming REFS ``k``."""
    res = linprog(c, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq, bounds=bounds, method="highs")
    if res.status != 0:
        raise SolverError("highs", f"REFS {k} at rest: {res.message}")
    return np.asarray(res.x, dtype=float)


def squeeze_drive(
    state: GraspState,
    result: Any,
    *,
    share: float = SQUEEZE_SHARE,
    assembly: Assembly | None = None,
    problem: WitnessProblem | None = None,
) -> Drive | None:
    """The hold test's drive of a grasp state: speeds 0, the central witness at alpha = 0 with
    ``share`` of the squeeze (module docstring) added to its torques; ``None`` when no pair of
    ``result`` (the state's [`TvmmpResult`][mjtvm.problem2.tvmmp.TvmmpResult]) has a witness.
    ``assembly``: ``assemble(state, horizon=True)``, shared by the witness and the squeeze's
    LPs (built here when not given). ``problem``: the state's
    [`WitnessProblem`][mjtvm.physics.witness.WitnessProblem] of REFS 0 when already built (the
    speed test's witnesses share it).

    Raises
    ------
    ParamError
        ``share`` outside [0, 1] (outside, the torques may leave the ranges).
    """
    if not (0.0 <= share <= 1.0):
        raise ParamError("share", f"expected a share in [0, 1], got {share!r}", share)
    optimal = [l for l, status in enumerate(result.status[0]) if status == "optimal"]
    if not optimal:
        return None
    l = optimal[0]
    asm = assemble(state, horizon=True) if assembly is None else assembly
    rest = witness_drive(
        state, 0, l, float(result.alpha[0, l]), 0.0, witness="central", assembly=asm, problem=problem
    )
    if share == 0.0:
        return rest
    tau_w = rest.torques  # the central witness at alpha = 0
    tau = tau_w + share * (squeeze_at_rest(state, 0, assembly=asm)["torques"] - tau_w)
    return dataclasses.replace(rest, torques=np.asarray(tau, dtype=float))


class Servo:
    """The position loop on the held configuration (module docstring) of one rollout's data.

    Parameters
    ----------
    model, data
        The simulation, at the held configuration (after ``mj_forward``): its actuator lengths
        are the loop's ``l_0`` unless ``l0`` is given.
    actuators, ctrl
        The driven ``<dcmotor>`` ids and their speed-setpoint control addresses
        ([`Rig`][mjtvm.physics.rig.Rig]'s ``acts`` and ``cadr``).
    gain
        kp (1/s); 0: no loop (speed setpoint 0, a damper).
    l0
        ``(A,)`` the lengths to hold (actuator-length units): a loop that continues another
        one's from a copy of its data (the other's ``l0``).

    Raises
    ------
    ParamError
        ``gain`` negative or not finite.
    """

    def __init__(
        self, model: mujoco.MjModel, data: mujoco.MjData, actuators: NDArray[np.int64],
        ctrl: NDArray[np.int64], gain: float, l0: NDArray[np.float64] | None = None,
    ) -> None:  # fmt: skip
        if not (np.isfinite(gain) and gain >= 0):
            raise ParamError("servo", f"expected a speed gain >= 0 (1/s), got {gain!r}", gain)
        self.m, self.d, self.acts, self.cadr, self.gain = model, data, actuators, ctrl, float(gain)
        self.l0 = (data.actuator_length[actuators] if l0 is None else np.asarray(l0, dtype=float)).copy()

    def step(self, n: int) -> None:
        """``n`` steps, the speed setpoints set before each from the last step's lengths."""
        if self.gain == 0.0:
            self.d.ctrl[self.cadr] = 0.0
            if n > 0:
                mujoco.mj_step(self.m, self.d, nstep=n)
            return
        d, acts, cadr, kp, l0 = self.d, self.acts, self.cadr, self.gain, self.l0
        for _ in range(n):
            d.ctrl[cadr] = kp * (l0 - d.actuator_length[acts])
            mujoco.mj_step(self.m, d)


def with_torsion(model: mujoco.MjModel, torsional: float) -> mujoco.MjModel:
    """A copy of ``model`` whose frictional point contacts (``condim`` 3) get torsional friction
    ``torsional`` (m, ``condim`` 4, the benchmark's ``_set_friction``); ``model`` itself at 0.

    Raises
    ------
    ParamError
        ``torsional`` negative or not finite.
    """
    if not (math.isfinite(torsional) and torsional >= 0):
        raise ParamError("torsional", f"expected a length >= 0 (m), got {torsional!r}", torsional)
    if torsional == 0.0:
        return model
    out = copy.deepcopy(model)
    point = out.geom_condim == 3
    out.geom_condim[point] = 4
    out.geom_friction[point, 1] = torsional
    return out


def with_position_loop(model: mujoco.MjModel, actuators: NDArray[np.int64], gain: float) -> mujoco.MjModel:
    r"""A copy of ``model`` whose ``<dcmotor>`` s ``actuators`` run [`Servo`][mjtvm.physics.squeeze.Servo]'s
    position loop in their own controller; ``model`` itself at ``gain`` 0.

    MuJoCo's dcmotor controller commands ``tau = k_p (u_pos - l) + k_d (u_vel - l') + u_ff``,
    a setpoint absent from ``input`` being 0 (our motors' ``input="vel ff"``, so
    ``u_pos = 0``; ``k_p`` is ``actuator_gainprm[:, 4]``, ``k_d`` ``[:, 6]``, read by MuJoCo at
    every step, so set in the compiled model: no recompile, the controls keep their layout).
    Here ``k_p = gain k_d``. With the speed setpoint ``u_vel = 0`` and the feedforward
    ``u_ff = tau_ff + k_p l_0`` the motor commands ``tau = k_d gain (l_0 - l) - k_d l' + tau_ff``,
    the torque of `Servo` (speed setpoint ``gain (l_0 - l)``) through the same voltage clamp
    and saturation, with ``l`` the length at the step's own state where `Servo` reads the
    previous step's (an O(dt) difference: one step of the motion). The controls are then
    constant, as ``mujoco.rollout`` steps them (``tau_ff`` the drive's feedforward).

    Parameters
    ----------
    actuators
        The driven ``<dcmotor>`` ids ([`Rig`][mjtvm.physics.rig.Rig]'s ``acts``); their
        ``k_p`` is replaced.
    gain
        The loop's speed gain (1/s), `Servo`'s ``gain``.

    Raises
    ------
    ParamError
        ``gain`` negative or not finite.
    """
    if not (math.isfinite(gain) and gain >= 0):
        raise ParamError("servo", f"expected a speed gain >= 0 (1/s), got {gain!r}", gain)
    if gain == 0.0:
        return model
    out = copy.deepcopy(model)
    acts = np.asarray(actuators, dtype=int)
    out.actuator_gainprm[acts, 4] = gain * out.actuator_gainprm[acts, 6]
    return out
