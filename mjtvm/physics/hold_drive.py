r"""The physics check's hold drive: the least forces, or the squeeze with its position loop.

``mjtvm verify --hold-drive`` (``docs/physics-check.md``, "The squeeze hold"):

* ``least``: the hold test and every rollout drive the central witness (the least forces that
  give the pair's motion: [`witness_drive()`][mjtvm.physics.witness.witness_drive]), the
  settle on speed setpoints 0.
* ``squeeze``: the hold test holds the state with
  [`squeeze_drive()`][mjtvm.physics.squeeze.squeeze_drive] and the position loop
  ([`Servo`][mjtvm.physics.squeeze.Servo], `SERVO_GAIN`) on the rollouts' own contacts (no
  torsional friction: the speed rollouts have none); the rollout at speed factor s drives
  [`squeezed_drive()`][mjtvm.physics.hold_drive.squeezed_drive], the witness at s plus the
  squeeze solved at the witness's motion, its settle with the loop on
  (``SimSettings.servo``) and the startup and window without it, so the loop produces no
  speed the rollout measures.
* ``auto`` (the default): ``least`` where the least forces hold the state at rest, by both of
  the check's rest criteria: the hold test's (the object within 0.5 mm over a rollout's
  length, [`hold_test()`][mjtvm.physics.hold.hold_test]) and the rollout's at speed factor 0
  (the object under 2 mm/s in the window, the bisection's first rollout); else ``squeeze``.
  A hand whose least forces hold at rest is checked as before, row for row.

Why the squeeze changes no speed limit: its torques beyond the witness's are
``J_c^T f_int`` of internal forces (``G f_int = 0``, eq. 19-20: no wrench on the object), and the
LP keeps the witness's joint speeds, slip speeds and twist; it adds only forces inside the
friction pyramids and torques inside the operation ranges at those speeds. It needs torque
room: at alpha_kl a motor on its range's edge has none, and the squeeze LP then returns the
witness's torque for it.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Literal

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError
from mjtvm.model.state import GraspState
from mjtvm.physics.hold import HoldResult, hold_test, state_hold
from mjtvm.physics.settings import SimSettings
from mjtvm.physics.simulate import rollout
from mjtvm.physics.squeeze import SERVO_GAIN, SQUEEZE_SHARE, squeeze_at_rest, squeeze_drive
from mjtvm.physics.witness import Drive, WitnessKind, WitnessProblem, alpha_column, witness_drive
from mjtvm.problem2.assembly import Assembly, assemble

__all__ = ["HOLD_DRIVES", "HoldDrive", "check_hold", "squeezed_drive"]

HoldDrive = Literal["auto", "least", "squeeze"]
HOLD_DRIVES: tuple[HoldDrive, ...] = ("auto", "least", "squeeze")
"""The hold drives of ``mjtvm verify --hold-drive`` (module docstring)."""
_F64 = NDArray[np.float64]


def squeezed_drive(
    state: GraspState,
    k: int,
    l: int,
    alpha: float,
    s: float,
    *,
    witness: WitnessKind = "central",
    vertex: Any = None,
    assembly: Assembly | None = None,
    share: float = SQUEEZE_SHARE,
) -> Drive:
    r"""The drive of pair (k, l) at speed factor ``s`` with the squeeze: the witness drive's
    speeds and twist, its torques ``tau_w + share (tau_sq - tau_w)``.

    ``tau_sq`` is [`squeeze_at_rest()`][mjtvm.physics.squeeze.squeeze_at_rest] at the motion of
    the witness whose torques the drive feeds forward: the central witness's at
    ``min(s, 1) alpha`` (above 1 its torques are those of s = 1,
    [`witness_drive()`][mjtvm.physics.witness.witness_drive]); the vertex's at alpha_kl (its
    torques at every s). Both torque vectors satisfy the same statics, pyramids and ranges at
    that motion, so their convex combination does (module docstring). At s = 0 it is
    [`squeeze_drive()`][mjtvm.physics.squeeze.squeeze_drive]'s drive.

    Raises
    ------
    SolverError
        The witness or a squeeze LP is not solved.
    """
    asm = assemble(state, horizon=True) if assembly is None else assembly
    if witness == "central":
        qp = WitnessProblem(state, k, assembly=asm)
        base = witness_drive(state, k, l, alpha, s, witness=witness, assembly=asm, problem=qp)
        a = alpha * min(s, 1.0) * (1.0 - 1e-7)  # witness_drive's
        sol = qp.solve(l, a)  # the drive's own solution, kept by qp: not solved again
        qd, rho = sol["speeds"], sol["slip_speeds"]
    else:
        base = witness_drive(state, k, l, alpha, s, witness=witness, vertex=vertex, assembly=asm)
        a, qd, rho = alpha, vertex.speeds, vertex.slip_speeds
    col = alpha_column(state, asm, l)
    tau_sq = squeeze_at_rest(state, k, assembly=asm, motion=(qd, rho, a * col))["torques"]
    tau = base.torques + share * (tau_sq - base.torques)
    return dataclasses.replace(base, torques=np.asarray(tau, dtype=float))


def check_hold(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    result: Any,
    *,
    hold_drive: HoldDrive = "auto",
    settings: SimSettings | None = None,
    object_body: str = "object",
    duration: float | None = None,
) -> tuple[HoldResult | None, str]:
    """The physics check's hold test of a state and the drive its rollouts then use
    (``"least"`` or ``"squeeze"``, module docstring); ``None`` when no pair has a witness.
    ``auto`` tries the least forces first (the hold test, then the rollout at speed factor 0)
    and reports the squeeze's hold where they fail.

    Raises
    ------
    ParamError
        ``hold_drive`` not one of `HOLD_DRIVES`.
    """
    if hold_drive not in HOLD_DRIVES:
        raise ParamError("hold_drive", f"expected one of {HOLD_DRIVES}, got {hold_drive!r}", hold_drive)
    if hold_drive != "squeeze":
        hold = state_hold(
            model, qpos, state, result, settings=settings, object_body=object_body, duration=duration
        )
        if hold_drive == "least" or hold is None:
            return hold, "least"
        if hold.held and _rests(model, qpos, state, result, settings, object_body):
            return hold, "least"
    drive = squeeze_drive(state, result)
    if drive is None:
        return None, "squeeze"
    hold = hold_test(
        model, qpos, drive, settings=settings, object_body=object_body, duration=duration, servo=SERVO_GAIN
    )
    return hold, "squeeze"


def _rests(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    result: Any,
    settings: SimSettings | None,
    object_body: str,
) -> bool:
    """Whether the rollout of the central witness at speed factor 0 (the same for every RVDS
    vertex: no twist) passes: the object at rest in the window, the rollouts' rest criterion."""
    l = next(l for l, status in enumerate(result.status[0]) if status == "optimal")
    drive = witness_drive(state, 0, l, float(result.alpha[0, l]), 0.0, witness="central")
    return rollout(model, qpos, drive, settings=settings, object_body=object_body).passed
