"""`float_array()`: a float array takes the checked path's result without its per-number loop."""

from __future__ import annotations

import numpy as np
import pytest

from mjtvm.errors import StateError
from mjtvm.model.bounds import MAX_ABS, float_array


@pytest.mark.parametrize(
    ("value", "ndim"),
    [
        (np.array([1.5, -0.0, 2e-310, -3.0]), 1),
        (np.array([0.1, 0.2], dtype=np.float32), 1),
        (np.zeros(0), 1),
        (np.arange(6.0).reshape(2, 3), 2),
        (np.zeros((0, 3)), 2),
        (np.zeros((2, 0)), 2),
    ],
)
def test_float_arrays_as_the_checked_lists(value: np.ndarray, ndim: int) -> None:
    fast = float_array(value, "x", ndim=ndim)
    slow = float_array(value.tolist(), "x", ndim=ndim)
    assert fast.shape == slow.shape and fast.dtype == slow.dtype and not fast.flags.writeable
    assert np.array_equal(fast, slow) and np.array_equal(np.signbit(fast), np.signbit(slow))


@pytest.mark.parametrize("bad", [np.nan, np.inf, 2 * MAX_ABS])
def test_float_arrays_refused_as_the_lists(bad: float) -> None:
    value = np.array([[1.0, bad]])
    with pytest.raises(StateError) as fast:
        float_array(value, "x", ndim=2)
    with pytest.raises(StateError) as slow:
        float_array(value.tolist(), "x", ndim=2)
    assert str(fast.value) == str(slow.value)


def test_float_arrays_keep_the_size_limits() -> None:
    with pytest.raises(StateError, match="at most 2 entries"):
        float_array(np.zeros(3), "x", ndim=1, max_len=2)
    with pytest.raises(StateError, match="rows of at most 2"):
        float_array(np.zeros((1, 3)), "x", ndim=2, max_width=2)


def test_float_arrays_come_row_major() -> None:
    """A transposed (column-major) array comes back row-major, as from its lists: products
    over it round the same."""
    out = float_array(np.arange(6.0).reshape(3, 2).T, "x", ndim=2)
    assert out.flags.c_contiguous
