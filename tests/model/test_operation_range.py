"""Operation ranges (eq. 1-3): validation, half-planes, the box reduction, the datasheet constructor."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mjtvm import OperationRange, StateError, default_operation_range, load_motor_data

from ..helpers import Q_MAX, Q_NOM, RPM, T_MAX


def test_default_is_the_re25_behind_the_1_to_40_gear():
    """Datasheet: 26.3 mNm x 40 = 1.052 N m; 8330 rpm / 40 = 21.81 rad/s; 9560 rpm / 40 = 25.03 rad/s."""
    op = default_operation_range()
    np.testing.assert_allclose(op.vertices, [[0, 0], [T_MAX, 0], [T_MAX, Q_NOM], [0, Q_MAX]], rtol=1e-12)
    assert op.vertices[2] == pytest.approx([1.052, 21.81], abs=5e-3)
    assert op.vertices[3] == pytest.approx([0.0, 25.03], abs=5e-3)
    assert load_motor_data()["source"]


def test_gear_efficiency_scales_torque_only():
    op = default_operation_range(gear_efficiency=0.7)
    assert op.max_torque == pytest.approx(0.7 * T_MAX) and op.max_torque == pytest.approx(0.736, abs=1e-3)
    assert op.max_speed == pytest.approx(Q_MAX)


def test_max_permissible_speed_cuts_the_speed_torque_line():
    r"""A cap below the no-load speed: the line n(T) = 9560 - (9560 - 8330) T / 26.3 rpm
    meets 9000 rpm at T = (9560 - 9000) 26.3 / 1230 mNm, i.e. x 40 / 1000 N m at the joint."""
    m = load_motor_data()
    op = OperationRange.from_datasheet(
        no_load_speed_rpm=m["no_load_speed_rpm"],
        nominal_speed_rpm=m["nominal_speed_rpm"],
        nominal_torque_mNm=m["nominal_torque_mNm"],
        max_permissible_speed_rpm=9000.0,
        gear_ratio=40.0,
    )
    knee = (9560 - 9000) * 26.3 / 1230 * 40 / 1000
    np.testing.assert_allclose(
        op.vertices,
        [[0, 0], [T_MAX, 0], [T_MAX, Q_NOM], [knee, 9000 * RPM / 40], [0, 9000 * RPM / 40]],
        rtol=1e-12,
    )


def test_max_speed_at_follows_the_line():
    op = default_operation_range()
    assert op.max_speed_at(0.0) == pytest.approx(Q_MAX)
    assert op.max_speed_at(-T_MAX) == pytest.approx(Q_NOM)
    assert op.max_speed_at(0.5) == pytest.approx(Q_MAX - (Q_MAX - Q_NOM) * 0.5 / T_MAX)
    assert op.max_speed_at(1.1 * T_MAX) == -np.inf


@given(t=st.floats(-2, 2), q=st.floats(-40, 40))
def test_mirrored_halfplanes_describe_the_absolute_values(t, q):
    """(tau, qd) satisfies the mirrored rows iff (|tau|, |qd|) lies in the polygon (by geometry)."""
    op = default_operation_range()
    rows = op.mirrored_halfplanes
    inside_rows = bool(np.all(rows[:, 0] * t + rows[:, 1] * q <= rows[:, 2] + 1e-12))
    x, y = abs(t), abs(q)
    inside_geometry = x <= T_MAX + 1e-12 and y <= Q_MAX - (Q_MAX - Q_NOM) * x / T_MAX + 1e-9
    if abs(x - T_MAX) > 1e-9 and abs(y - (Q_MAX - (Q_MAX - Q_NOM) * x / T_MAX)) > 1e-6:
        assert inside_rows == inside_geometry


def test_vertex_order_and_orientation_do_not_matter_for_halfplanes():
    v = [[0, 0], [1, 0], [1, 2], [0.3, 3], [0, 3]]
    a, b = OperationRange(v), OperationRange(v[::-1])
    np.testing.assert_allclose(np.sort(a.halfplanes, axis=0), np.sort(b.halfplanes, axis=0))
    assert np.all(a.halfplanes[:, :2] >= 0)


@pytest.mark.parametrize(
    ("vertices", "match"),
    [
        ([[0, 0], [1, 0], [0.3, 0.3], [0, 1]], "not convex"),
        ([[0, 0], [1, 0], [1, 1], [0, 1], [0.6, 0.6]], "not convex"),
        ([[0, 0], [1, 0], [1.2, 1], [0, 1]], "not down-closed: the largest torque"),
        ([[0, 0], [1, 0], [1, 1], [0.5, 2], [0, 1.5]], "not down-closed: the largest speed"),
        ([[0, 0], [1, 0], [1, 1], [-0.2, 1]], "no negative coordinate"),
        ([[0.1, 0], [1, 0], [1, 1], [0, 1]], "origin"),
        ([[0, 0], [1, 0], [1, float("nan")], [0, 1]], "finite"),
        ([[0, 0], [1, 0]], "at least 3"),
        ([[0, 0], [0, 0], [1, 0], [0, 1]], "repeated vertex"),
    ],
)
def test_invalid_operation_ranges_are_rejected(vertices, match):
    with pytest.raises(StateError, match=match):
        OperationRange(vertices)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"no_load_speed_rpm": -1.0}, "no_load_speed_rpm"),
        ({"nominal_speed_rpm": 9600.0}, "nominal_speed_rpm"),
        ({"gear_efficiency": 1.5}, "gear_efficiency"),
    ],
)
def test_invalid_datasheet_figures(kwargs, match):
    base = {
        "no_load_speed_rpm": 9560.0,
        "nominal_speed_rpm": 8330.0,
        "nominal_torque_mNm": 26.3,
        "max_permissible_speed_rpm": 14000.0,
        "gear_ratio": 40.0,
    }
    with pytest.raises(StateError, match=match):
        OperationRange.from_datasheet(**{**base, **kwargs})


def test_losses_fold_into_the_range_by_hand():
    """RE 25 at 1/40 with joint damping d = 0.01 N m s/rad and friction loss f = 0.1 N m: every
    vertex (t, w) -> (t - d w - f, w), clipped where the net torque reaches 0. On the
    speed-torque line T(w) = 1.052 (w0 - w) / (w0 - w1) the new no-load speed solves
    T(w) = d w + f."""
    r = default_operation_range()
    w1, w0 = r.vertices[2, 1], r.vertices[3, 1]
    d, f = 0.01, 0.1
    slope = 1.052 / (w0 - w1)
    w_star = (slope * w0 - f) / (slope + d)
    folded = r.with_losses(damping=d, friction=f)
    np.testing.assert_allclose(
        folded.vertices, [[0, 0], [1.052 - f, 0], [1.052 - d * w1 - f, w1], [0, w_star]], rtol=1e-12
    )
    assert r.with_losses() is r
    # exact in the driving quadrant: at the vertex speed, motor torque = net torque + d w + f
    assert folded.max_speed_at(0.5) == pytest.approx((slope * w0 - f - 0.5) / (slope + d), rel=1e-12)
    with pytest.raises(StateError, match="friction loss 2 N m leaves no torque"):
        r.with_losses(friction=2.0)
    with pytest.raises(StateError, match="damping: expected a finite number >= 0"):
        r.with_losses(damping=-1.0)
