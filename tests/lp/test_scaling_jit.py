"""`scaling_jit`'s passes give `equilibrate()`'s numpy passes' factors bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from mjtvm.lp import scaling
from mjtvm.lp.csc import Csc

scaling_jit = pytest.importorskip("mjtvm.lp.scaling_jit")  # numba


def _random_csc(rng: np.random.Generator) -> Csc:
    """A matrix whose entries span 1e-30 to 1e30, some rows and columns empty."""
    m, k = (int(v) for v in rng.integers(1, 40, 2))
    a = rng.standard_normal((m, k)) * 10.0 ** rng.integers(-30, 30, (m, k))
    a[rng.random((m, k)) > rng.random()] = 0.0
    cols, rows = np.nonzero(a.T)  # column-major: a CSC's stored entries
    indptr = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=k))])
    return Csc(a[rows, cols], rows, indptr, (m, k))


@pytest.mark.parametrize("passes", [64, 3, 0])
def test_the_compiled_passes_are_the_numpy_ones_bit_for_bit(passes: int) -> None:
    rng = np.random.default_rng(passes)
    for i in range(60):
        a = _random_csc(rng)
        rhs = None
        if i % 2:
            rhs = np.abs(rng.standard_normal(a.shape[0])) * 10.0 ** rng.integers(-20, 20, a.shape[0])
            rhs[rng.random(a.shape[0]) < 0.3] = 0.0  # bounds of 0: left out
        e = scaling._log_entries(a, rhs)
        mean = scaling._mean_of_logs(e)
        compiled_mean = scaling._mean_of_logs(e, scaling_jit)
        ruiz = scaling._ruiz_passes(e, *mean, passes)
        compiled_ruiz = scaling._ruiz_passes(e, *mean, passes, scaling_jit)
        for want, got in zip(mean + ruiz, compiled_mean + compiled_ruiz, strict=True):
            assert np.array_equal(want.view(np.int64), got.view(np.int64))  # the bits, -0.0 included
        s, t = (
            scaling.equilibrate(a, rhs=rhs, passes=passes),
            scaling.equilibrate(a, rhs=rhs, passes=passes, jit=scaling_jit),
        )
        assert np.array_equal(s.row, t.row) and np.array_equal(s.col, t.col)
