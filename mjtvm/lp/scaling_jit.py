r"""The passes of [`equilibrate()`][mjtvm.lp.scaling.equilibrate] in numba: the same
arithmetic in the same order as its numpy passes, so the same factors bit for bit (the sums of
``np.bincount`` are sequential, a maximum is exact), without a few numpy calls per pass.

Imported on the batch paths only (with [`dual_jit`][mjtvm.lp.dual_jit]; compiled code
cached on disk, ``cache=True``).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["mean_of_logs", "ruiz_passes"]


@numba.njit(cache=True)
def mean_of_logs(
    rows: np.ndarray,
    cols: np.ndarray,
    logs: np.ndarray,
    r_counts: np.ndarray,
    c_counts: np.ndarray,
    passes: int,
) -> tuple[np.ndarray, np.ndarray]:
    """``passes`` alternating mean-of-logs passes from 0 (`scaling._mean_of_logs()`):
    ``(rho (m,), kappa (n + 1,))``, the right-hand side's column (the last) pinned at 0."""
    m, n1 = len(r_counts), len(c_counts)
    rho, kappa = np.zeros(m), np.zeros(n1)
    if len(rows) == 0:  # np.bincount of nothing is integer: 0, not -0.0, every pass
        return rho, kappa
    for _ in range(passes):
        s = np.zeros(m)
        for e in range(len(rows)):  # np.bincount's order
            s[rows[e]] += logs[e] + kappa[cols[e]]
        for i in range(m):
            rho[i] = -s[i] / max(r_counts[i], 1)
        t = np.zeros(n1)
        for e in range(len(cols)):
            t[cols[e]] += logs[e] + rho[rows[e]]
        for j in range(n1):
            kappa[j] = -t[j] / max(c_counts[j], 1)
        kappa[n1 - 1] = 0.0
    return rho, kappa


@numba.njit(cache=True)
def _segment_max(
    indptr: np.ndarray,
    idx: np.ndarray,
    logs: np.ndarray,
    factor: np.ndarray,
    own: np.ndarray,
    step: np.ndarray,
) -> float:
    """``step[i] = (max_e logs[e] + factor[idx[e]] + own[i]) / 2`` over segment i's entries
    (0 where it has none; ``np.maximum``'s nan), and the largest ``|step|`` (``np.max``'s)."""
    big = 0.0
    for i in range(len(indptr) - 1):
        a, b = indptr[i], indptr[i + 1]
        v = 0.0
        if b > a:
            best = logs[a] + factor[idx[a]]
            for e in range(a + 1, b):
                x = logs[e] + factor[idx[e]]
                if x > best or x != x:
                    best = x
            v = (best + own[i]) / 2
        step[i] = v
        u = abs(v)
        if u > big or u != u:
            big = u
    return big


@numba.njit(cache=True)
def ruiz_passes(
    r_indptr: np.ndarray,
    r_idx: np.ndarray,
    r_logs: np.ndarray,
    c_indptr: np.ndarray,
    c_idx: np.ndarray,
    c_logs: np.ndarray,
    rho: np.ndarray,
    kappa: np.ndarray,
    passes: int,
) -> tuple[np.ndarray, np.ndarray]:
    """`scaling._ruiz_passes()` from ``(rho, kappa)`` (not changed): the entries by row
    (``r_indptr`` over the m rows, their columns ``r_idx``) and by column (``c_indptr`` over the
    n + 1 columns, the right-hand side's last and pinned, their rows ``c_idx``)."""
    rho, kappa = rho.copy(), kappa.copy()
    m, n1 = len(rho), len(kappa)
    step, cstep = np.empty(m), np.empty(n1)
    for _ in range(passes):
        big_r = _segment_max(r_indptr, r_idx, r_logs, kappa, rho, step)
        for i in range(m):
            rho[i] = rho[i] - step[i]
        big_c = _segment_max(c_indptr, c_idx, c_logs, rho, kappa, cstep)
        if n1 > 0:
            # the pinned column's step is 0: the largest |step| without it
            cstep[n1 - 1] = 0.0
            big_c = 0.0
            for j in range(n1):
                u = abs(cstep[j])
                if u > big_c or u != u:
                    big_c = u
        for j in range(n1):
            kappa[j] = kappa[j] - cstep[j]
        if (big_c if big_c > big_r else big_r) < 0.25:
            break
    return rho, kappa
