r"""A servo datasheet: stall torque and no-load speed, the form servo makers publish.

A servo's datasheet gives the two ends of its speed-torque line at a supply voltage (e.g.
ROBOTIS's DYNAMIXEL XH430-W350: stall torque 3.4 N m and no-load speed 30 rev/min at 12 V,
both at the output shaft, ``mjtvm/data/dynamixel_xh430_w350.json``) rather than maxon's
nominal point. A DC motor's speed falls linearly with its torque between those ends, so the
operation range (eq. 1-3, the paper's Fig. 1 form) at the joint is the region under that line,
left of the continuous (rated, thermal) torque when the sheet gives one:

$$
(0, 0),\ (T_c, 0),\ (T_c, \omega_0 (1 - T_c / T_s)),\ (0, \omega_0)
$$

(``|tau|`` N m, ``|qdot|`` rad/s), with $T_s$ and $T_c$ times the gear ratio and
efficiency and $\omega_0$ over the gear ratio; the triangle $(0, 0), (T_s, 0),
(0, \omega_0)$ without a continuous torque (the servo may then hold its stall torque).

Keys (a JSON file or an inline table, as ``[ranges]`` ``datasheet = ...`` takes it;
``docs/grasp-format.md``): ``voltage_V``, ``stall_torque_Nm``, ``no_load_speed_rpm``
(required); ``gear_ratio`` (default 1: the figures are at the output), ``gear_efficiency``
(default 1), ``continuous_torque_Nm`` and ``rotor_inertia_kgm2`` (optional), each on the
side of the gear where the stall torque is given. Other keys (``servo``, ``source``, notes)
are the file's description and are not read.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.model.operation_range import OperationRange

__all__ = ["SERVO_KEYS", "SERVO_OPTIONAL", "ServoDatasheet", "is_servo_form"]

_RPM = 2.0 * math.pi / 60.0
SERVO_KEYS = ("voltage_V", "stall_torque_Nm", "no_load_speed_rpm")
"""The required keys of the servo form; ``stall_torque_Nm`` marks a sheet as one."""
SERVO_OPTIONAL = ("gear_ratio", "gear_efficiency", "continuous_torque_Nm", "rotor_inertia_kgm2")
"""The optional keys of the servo form."""
# the maxon form's line figures: in a servo sheet they would give a second speed-torque line
_MAXON_ONLY = ("nominal_speed_rpm", "nominal_torque_mNm", "stall_torque_mNm")


def is_servo_form(figures: Mapping[str, Any]) -> bool:
    """Whether a datasheet's figures are in the servo form (they give ``stall_torque_Nm``)."""
    return "stall_torque_Nm" in figures


@dataclass(frozen=True)
class ServoDatasheet:
    r"""A servo's published figures (SI units).

    Parameters
    ----------
    voltage
        Supply voltage of the figures (V); the ``<dcmotor>``'s Vmax.
    stall_torque
        Torque at zero speed (N m), motor side (at the output when ``gear_ratio`` is 1).
    no_load_speed
        Speed at zero torque (rad/s), on the same side.
    gear_ratio
        Motor turns per joint turn (1: the figures are at the output).
    gear_efficiency
        In (0, 1]: scales the torques at the joint.
    continuous_torque
        Rated (thermal) torque (N m), same side as the stall torque, or ``None``: the range
        reaches the stall torque.
    rotor_inertia
        Rotor inertia (kg m^2), same side; MuJoCo's actuator ``armature`` (reflected by the
        gear ratio squared at the joint).

    Raises
    ------
    ModelError
        A figure that is not a positive finite number (``rotor_inertia``: >= 0), an efficiency
        above 1, or a continuous torque above the stall torque.
    """

    voltage: float
    stall_torque: float
    no_load_speed: float
    gear_ratio: float = 1.0
    gear_efficiency: float = 1.0
    continuous_torque: float | None = None
    rotor_inertia: float = 0.0

    def __post_init__(self) -> None:
        names = ("voltage", "stall_torque", "no_load_speed", "gear_ratio", "gear_efficiency")
        for name in (*names, *(("continuous_torque",) if self.continuous_torque is not None else ())):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ModelError(
                    f"ServoDatasheet.{name}", f"expected a positive finite number, got {value!r}"
                )
        if not (math.isfinite(self.rotor_inertia) and self.rotor_inertia >= 0):
            raise ModelError(
                "ServoDatasheet.rotor_inertia", f"expected a finite number >= 0, got {self.rotor_inertia!r}"
            )
        if self.gear_efficiency > 1.0:
            raise ModelError("gear_efficiency", f"expected a number in (0, 1], got {self.gear_efficiency!r}")
        if self.continuous_torque is not None and self.continuous_torque > self.stall_torque:
            raise ModelError(
                "continuous_torque_Nm",
                f"{self.continuous_torque!r} N m is above the stall torque {self.stall_torque!r} N m",
            )

    @classmethod
    def from_figures(cls, figures: Mapping[str, Any]) -> ServoDatasheet:
        """The datasheet of a servo-form table (module docstring), speeds in rpm.

        Raises
        ------
        ModelError
            A missing required key, a figure that is not a number, a maxon-form line figure
            mixed in (the line would be given twice), or a value refused by the class.
        """
        missing = [k for k in SERVO_KEYS if k not in figures]
        if missing:
            raise ModelError(missing[0], "required in a servo datasheet (with stall_torque_Nm)")
        mixed = [k for k in _MAXON_ONLY if k in figures]
        if mixed:
            raise ModelError(
                mixed[0],
                "a maxon-form figure in a servo datasheet (stall_torque_Nm and no_load_speed_rpm "
                "give the speed-torque line): give one form",
            )
        numbers: dict[str, float] = {}
        for key in (*SERVO_KEYS, *SERVO_OPTIONAL):
            if key in figures:
                value = figures[key]
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    raise ModelError(key, f"expected a number, got {value!r}")
                x = float(value) if abs(value) < 1e300 else math.inf
                low_ok = x >= 0 if key == "rotor_inertia_kgm2" else x > 0
                if not (math.isfinite(x) and low_ok):
                    kind = (
                        "a finite number >= 0" if key == "rotor_inertia_kgm2" else "a positive finite number"
                    )
                    raise ModelError(key, f"expected {kind}, got {value!r}")
                numbers[key] = x
        return cls(
            voltage=numbers["voltage_V"],
            stall_torque=numbers["stall_torque_Nm"],
            no_load_speed=numbers["no_load_speed_rpm"] * _RPM,
            gear_ratio=numbers.get("gear_ratio", 1.0),
            gear_efficiency=numbers.get("gear_efficiency", 1.0),
            continuous_torque=numbers.get("continuous_torque_Nm"),
            rotor_inertia=numbers.get("rotor_inertia_kgm2", 0.0),
        )

    def operation_range(self) -> OperationRange:
        r"""The range at the joint (module docstring): vertices in (N m, rad/s)."""
        scale = self.gear_ratio * self.gear_efficiency
        stall, w0 = self.stall_torque * scale, self.no_load_speed / self.gear_ratio
        tc = self.continuous_torque
        if tc is None or tc >= self.stall_torque:
            return OperationRange(np.array([[0.0, 0.0], [stall, 0.0], [0.0, w0]]))
        knee = w0 * (1.0 - tc / self.stall_torque)
        return OperationRange(np.array([[0.0, 0.0], [tc * scale, 0.0], [tc * scale, knee], [0.0, w0]]))

    def motor(self) -> DCMotor:
        """The ``<dcmotor>`` of the physics check: the same speed-torque line at ``voltage``,
        saturated at the continuous torque (at the stall torque without one), its speed loop's
        gain ``stall_torque / no_load_speed`` (N m s/rad, on the figures' side of the gear).

        A servo publishes no loop gain, so it gets the rule of a box range's motor
        ([`box_motor()`][mjtvm.physics.motors.box_motor]): a speed error of the whole no-load
        speed asks the whole stall torque. At the joint that is ``T_s g / (w_0 / g) / g^2 =
        T_s / w_0`` whichever side of the gear the figures are on (3.4 / pi = 1.082 N m s/rad
        for the XH430-W350), where `DCMotor`'s default gain (5e-4 N m s/rad, the paper's
        motor-side figure behind its 40:1 gear) would give 5e-4 at an output-side servo's
        joint and 62.5 behind its 353.5:1 gear (``docs/physics-check.md``, "The dataset
        benchmark").

        Raises
        ------
        ModelError
            A gear efficiency other than 1 (MuJoCo's gear is ideal).
        """
        if self.gear_efficiency != 1.0:
            raise ModelError("gear_efficiency", "MuJoCo's <dcmotor> gear is ideal; expected 1")
        return DCMotor(
            voltage=self.voltage,
            stall_torque=self.stall_torque,
            no_load_speed=self.no_load_speed,
            max_continuous_torque=self.stall_torque
            if self.continuous_torque is None
            else self.continuous_torque,
            gear=self.gear_ratio,
            rotor_inertia=self.rotor_inertia,
            velocity_gain=self.stall_torque / self.no_load_speed,
        )
