r"""A joint's continuous operation range read from its compiled ``<dcmotor>`` actuator
(the actuators [`hand_mjcf()`][mjtvm.paper_hand.hand.hand_mjcf] writes, or any MJCF's)."""

from __future__ import annotations

import mujoco
import numpy as np

from mjtvm.errors import ModelError
from mjtvm.model.operation_range import OperationRange

__all__ = ["operation_range_from_actuator"]


def _actuator_id(model: mujoco.MjModel, actuator: int | str) -> int:
    if isinstance(actuator, str):
        aid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, actuator)
        if aid < 0:
            raise ModelError(f"actuator {actuator!r}", "not in the model")
        return int(aid)
    if not 0 <= int(actuator) < model.nactuator:
        raise ModelError(f"actuator #{actuator}", f"no such actuator (the model has {model.nactuator})")
    return int(actuator)


def operation_range_from_actuator(model: mujoco.MjModel, actuator_id: int | str) -> OperationRange:
    r"""Continuous operation range at the joint of a compiled ``<dcmotor>`` actuator.

    MuJoCo 4 stores the compiled motor in ``actuator_gainprm`` (``[0]`` terminal resistance
    R in Ohm, ``[1]`` motor constant K in N m/A = V s/rad, ``[2:4]`` thermal coefficient
    and reference temperature, ``[4:7]`` controller kp ki kd, ``[7]`` controller Vmax in V),
    the continuous-torque ``saturation`` in ``actuator_forcerange`` (motor side, with
    ``actuator_forcelimited``) and the gear in ``actuator_gear[:, 0]``. From the
    ``nominal`` attribute the compiler sets K = V / no_load_speed and R = K V / stall_torque,
    so the speed-torque line at the supply voltage V is recovered exactly:
    no-load speed V / K, stall torque K V / R (motor side).

    The supply voltage is Vmax, or, for a voltage-commanded motor without Vmax, the bound
    of its voltage control's ``ctrlrange``. The polygon in (|joint torque| N m,
    |joint speed| rad/s), with torque x gear and speed / gear, is (0, 0), (T_c, 0),
    (T_c, w_c), (0, w_0): T_c the continuous torque (also capped by the joint's
    ``actuatorfrcrange``), w_c the speed on the line at T_c; a triangle when T_c reaches the
    stall torque. The resistance is taken at its reference temperature; the max
    permissible speed is not part of the MJCF (it does not cut the RE25's range).

    Parameters
    ----------
    model
        Compiled model.
    actuator_id
        Actuator index or name.

    Raises
    ------
    ModelError
        Not a ``<dcmotor>``, not a joint transmission, no supply voltage, or cogging,
        LuGre friction or actuator damping present (they would change the range).
    """
    a = _actuator_id(model, actuator_id)
    label = f"actuator {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) or '#' + str(a)!r}"
    if int(model.actuator_gaintype[a]) != int(mujoco.mjtGain.mjGAIN_DCMOTOR):
        raise ModelError(label, "is not a <dcmotor> actuator")
    if int(model.actuator_trntype[a]) != int(mujoco.mjtTrn.mjTRN_JOINT):
        raise ModelError(label, "does not drive a joint directly (transmission must be a joint)")
    damped = np.any(model.actuator_damping[a] != 0) or np.any(model.actuator_dampingpoly[a] != 0)
    if np.any(model.actuator_biasprm[a, :6] != 0) or damped:
        raise ModelError(label, "has cogging, LuGre friction or damping, which the operation range ignores")
    r_ohm, k = float(model.actuator_gainprm[a, 0]), float(model.actuator_gainprm[a, 1])
    if not (r_ohm > 0 and k > 0):
        raise ModelError(label, f"needs positive resistance and motor constant, got R={r_ohm}, K={k}")
    volts = float(model.actuator_gainprm[a, 7])
    spec = int(model.actuator_ctrlspec[a])
    if volts <= 0 and spec & int(mujoco.mjtCtrlInput.mjINPUT_VOLTAGE):
        c = int(model.actuator_ctrladr[a] + model.actuator_ctrlnum[a] - 1)
        if model.actuator_ctrllimited[c]:
            volts = float(np.max(np.abs(model.actuator_ctrlrange[c])))
    if not volts > 0:
        raise ModelError(label, "has no supply voltage (set the controller's Vmax or a voltage ctrlrange)")
    gear = float(model.actuator_gear[a, 0])
    if not gear > 0:
        raise ModelError(label, f"needs a positive gear, got {gear}")
    stall = k * volts / r_ohm  # motor side, N m
    torque = stall
    if model.actuator_forcelimited[a]:
        lo, hi = model.actuator_forcerange[a]
        torque = min(torque, -float(lo), float(hi))
    joint_torque = gear * torque
    j = int(model.actuator_trnid[a, 0])
    if model.jnt_actfrclimited[j]:
        lo, hi = model.jnt_actfrcrange[j]
        joint_torque = min(joint_torque, -float(lo), float(hi))
    if not joint_torque > 0:
        raise ModelError(label, "has no positive torque limit")
    w0 = volts / k / gear  # joint side, rad/s
    w_at = (volts - r_ohm * (joint_torque / gear) / k) / k / gear
    if w_at <= w0 * 1e-12:
        return OperationRange(np.array([[0.0, 0.0], [gear * stall, 0.0], [0.0, w0]]))
    return OperationRange(np.array([[0.0, 0.0], [joint_torque, 0.0], [joint_torque, w_at], [0.0, w0]]))
