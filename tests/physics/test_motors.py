"""DC motors attached with MjSpec (mjtvm.physics.motors): datasheet ranges, the template's arrays, refusals."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.actuator import operation_range_from_actuator
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.grasp.actuation.dcmotor import mjcf_numbers as _fmt
from mjtvm.physics.motors import (
    attach_dcmotors,
    dcmotor_of_joint,
    motor_of_actuator,
    require_motors,
)

HAND = Path(__file__).resolve().parents[2] / "models" / "paper_hand" / "four_finger_hand.xml"
SERVOS = """<mujoco>
  <default><position kp="5" ctrlrange="-1 1"/></default>
  <worldbody><body name="b"><joint name="a" axis="0 0 1"/><joint name="b" axis="0 1 0"/>
    <joint name="c" type="slide" axis="1 0 0"/><geom type="box" size="0.01 0.02 0.03"/></body></worldbody>
  <actuator><position name="pa" joint="a"/><position name="pb" joint="b"/><motor name="mc" joint="c"/></actuator>
  <sensor><actuatorfrc name="fa" actuator="pa"/><actuatorfrc name="fc" actuator="mc"/></sensor>
  <keyframe><key name="k" qpos="0.1 0.2 0.3" ctrl="0.5 0.6 0.7"/></keyframe>
</mujoco>"""


def test_attached_motors_give_the_datasheet_range() -> None:
    motor = DCMotor.from_datasheet()
    model = attach_dcmotors(SERVOS, {"a": motor, "b": motor})
    assert [model.actuator(i).name for i in range(model.nactuator)] == ["mc", "a", "b"]
    want = operation_range_from_actuator(
        mujoco.MjModel.from_xml_string(
            f'<mujoco><worldbody><body><joint name="j"/><geom size="0.1"/></body></worldbody>'
            f"<actuator>{motor.mjcf('j', 'j')}</actuator></mujoco>"
        ),
        0,
    ).vertices
    for joint in ("a", "b"):
        a = dcmotor_of_joint(model, joint)
        assert a is not None and model.actuator_ctrllimited[a] == 0  # the default's ctrlrange does not leak
        np.testing.assert_allclose(
            operation_range_from_actuator(model, a).vertices, want, rtol=1e-9, atol=1e-12
        )
        back = motor_of_actuator(model, a)
        for f in (
            "voltage",
            "stall_torque",
            "no_load_speed",
            "max_continuous_torque",
            "gear",
            "rotor_inertia",
        ):
            assert getattr(back, f) == pytest.approx(getattr(motor, f), rel=1e-9)
    assert dcmotor_of_joint(model, "c") is None  # its motor stays
    assert model.nsensor == 1 and model.sensor(0).name == "fc"  # the removed servo's sensor went with it
    np.testing.assert_array_equal(model.key_ctrl[0], [0.7, 0, 0, 0, 0])  # the kept control survives
    assert dcmotor_of_joint(attach_dcmotors(mujoco.MjSpec.from_string(SERVOS), {"a": motor}), "a") is not None


def test_reattaching_the_hand_motors_reproduces_the_template() -> None:
    template = mujoco.MjModel.from_xml_path(str(HAND))
    joints = [template.joint(j).name for j in range(template.njnt) if template.joint(j).name != "object"]
    exact = DCMotor.from_datasheet()
    # the template writes 10 significant digits (hand._fmt): the same motor, as the XML has it
    written = DCMotor(
        *(
            float(_fmt(getattr(exact, f)))
            for f in (
                "voltage",
                "stall_torque",
                "no_load_speed",
                "max_continuous_torque",
                "gear",
                "rotor_inertia",
                "velocity_gain",
            )
        )
    )
    fields = (
        "gainprm",
        "biasprm",
        "dynprm",
        "gear",
        "forcerange",
        "armature",
        "ctrlspec",
        "trnid",
        "dyntype",
        "gaintype",
        "biastype",
        "forcelimited",
        "ctrllimited",
    )
    again = attach_dcmotors(HAND, dict.fromkeys(joints, written))
    for f in fields:
        np.testing.assert_array_equal(getattr(again, f"actuator_{f}"), getattr(template, f"actuator_{f}"), f)
    close = attach_dcmotors(HAND, dict.fromkeys(joints, exact))  # unrounded: R differs by ~1e-10 relative
    np.testing.assert_allclose(close.actuator_gainprm, template.actuator_gainprm, rtol=1e-9)


def test_motors_of_a_grasp_are_required() -> None:
    hand = mujoco.MjModel.from_xml_path(str(HAND))
    servos = mujoco.MjModel.from_xml_string(SERVOS)
    motor = DCMotor.from_datasheet()
    assert require_motors(servos, ["a"], {"a": motor}) == {"a": motor}
    assert require_motors(hand, ["f1_yaw0"], {"f1_yaw0": None}) == {}  # has its own <dcmotor>
    with pytest.raises(ModelError, match=r"^joint 'b': its range is a polygon.*needs a DC motor; give"):
        require_motors(servos, ["a", "b"], {"a": motor, "b": "its range is a polygon, not a motor model"})
    with pytest.raises(ModelError, match=r"^joint 'a': no <dcmotor>"):
        require_motors(servos, ["a"], {"a": None})
    with pytest.raises(ModelError, match="joint 'nope'"):
        attach_dcmotors(SERVOS, {"nope": motor})
    with pytest.raises(ModelError, match="MJCF text"):
        attach_dcmotors("<mujoco><bad", {"a": motor})


def test_motor_model_attaches_or_refuses(tmp_path: Path) -> None:
    from types import SimpleNamespace

    from mjtvm.physics.check import motor_model

    path = tmp_path / "servos.xml"
    path.write_text(SERVOS)
    servos = mujoco.MjModel.from_xml_path(str(path))
    motor = DCMotor.from_datasheet()
    grasp = SimpleNamespace(model=servos, model_path=path, joints=("a", "b"), motors={"a": motor, "b": motor})
    model = motor_model(grasp)
    assert dcmotor_of_joint(model, "a") is not None and dcmotor_of_joint(model, "b") is not None
    assert motor_model(grasp) is model  # once per grasp
    hand = SimpleNamespace(
        model=mujoco.MjModel.from_xml_path(str(HAND)),
        model_path=HAND,
        joints=("f1_yaw0",),
        motors={"f1_yaw0": None},
    )
    assert motor_model(hand) is hand.model  # its own <dcmotor>s: as is
    bad = SimpleNamespace(
        model=servos, model_path=path, joints=("a",), motors={"a": "its range is a polygon"}
    )
    with pytest.raises(ModelError, match=r"^joint 'a': its range is a polygon"):
        motor_model(bad)


def test_tendon_servos_through_a_motor_joint_are_removed() -> None:
    """A servo on a fixed tendon through joints a and b (the Shadow hand's coupled finger joints)
    moves b: attaching a motor to b removes it; a servo of an untouched joint c stays."""
    xml = """<mujoco><worldbody><body><joint name="a"/><geom size=".1" mass="1"/>
      <body pos="0 0 .2"><joint name="b"/><geom size=".1" mass="1"/>
      <body pos="0 0 .2"><joint name="c"/><geom size=".1" mass="1"/></body></body></body></worldbody>
      <tendon><fixed name="t"><joint joint="a" coef="1"/><joint joint="b" coef="1"/></fixed></tendon>
      <actuator><position name="coupled" tendon="t" kp="5"/><position name="third" joint="c" kp="5"/></actuator>
    </mujoco>"""
    model = attach_dcmotors(xml, {"b": DCMotor.from_datasheet()})
    names = [model.actuator(i).name for i in range(model.nactuator)]
    assert names == ["third", "b"]
