r"""Motor datasheets of a grasp file's ``ranges`` table: the shipped ones (``mjtvm/data``),
a JSON file or an inline table, read in maxon's form (no-load speed, nominal point, max
permissible speed) or the servo form ([`ServoDatasheet`][mjtvm.grasp.actuation.servo.ServoDatasheet]),
into an operation range (eq. 1-3) and the physics check's ``<dcmotor>``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from mjtvm.errors import MjtvmError
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.grasp.actuation.servo import SERVO_KEYS, SERVO_OPTIONAL, ServoDatasheet, is_servo_form
from mjtvm.model.bounds import MAX_FILE_BYTES
from mjtvm.model.operation_range import OperationRange

__all__ = ["datasheet", "from_datasheet_entry", "shipped_datasheets"]

_DATASHEET_KEYS = (
    "no_load_speed_rpm",
    "nominal_speed_rpm",
    "nominal_torque_mNm",
    "max_permissible_speed_rpm",
)
_DC_FORM = f"read as the DC-motor (maxon) form: {', '.join(_DATASHEET_KEYS)}"
_SERVO_FORM = f"the servo form has {', '.join(SERVO_KEYS)}"
# keys of the servo form only: a sheet with one and no stall_torque_Nm is a servo's missing it
_SERVO_ONLY = tuple(
    k for k in (*SERVO_KEYS, *SERVO_OPTIONAL) if k not in (*_DATASHEET_KEYS, "gear_ratio", "gear_efficiency")
)


def shipped_datasheets() -> list[str]:
    """The names of the datasheets shipped in ``mjtvm/data`` (``maxon_re25_20w``, ...)."""
    return sorted(p.name[:-5] for p in resources.files("mjtvm.data").iterdir() if p.name.endswith(".json"))


def datasheet(value: Any, base: Path | None, fail: Any) -> dict[str, Any]:
    """The datasheet figures of a ``datasheet`` value: a shipped name, a JSON path or a table."""
    if isinstance(value, Mapping):
        return dict(value)
    text = str(value)
    if not text.endswith(".json"):
        shipped = resources.files("mjtvm.data").joinpath(f"{text}.json")
        if not shipped.is_file():
            names = ", ".join(shipped_datasheets())
            raise fail(f"no shipped datasheet {text!r} (shipped: {names}; or give a .json path)")
        return dict(json.loads(shipped.read_text(encoding="utf-8")))
    path = Path(text) if base is None or Path(text).is_absolute() else base / text
    try:
        with path.open("rb") as f:
            raw = f.read(MAX_FILE_BYTES + 1)  # bounded: a device or a huge file is refused
    except OSError as e:
        raise fail(f"cannot read datasheet {str(path)!r}: {e.strerror or e}") from e
    except ValueError as e:  # a NUL in the path
        raise fail(f"cannot read datasheet {str(path)!r}: {e}") from e
    if len(raw) > MAX_FILE_BYTES:
        raise fail(f"datasheet {str(path)!r}: larger than {MAX_FILE_BYTES} bytes: not a datasheet")
    try:
        doc = json.loads(raw.decode("utf-8"))
    except ValueError as e:  # not UTF-8, malformed JSON
        raise fail(f"cannot read datasheet {str(path)!r}: {' '.join(str(e).split())}") from e
    if not isinstance(doc, dict):
        raise fail(f"datasheet {str(path)!r}: expected a JSON object")
    return doc


def from_datasheet_entry(
    entry: Mapping[str, Any], base: Path | None, fail: Any
) -> tuple[OperationRange, DCMotor | str]:
    """The operation range and the ``<dcmotor>`` (or why there is none) of a ``ranges`` entry
    with a ``datasheet`` (its ``gear_ratio`` and ``gear_efficiency`` over the sheet's), in the
    servo form or maxon's; ``fail(message)`` makes the error to raise."""
    figures = datasheet(entry["datasheet"], base, fail)
    for k in ("gear_ratio", "gear_efficiency"):
        if k in entry:
            figures[k] = entry[k]
    if is_servo_form(figures):
        try:
            servo = ServoDatasheet.from_figures(figures)
        except MjtvmError as e:
            raise fail(f"datasheet: {e}") from e
        try:
            servo_motor: DCMotor | str = servo.motor()
        except MjtvmError as e:
            servo_motor = f"its datasheet gives no <dcmotor> ({e})"
        return servo.operation_range(), servo_motor
    missing = [k for k in _DATASHEET_KEYS if k not in figures]
    servo_keys = [k for k in _SERVO_ONLY if k in figures]
    if servo_keys and all(k in missing for k in _DATASHEET_KEYS[1:]):  # no maxon-only figure
        raise fail(
            f"datasheet looks like a servo's (it has {', '.join(servo_keys)}) but lacks stall_torque_Nm "
            f"({_SERVO_FORM})"
        )
    if missing:
        raise fail(f"datasheet lacks {', '.join(missing)} ({_DC_FORM}; {_SERVO_FORM})")
    try:
        kwargs = {k: float(figures[k]) for k in _DATASHEET_KEYS}
        rng = OperationRange.from_datasheet(
            **kwargs,
            gear_ratio=float(figures.get("gear_ratio", 1.0)),
            gear_efficiency=float(figures.get("gear_efficiency", 1.0)),
        )
    except (MjtvmError, TypeError, ValueError) as e:
        raise fail(f"datasheet: {e} ({_DC_FORM}; {_SERVO_FORM})") from e
    try:
        motor: DCMotor | str = DCMotor.from_datasheet(figures)
    except (MjtvmError, KeyError, TypeError, ValueError) as e:  # e.g. a gear efficiency below 1
        motor = f"its datasheet gives no <dcmotor> ({e})"
    return rng, motor
