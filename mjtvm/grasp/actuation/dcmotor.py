r"""A DC motor behind an ideal gear, as MuJoCo's ``<dcmotor>`` actuator takes it.

A grasp file's ``motors`` table names datasheets ([`DCMotor.from_datasheet()`][mjtvm.grasp.actuation.dcmotor.DCMotor.from_datasheet]); the paper's
hand ([`hand_mjcf()`][mjtvm.paper_hand.hand.hand_mjcf]) and the physics check write the actuators
([`DCMotor.mjcf()`][mjtvm.grasp.actuation.dcmotor.DCMotor.mjcf]).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from mjtvm.errors import ModelError
from mjtvm.model.operation_range import load_motor_data

__all__ = ["DCMotor", "mjcf_numbers"]

_RPM = 2.0 * math.pi / 60.0


def mjcf_numbers(*values: float) -> str:
    """``values`` as MJCF attribute text: 10 significant digits, round-off below 1e-12 as 0."""
    return " ".join(f"{(0.0 if abs(float(v)) < 1e-12 else float(v)) + 0.0:.10g}" for v in values)


@dataclass(frozen=True)
class DCMotor:
    r"""A DC motor behind an ideal gear, as MuJoCo's ``<dcmotor>`` takes it.

    Parameters
    ----------
    voltage
        Supply voltage (V); also the controller's Vmax.
    stall_torque
        Motor-side torque at zero speed on the speed-torque line at ``voltage`` (N m).
    no_load_speed
        Motor-side speed at zero torque (rad/s).
    max_continuous_torque
        Motor-side thermal limit (N m), MuJoCo's ``saturation``.
    gear
        Motor turns per joint turn (40 for the paper's 1/40 gear).
    rotor_inertia
        Motor-side rotor inertia (kg m^2), MuJoCo's actuator ``armature`` (reflected by gear^2).
    velocity_gain
        ``kd`` of the on-board controller (N m s/rad, motor side, torque space).
    """

    voltage: float
    stall_torque: float
    no_load_speed: float
    max_continuous_torque: float
    gear: float
    rotor_inertia: float = 0.0
    velocity_gain: float = 5e-4

    def __post_init__(self) -> None:
        for name in ("voltage", "stall_torque", "no_load_speed", "max_continuous_torque", "gear"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ModelError(f"DCMotor.{name}", f"expected a positive finite number, got {value!r}")
        for name in ("rotor_inertia", "velocity_gain"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ModelError(f"DCMotor.{name}", f"expected a finite number >= 0, got {value!r}")

    @classmethod
    def from_datasheet(
        cls, data: Mapping[str, Any] | None = None, *, line: Literal["nominal", "stall"] = "nominal"
    ) -> DCMotor:
        r"""The motor of a datasheet (default: [`load_motor_data()`][mjtvm.model.operation_range.load_motor_data]).

        Parameters
        ----------
        data
            Datasheet figures with the keys of ``mjtvm/data/maxon_re25_20w.json``.
        line
            Which speed-torque line the ``nominal`` attribute encodes. ``"nominal"``
            (default): the line through the no-load point and the nominal point (max
            continuous torque at nominal speed), i.e. the stall torque
            ``T_N n_0 / (n_0 - n_N)`` (204.4 mN m for the RE25): the actuator's continuous
            range then equals [`default_operation_range()`][mjtvm.model.operation_range.default_operation_range].
            ``"stall"``: the catalogue stall torque (243 mN m); that line passes 2.3 % above
            the catalogue nominal point (8525 rpm instead of 8330 rpm at 26.3 mN m).
        """
        d = load_motor_data() if data is None else data
        if float(d.get("gear_efficiency", 1.0)) != 1.0:
            raise ModelError("gear_efficiency", "MuJoCo's <dcmotor> gear is ideal; expected 1")
        n0 = float(d["no_load_speed_rpm"]) * _RPM
        n_nom = float(d["nominal_speed_rpm"]) * _RPM
        t_nom = float(d["nominal_torque_mNm"]) * 1e-3
        if float(d["max_permissible_speed_rpm"]) * _RPM < n0:
            raise ModelError("max_permissible_speed_rpm", "below the no-load speed: <dcmotor> has no cap")
        if line == "nominal":
            if n_nom >= n0:
                raise ModelError("nominal_speed_rpm", "must be below the no-load speed")
            stall = t_nom * n0 / (n0 - n_nom)
        elif line == "stall":
            stall = float(d["stall_torque_mNm"]) * 1e-3
        else:
            raise ModelError("line", f"expected 'nominal' or 'stall', got {line!r}")
        return cls(
            voltage=float(d["nominal_voltage_V"]),
            stall_torque=stall,
            no_load_speed=n0,
            max_continuous_torque=t_nom,
            gear=float(d["gear_ratio"]),
            rotor_inertia=float(d.get("rotor_inertia_gcm2", 0.0)) * 1e-7,
        )

    def mjcf(self, name: str, joint: str) -> str:
        """The ``<dcmotor>`` element driving ``joint``."""
        return (
            f'<dcmotor name="{name}" joint="{joint}" gear="{mjcf_numbers(self.gear)}" '
            f'nominal="{mjcf_numbers(self.voltage, self.stall_torque, self.no_load_speed)}" '
            f'saturation="{mjcf_numbers(self.max_continuous_torque)} 0 0" armature="{mjcf_numbers(self.rotor_inertia)}" '
            f'input="vel ff" controller="0 0 {mjcf_numbers(self.velocity_gain)} 0 0 {mjcf_numbers(self.voltage)}"/>'
        )
