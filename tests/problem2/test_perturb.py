"""The state generators of :mod:`tests.support.perturb`: each changes what it says and nothing else."""

from __future__ import annotations

import numpy as np
import pytest

from mjtvm.problem2.tvmmp import tvmmp
from tests.support.perturb import (
    add_jacobian_roundoff,
    random_case,
    rescale_joints,
    scale_joint_column,
    scale_range,
    slide_contact,
)


def test_random_case_is_seeded() -> None:
    """The same seed gives the same state; different seeds differ."""
    (fa, a), (fb, b), (_, c) = random_case(3), random_case(3), random_case(4)
    assert fa == fb and fa.startswith("random-")
    assert np.array_equal(a.refs, b.refs) and not np.array_equal(a.refs, c.refs)


def test_rescale_joints_keeps_alphas() -> None:
    """A joint unit of 1e-6 rad: Jacobians and gravity torques times 1e-6, same alphas."""
    _, state = random_case(4)
    tiny = rescale_joints(state, 1e-6)
    assert np.allclose(tiny.contacts[0].jacobian, 1e-6 * state.contacts[0].jacobian, rtol=0, atol=0)
    assert np.array_equal(tiny.gravity_torque, 1e-6 * state.gravity_torque)
    np.testing.assert_allclose(tvmmp(tiny).alpha, tvmmp(state).alpha, rtol=1e-7)


def test_scale_range_scales_its_axes() -> None:
    _, state = random_case(0)
    op = state.operation_ranges[0]
    out = scale_range(op, 2.0, 0.5)
    assert out.max_torque == 2.0 * op.max_torque and out.max_speed == 0.5 * op.max_speed


def test_scale_joint_column_touches_one_column() -> None:
    _, state = random_case(1)
    out = scale_joint_column(state, 1, 1e-6)
    for a, b in zip(state.contacts, out.contacts):
        np.testing.assert_array_equal(b.jacobian[:, 1], 1e-6 * a.jacobian[:, 1])
        np.testing.assert_array_equal(np.delete(b.jacobian, 1, axis=1), np.delete(a.jacobian, 1, axis=1))
    with pytest.raises(ValueError, match="joint"):
        scale_joint_column(state, state.num_joints, 0.5)


def test_slide_contact_slides_in_the_tangent_plane() -> None:
    _, state = random_case(4)  # spatial, first contact F
    assert state.space == 3 and state.contacts[0].type == "F"
    out = slide_contact(state, 0, 0.7)
    c = out.contacts[0]
    assert c.type == "S" and c.slide_direction is not None
    assert abs(c.slide_direction @ c.normal) < 1e-15 and abs(np.linalg.norm(c.slide_direction) - 1) < 1e-15


def test_roundoff_noise_only_in_zeros_and_below_the_rule() -> None:
    _, state = random_case(2)
    noisy = add_jacobian_roundoff(state, np.random.default_rng(0))
    for a, b in zip(state.contacts, noisy.contacts):
        zero = a.jacobian == 0.0
        np.testing.assert_array_equal(b.jacobian[~zero], a.jacobian[~zero])
        assert np.all(b.jacobian[zero] != 0.0) and np.all(np.abs(b.jacobian[zero]) <= 1e-14)
    assert any(np.any(c.jacobian == 0.0) for c in state.contacts)  # there was something to fill
    with pytest.raises(ValueError, match="not round-off"):
        add_jacobian_roundoff(state, np.random.default_rng(0), high=1e-3)
