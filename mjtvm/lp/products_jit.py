r"""Products of many vectors with a sparse matrix's stored entries, in numba: the shared
columns of a family's certificates ([`Certifier.check_many()`][mjtvm.lp.certifier.Certifier.check_many]).

A state's matrix is a few percent full (the 22-joint hand: 1171 of 207 x 142 entries); its
answers' products over the stored entries only are ~1/25 of the dense products' multiply-adds
and need no BLAS thread. The sums are the same terms as the dense products', added in another
order (equal to round-off).

Imported on the batch paths only (with [`dual_jit`][mjtvm.lp.dual_jit]; compiled code
cached on disk, ``cache=True``).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["left", "right"]


@numba.njit(cache=True)
def right(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, xs: np.ndarray, out: np.ndarray) -> None:
    """``out = xs[:, :k] @ A.T`` for the ``(m, k)`` CSC matrix ``A`` (``indptr`` of ``k + 1``
    entries): ``xs`` ``(P, >= k)`` in (its columns past ``k`` unread), ``out`` ``(P, m)``
    overwritten."""
    out[:] = 0.0
    for p in range(xs.shape[0]):
        for j in range(len(indptr) - 1):
            x = xs[p, j]
            for e in range(indptr[j], indptr[j + 1]):
                out[p, indices[e]] += data[e] * x


@numba.njit(cache=True)
def left(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, ys: np.ndarray, out: np.ndarray) -> None:
    """``out[:, :k] = ys @ A`` for the ``(m, k)`` CSC matrix ``A``: ``ys`` ``(P, m)`` in,
    ``out`` ``(P, >= k)`` (its columns past ``k`` left as they are)."""
    for p in range(ys.shape[0]):
        for j in range(len(indptr) - 1):
            s = 0.0
            for e in range(indptr[j], indptr[j + 1]):
                s += data[e] * ys[p, indices[e]]
            out[p, j] = s
