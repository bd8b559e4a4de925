"""The memo of the operation ranges (`joint_ranges(memo=)`, `actuator_ranges(memo=)`): a hit
returns what was computed, and anything the ranges are read from (the model's fields, the
moment, the ranges table) read anew when it differs. Values derived by hand from the MJCF."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import mujoco
import numpy as np
import pytest

from mjtvm import OperationRange
from mjtvm.grasp.actuation.ranges import MEMO_SIZE, RangesMemo, actuator_ranges, joint_ranges
from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.resolve.batch import BatchModels
from mjtvm.grasp.resolve.file import grasp_from_model

GRASP = "shadow_hand_coupled-sphere"
EXAMPLE = Path(__file__).resolve().parents[3] / "mjtvm" / "data" / "examples" / "shadow-sphere-dataset.npz"

# Two hinges on a fixed tendon a + b, pulled by a motor of gear 2 (moment [2, 2]); the joint
# a has a friction loss of 0.2 N m, which the actuator's force must overcome through its arm.
TENDON = """<mujoco><worldbody><body><joint name="a" frictionloss="0.2"/><geom size=".1" mass="1"/>
<body pos="0 0 .2"><joint name="b"/><geom size=".1" mass="1"/></body></body></worldbody>
<tendon><fixed name="t"><joint joint="a" coef="1"/><joint joint="b" coef="1"/></fixed></tendon>
<actuator><motor name="m" tendon="t" gear="2" forcelimited="true" forcerange="-3 3"/></actuator></mujoco>"""


def _tendon() -> tuple[mujoco.MjModel, np.ndarray]:
    model = mujoco.MjModel.from_xml_string(TENDON)
    return model, np.array([[2.0, 2.0]])


def _box(ranges: Mapping[str, OperationRange], name: str) -> tuple[float, float]:
    return ranges[name].max_torque, ranges[name].max_speed


def test_a_hit_returns_the_computed_ranges_and_a_changed_input_is_read_anew() -> None:
    model, moment = _tendon()
    table = {"m": {"source": "actuator", "actuator": True, "speed_limit": 2.0}}
    memo = RangesMemo()

    def ranges(m: np.ndarray = moment, t: dict = table) -> dict:
        return actuator_ranges(model, ("m",), m, (0, 1), t, base=None, file="f", memo=memo)[0]

    plain, _ = actuator_ranges(model, ("m",), moment, (0, 1), table, base=None, file="f")
    # |u| <= 3 - max(0.2 / 2, 0 / 2) = 2.9 N, |s| <= 2 (the box less the friction share)
    assert _box(plain, "m") == pytest.approx((2.9, 2.0), rel=1e-15)
    first = ranges()
    np.testing.assert_array_equal(first["m"].vertices, plain["m"].vertices)
    again = ranges()
    assert again["m"] is first["m"] and len(memo) == 1  # a hit: the same range, not recomputed
    again.clear()  # the caller's copy: the memo's own dict is untouched
    assert ranges()["m"] is first["m"]

    model.actuator_forcerange[0] = [-5.0, 5.0]  # a model field, changed in place: read anew
    assert _box(ranges(), "m") == pytest.approx((4.9, 2.0), rel=1e-15)
    # another moment (a spatial tendon's arms at another configuration): 5 - 0.2 / 4
    assert _box(ranges(2.0 * moment), "m") == pytest.approx((4.95, 2.0), rel=1e-15)
    # another ranges table (not the same object): read anew, though its key may be reused
    faster = {"m": {"source": "actuator", "actuator": True, "speed_limit": 3.0}}
    assert _box(ranges(t=faster), "m") == pytest.approx((4.9, 3.0), rel=1e-15)


def test_the_memo_is_bounded() -> None:
    model, moment = _tendon()
    table = {"m": {"source": "actuator", "actuator": True, "speed_limit": 2.0}}
    memo = RangesMemo()
    for k in range(MEMO_SIZE + 3):
        arms = (1.0 + 0.1 * k) * moment
        found, _ = actuator_ranges(model, ("m",), arms, (0, 1), table, base=None, file="f", memo=memo)
        assert found["m"].max_torque == pytest.approx(3.0 - 0.2 / arms[0, 0], rel=1e-15)
    assert len(memo) == MEMO_SIZE


def test_joint_ranges_memo_reads_the_joints_damping_anew() -> None:
    model = mujoco.MjModel.from_xml_string(
        """<mujoco><worldbody><body><joint name="a" damping="0.5"/><geom size=".1" mass="1"/></body>
        </worldbody><actuator><motor name="m" joint="a" forcelimited="true" forcerange="-2 2"/></actuator></mujoco>"""
    )
    table = {"*": {"source": "actuator", "actuator": True, "speed_limit": 1.0}}
    memo = RangesMemo()
    first, motors = joint_ranges(model, ("a",), table, base=None, file="f", memo=memo)
    # the box 2 N m x 1 rad/s less the damping's 0.5 qd: 1.5 N m left at 1 rad/s
    np.testing.assert_allclose(
        sorted(map(tuple, first["a"].vertices)), [(0, 0), (0, 1), (1.5, 1), (2, 0)], rtol=1e-15, atol=0
    )
    assert joint_ranges(model, ("a",), table, base=None, file="f", memo=memo)[0]["a"] is first["a"]
    assert motors["a"] == joint_ranges(model, ("a",), table, base=None, file="f")[1]["a"]
    model.dof_damping[0] = 1.0
    again, _ = joint_ranges(model, ("a",), table, base=None, file="f", memo=memo)
    np.testing.assert_allclose(
        sorted(map(tuple, again["a"].vertices)), [(0, 0), (0, 1), (1, 1), (2, 0)], rtol=1e-15, atol=0
    )


def test_batch_grasps_at_two_scales_share_the_ranges_a_fresh_grasp_reads() -> None:
    """The example dataset's Shadow hand (fixed tendons: the moment is the same at every
    scale and configuration): a later grasp's ranges are the first's objects, and equal to
    those read without a memo on its own model."""
    from mjtvm.jobs.rank_inputs import read_datasets

    batch = BatchModels.from_file(GRASP)
    grasps = []
    for entry in read_datasets(GRASP, [str(EXAMPLE)]):
        try:
            grasps.append(batch.grasp(entry))
        except GraspError:  # the dataset's broken grasps
            continue
        if len(grasps) == 2:
            break
    first, other = grasps
    assert other.model is not first.model  # a scale per grasp: another compiled model
    assert set(other.operation_ranges) == set(first.operation_ranges)
    assert all(other.operation_ranges[a] is first.operation_ranges[a] for a in first.operation_ranges)
    fresh = grasp_from_model(dict(other.document), batch.path, other.model, batch.model_path)
    assert set(fresh.operation_ranges) == set(other.operation_ranges)
    for a, rng in fresh.operation_ranges.items():
        assert rng is not other.operation_ranges[a]
        np.testing.assert_array_equal(rng.vertices, other.operation_ranges[a].vertices)
    assert dict(fresh.motors) == dict(other.motors)
