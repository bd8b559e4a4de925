r"""The joint torque that the motion of a witness needs beyond eq. (19), from MuJoCo.

The quasi-static TVMMP (eq. 31) balances gravity and the contact forces only. Moving the
object at the constant twist $\alpha \hat r_l$ while the configuration changes takes
joint accelerations, and the motors must supply

$$
d = M(q)\,\ddot q + c(q, \dot q)
$$

on the finger joints (mass matrix with the motors' rotor inertia, i.e. MuJoCo's armature;
Coriolis and centrifugal terms; gravity excluded: it is $g_f$ already). The joint
motion is the one a rollout drives ([`mjtvm.physics.simulate`][mjtvm.physics.simulate]): the witness's joint
speeds, corrected at every configuration by [`setpoints()`][mjtvm.physics.rig.Rig.setpoints] so that
each finger's contact point follows the object (F: all of its velocity, L: the normal part,
S: eq. 13 with the witness's slip). Its acceleration at the state's configuration is a
central difference of those setpoints along the motion ([`joint_demand()`][mjtvm.physics.dynamic.joint_demand]).

A rollout checks a span of motion (``startup + window``, 7 ms by default), not an instant,
and near a stretched finger the demand grows within it. [`window_demand()`][mjtvm.physics.dynamic.window_demand] integrates the
same motion kinematically over such a span and keeps each joint's largest and least demand;
with a ``window`` ([`dynamic_pair()`][mjtvm.physics.dynamic.dynamic_pair]) both must fit the joint's operation range with the
torque of eq. (19) ([`mjtvm.problem2.dynamic`][mjtvm.problem2.dynamic], "Demands along a window"). The demand covers
every driven joint, those of fingers whose witness force is zero included: their motors alone
must accelerate them. With a transmission the demand is per joint and joins the balance
``P^T u - J^T f + J_eq^T lambda = g_f + d`` (the damping a loss of the ranges,
[`mjtvm.problem2.assembly`][mjtvm.problem2.assembly]); the
motion keeps the equality rows of a forward pass at each configuration.

[`dynamic_pair()`][mjtvm.physics.dynamic.dynamic_pair] hands this demand, as a function of alpha, to the simulator-free core
([`dynamic_alpha()`][mjtvm.problem2.dynamic.dynamic_alpha]), which bisects over LPs for
$\alpha^{dyn}_{kl}$. The joint speeds grow as alpha and the demand as alpha^2; the
witness (and with it the joint motion of redundant fingers) is recomputed at each candidate
alpha, as the rollout at that speed would drive it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError, SolverError
from mjtvm.model.state import GraspState
from mjtvm.physics.inertia import gravity_bias
from mjtvm.physics.rig import Rig
from mjtvm.physics.witness import Drive, WitnessKind, central_witness, witness_drive
from mjtvm.problem2.dynamic import DynamicAlpha, dynamic_alpha, limiting_term
from mjtvm.problem2.tvmmp import tvmmp

__all__ = ["JointDemand", "demand_of", "dynamic_pair", "joint_demand", "window_demand"]

_F64 = NDArray[np.float64]


@dataclass(frozen=True)
class JointDemand:
    r"""The extra torque of a motion at one configuration, per driven joint (N m).

    Attributes
    ----------
    inertia
        $M(q)\ddot q$ on the driven joints (rotor inertia included).
    bias
        $c(q, \dot q)$: Coriolis and centrifugal torques (gravity excluded).
    acceleration
        $\ddot q$ of the driven joints (rad/s^2).
    speeds
        $\dot q$ of the driven joints at the configuration (the tracked setpoints).
    """

    inertia: _F64
    bias: _F64
    acceleration: _F64
    speeds: _F64

    @property
    def total(self) -> _F64:
        """$M\\ddot q + c$ (N m)."""
        return self.inertia + self.bias


def _set_motion(m: mujoco.MjModel, d: mujoco.MjData, rig: Rig, drive: Drive, qpos: _F64) -> _F64:
    """``d`` at ``qpos`` moving with the drive's twist and tracked joint speeds; returns those speeds."""
    d.qpos[:] = qpos
    d.qvel[:] = 0.0
    if rig.coupled:  # the equality rows the setpoints keep (Rig.equality_rows) are those of a forward pass
        mujoco.mj_forward(m, d)
    else:
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
    fa, tw = rig.fadr, drive.twist
    d.qvel[fa : fa + 3] = tw[:3]
    d.qvel[fa + 3 : fa + 6] = d.xmat[rig.ob].reshape(3, 3).T @ tw[3:]
    speeds = rig.setpoints(d, drive)
    d.qvel[rig.dofs] = speeds
    return speeds


def joint_demand(
    model: mujoco.MjModel,
    qpos: _F64,
    drive: Drive,
    *,
    object_body: str = "object",
    step: float | None = None,
    rig: Rig | None = None,
) -> JointDemand:
    r"""$M(q)\ddot q$ and $c(q, \dot q)$ of the drive's motion at ``qpos`` (module docstring).

    Parameters
    ----------
    model
        A model whose driven joints have ``<dcmotor>`` actuators
        ([`sim_model()`][mjtvm.physics.settings.sim_model]); the armature (rotor inertia) is part of
        its mass matrix.
    drive
        The motion: object twist, joint speeds and contact types ([`Drive`][mjtvm.physics.witness.Drive]).
    step
        Time step (s) of the central difference of the tracked speeds; default the model's
        time step.
    """
    m = model
    rig = rig or Rig(m, drive, object_body)
    h = m.opt.timestep if step is None else step
    return _demand_at(m, mujoco.MjData(m), mujoco.MjData(m), rig, drive, qpos, h)[0]


def _demand_at(
    m: mujoco.MjModel, d: mujoco.MjData, probe: mujoco.MjData, rig: Rig, drive: Drive, qpos: _F64, h: float
) -> tuple[JointDemand, _F64]:
    """The demand at ``qpos`` ([`joint_demand()`][mjtvm.physics.dynamic.joint_demand]) and the full ``qvel`` of the motion there."""
    speeds = _set_motion(m, d, rig, drive, qpos)
    qvel = d.qvel.copy()
    ahead = []
    for sign in (1.0, -1.0):
        q = np.array(qpos, dtype=float)
        mujoco.mj_integratePos(m, q, qvel, sign * h)
        ahead.append(_set_motion(m, probe, rig, drive, q))
    acc = (ahead[0] - ahead[1]) / (2 * h)
    d.qpos[:] = qpos
    d.qvel[:] = qvel
    mujoco.mj_forward(m, d)
    full = np.zeros(m.nv)
    full[rig.dofs] = acc
    out = np.zeros(m.nv)
    mujoco.mj_mulM(m, d, out, full)
    bias = d.qfrc_bias - gravity_bias(m, probe, np.asarray(qpos, dtype=float))
    return JointDemand(out[rig.dofs].copy(), bias[rig.dofs].copy(), acc, speeds), qvel


def window_demand(
    model: mujoco.MjModel,
    qpos: _F64,
    drive: Drive,
    duration: float,
    *,
    object_body: str = "object",
    rig: Rig | None = None,
) -> _F64:
    r"""``(2, M)``: each joint's largest and least demand $M\ddot q + c$ along the motion.

    The drive's motion (object at its twist, joints at the tracked setpoints) is integrated
    kinematically from ``qpos`` for ``duration`` (s) in steps of the model's time step
    (``mj_integratePos``), and [`joint_demand()`][mjtvm.physics.dynamic.joint_demand] taken at every configuration passed,
    ``qpos`` and the last included. Row 0 is the per-joint maximum, row 1 the minimum (N m):
    the operation range bounds $|\tau_j|$, so both ends of each joint's demand must fit
    ([`mjtvm.problem2.dynamic`][mjtvm.problem2.dynamic], "Demands along a window"). ``duration = 0``: the demand at
    ``qpos`` twice.
    """
    if not (math.isfinite(duration) and duration >= 0):
        raise ParamError("duration", f"expected a finite number of seconds >= 0, got {duration!r}", duration)
    m = model
    rig = rig or Rig(m, drive, object_body)
    h = m.opt.timestep
    d, probe = mujoco.MjData(m), mujoco.MjData(m)
    q = np.array(qpos, dtype=float)
    totals = []
    for _ in range(round(duration / h) + 1):
        dem, qvel = _demand_at(m, d, probe, rig, drive, q, h)
        totals.append(dem.total)
        mujoco.mj_integratePos(m, q, qvel, h)
    arr = np.array(totals)
    return np.vstack([arr.max(axis=0), arr.min(axis=0)])


def demand_of(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    k: int,
    l: int,
    alpha_kl: float,
    *,
    witness: WitnessKind = "central",
    vertex: Any = None,
    object_body: str = "object",
    window: float = 0.0,
) -> Any:
    r"""The demand $a \mapsto M\ddot q + c$ of pair (k, l) for [`dynamic_alpha()`][mjtvm.problem2.dynamic.dynamic_alpha].

    At a candidate alpha ``a`` the motion is the rollout's drive at speed factor
    ``a / alpha_kl`` ([`witness_drive()`][mjtvm.physics.witness.witness_drive]: the central witness at
    ``min(a, alpha_kl)``, its speeds scaled above), so the demand is the torque the check at
    that speed needs. Zero at ``a = 0``. ``window`` (s) > 0: the ``(2, M)`` extremes of that
    demand along the motion's first ``window`` seconds ([`window_demand()`][mjtvm.physics.dynamic.window_demand]), else the demand
    at ``qpos``.
    """
    rig: list[Rig] = []

    def demand(a: float) -> _F64:
        if a <= 0.0 or alpha_kl <= 0.0:
            return np.zeros(state.num_joints)
        drive = witness_drive(state, k, l, alpha_kl, a / alpha_kl, witness=witness, vertex=vertex)
        if not rig:
            rig.append(Rig(model, drive, object_body))
        if window > 0:
            return window_demand(model, qpos, drive, window, rig=rig[0])
        return joint_demand(model, qpos, drive, object_body=object_body, rig=rig[0]).total

    return demand


def dynamic_pair(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    k: int,
    l: int,
    *,
    result: Any = None,
    witness: WitnessKind = "central",
    object_body: str = "object",
    rtol: float = 1e-3,
    window: float = 0.0,
) -> DynamicAlpha:
    r"""$\alpha^{dyn}_{kl}$ of one pair of a MuJoCo grasp state (module docstring).

    ``model`` from [`sim_model()`][mjtvm.physics.settings.sim_model] (the grasp's model with its
    motors), ``qpos`` the state's configuration, ``result`` the state's quasi-static
    [`TvmmpResult`][mjtvm.problem2.tvmmp.TvmmpResult] (solved here when omitted). ``window`` (s): the
    demand is taken along the motion's first ``window`` seconds ([`demand_of()`][mjtvm.physics.dynamic.demand_of]); a
    rollout's is its ``startup + window``, the span over which it is checked.

    Raises
    ------
    ParamError
        The pair has no quasi-static solution.
    """
    res = tvmmp(state) if result is None else result
    if res.status[k][l] != "optimal":
        raise ParamError("k, l", f"pair ({k}, {l}) is {res.status[k][l]}: no witness to move")
    alpha = float(res.alpha[k, l])
    if not math.isfinite(alpha):
        raise ParamError("k, l", f"pair ({k}, {l}) has alpha {alpha}")
    demand = demand_of(
        model,
        qpos,
        state,
        k,
        l,
        alpha,
        witness=witness,
        vertex=res.witnesses[k][l],
        object_body=object_body,
        window=window,
    )
    dyn = dynamic_alpha(state, k, l, demand, rtol=rtol)
    if dyn.alpha > 0 and dyn.witness is not None:
        # the simplex witness puts redundant joints on their limits; the limiting joint is named
        # at the least-motion, force-centred solution of the dynamic LP at alpha_dyn instead
        loaded = state.with_(gravity_torque=state.gravity_torque + dyn.demand)
        try:
            sol = central_witness(loaded, k, l, dyn.alpha * (1 - 1e-6))
        except SolverError:
            return dyn
        j, term = limiting_term(state, sol["torques"], sol["speeds"], dyn.demand)
        dyn = replace(dyn, joint=j, term=term)
    return dyn
