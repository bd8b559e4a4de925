"""A datasheet that does not read says which form it was read as and what the other form has:
a maxon-form figure refused names the servo form's keys, and a servo's sheet that lacks
``stall_torque_Nm`` is named as a servo's, not read as a maxon sheet lacking four figures."""

from __future__ import annotations

import re
from typing import Any

import pytest

from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.resolve.file import load_grasp
from mjtvm.model.operation_range import load_motor_data
from tests.grasp.actuation.test_servo import XH430, _gripper_doc

SERVO = r"the servo form has voltage_V, stall_torque_Nm, no_load_speed_rpm"
DC = (
    r"read as the DC-motor \(maxon\) form: no_load_speed_rpm, nominal_speed_rpm, nominal_torque_mNm, "
    r"max_permissible_speed_rpm"
)


def _refused(figures: dict[str, Any]) -> str:
    with pytest.raises(GraspError) as info:
        load_grasp(_gripper_doc({"datasheet": figures}))
    assert "\n" not in str(info.value)
    return str(info.value)


def test_a_maxon_figure_at_zero_names_the_form_read_and_the_servo_form_s_keys() -> None:
    text = _refused({**load_motor_data(), "nominal_speed_rpm": 0})
    assert re.search(
        r"ranges\.\*: joint 'f1j1': datasheet: nominal_speed_rpm: expected a positive finite number, "
        rf"got 0\.0 \({DC}; {SERVO}\)$",
        text,
    ), text


def test_a_maxon_sheet_lacking_figures_names_both_forms() -> None:
    figures = {k: v for k, v in load_motor_data().items() if k != "nominal_torque_mNm"}
    assert re.search(rf"datasheet lacks nominal_torque_mNm \({DC}; {SERVO}\)$", _refused(figures))


@pytest.mark.parametrize("extra", [{}, {"continuous_torque_Nm": 1.5}, {"rotor_inertia_kgm2": 1e-7}])
def test_a_servo_sheet_lacking_its_stall_torque_is_named_a_servo_s(extra: dict[str, Any]) -> None:
    figures = {k: v for k, v in {**XH430, **extra}.items() if k != "stall_torque_Nm"}
    has = ", ".join(k for k in ("voltage_V", "continuous_torque_Nm", "rotor_inertia_kgm2") if k in figures)
    text = _refused(figures)
    assert re.search(
        rf"datasheet looks like a servo's \(it has {has}\) but lacks stall_torque_Nm \({SERVO}\)$", text
    ), text
    assert "nominal_speed_rpm" not in text
