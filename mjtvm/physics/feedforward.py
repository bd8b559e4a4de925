r"""A second drive for the dynamic alpha: the dynamic LP's witness with the inertial torque fed
forward (``mjtvm verify --dynamics``'s ``alpha_sim_ff``).

The rollouts' drive ([`witness_drive()`][mjtvm.physics.witness.witness_drive]) feeds forward the
quasi-static witness's torques, and the velocity loop supplies the inertial torque by lagging.
$\alpha^{dyn}_{kl}$ ([`dynamic_pair()`][mjtvm.physics.dynamic.dynamic_pair]) is the speed at which
the torques of eq. (19) plus the demand $d = M\ddot q + c$ fit the operation ranges; a drive
that commands what that LP solves tests it as stated. At speed factor ``s`` (of
$\alpha_{kl}$) the drive `feedforward_drive()` is the central witness
([`central_witness()`][mjtvm.physics.witness.central_witness]) of the state loaded with the demand
at $a = \min(s \alpha_{kl}, \alpha^{dyn})$ (gravity torque $g_f + d(a)$: the contact forces
that the dynamic LP chooses to make room for the demand), its speeds scaled to $s \alpha_{kl}$,
its torques without $d(a)$ (what holds the grasp, $J^T f + g_f$), and the rollout adds the
computed inertial and Coriolis torque of the tracked motion at every step
([`SimSettings.inertial_ff`][mjtvm.physics.settings.SimSettings]). Its bisection
(`alpha_sim_ff()`) gives alpha_sim under this drive; the two drives' alpha_sim / alpha_dyn
bracket what the dynamic alpha predicts, their spread its uncertainty (docs/dynamics.md).

Joint torques only: a hand with a transmission has actuator forces, where ``inertial_ff`` is
not available (`alpha_sim_ff()` raises ParamError).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError
from mjtvm.model.state import GraspState
from mjtvm.physics.bisection import Bisection, bisect
from mjtvm.physics.dynamic import demand_of
from mjtvm.physics.settings import SimSettings
from mjtvm.physics.simulate import RolloutResult, rollout
from mjtvm.physics.witness import Drive, witness_drive

__all__ = ["alpha_sim_ff", "feedforward_drive"]

_F64 = NDArray[np.float64]


def feedforward_drive(
    state: GraspState,
    k: int,
    l: int,
    alpha_kl: float,
    alpha_dyn: float,
    s: float,
    demand: Callable[[float], _F64],
) -> Drive:
    r"""The second drive of pair (k, l) at speed factor ``s`` of ``alpha_kl`` (module docstring).

    Parameters
    ----------
    state
        The grasp state (joint torques: no transmission).
    alpha_kl, alpha_dyn
        m/s (or rad/s): the pair's quasi-static and dynamic alpha, ``alpha_dyn > 0``.
    demand
        ``a -> (M,)`` the demand at alpha ``a`` (N m; [`demand_of()`][mjtvm.physics.dynamic.demand_of]
        with no window: the demand at the state's configuration).
    """
    a = s * alpha_kl
    if a <= 0.0:
        return witness_drive(state, k, l, alpha_kl, 0.0)
    a_w = min(a, alpha_dyn * (1.0 - 1e-6))  # past alpha_dyn the dynamic LP has no solution
    d = np.asarray(demand(a_w), dtype=float)
    loaded = state.with_(gravity_torque=state.gravity_torque + d)
    drive = witness_drive(loaded, k, l, a_w, a / a_w)
    return replace(drive, torques=drive.torques - d)


def alpha_sim_ff(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    k: int,
    l: int,
    alpha_kl: float,
    alpha_dyn: float,
    *,
    settings: SimSettings | None = None,
    object_body: str = "object",
    tol: float = 0.01,
) -> tuple[float, Bisection, RolloutResult]:
    r"""alpha_sim under the second drive: $s^* \alpha_{kl}$ by bisection on ``s`` in [0, 2] of
    rollouts of `feedforward_drive()` with ``settings`` and ``inertial_ff``; returns it, the
    bisection and the failing rollout just above s* (its failure is the verdict).

    Raises
    ------
    ParamError
        A hand with a transmission, or ``alpha_dyn <= 0``.
    """
    if state.transmission is not None:
        raise ParamError(
            "dynamics", "the feed-forward drive needs joint torques (a hand without a transmission)"
        )
    if not alpha_dyn > 0.0:
        raise ParamError("alpha_dyn", f"expected a positive dynamic alpha, got {alpha_dyn!r}")
    st = replace(settings or SimSettings(), inertial_ff=True)
    demand = demand_of(model, qpos, state, k, l, alpha_kl, object_body=object_body)

    def run(s: float) -> RolloutResult:
        drive = feedforward_drive(state, k, l, alpha_kl, alpha_dyn, s, demand)
        return rollout(model, qpos, drive, settings=st, object_body=object_body)

    b = bisect(lambda s: run(s).passed, 0.0, 2.0, tol=tol)
    return b.value * alpha_kl, b, run(min(b.value + tol, 2.0))
