r"""The classic capacity polytopes of one serial chain: velocity and force polytopes.

* [`velocity_polytope()`][mjtvm.polytopes.capacity.velocity_polytope]: $\{J \dot q : \dot q_{min} \le \dot q \le \dot q_{max}\}$,
  a zonotope ([`zonotope`][mjtvm.polytopes.zonotope]: vertices and facets from the Jacobian's
  columns, no LP, no Qhull);
* [`force_polytope()`][mjtvm.polytopes.capacity.force_polytope]: $\{f : \tau_{min} \le J^T f \le \tau_{max}\}$, the forces the
  joint torques can resist (pycapacity's definition, ``force_polytope``), an intersection of
  ``n`` slabs whose vertices come from one Qhull hull of its polar points.

These are what Problem 1 becomes when no force binds ([`speed_box`][mjtvm.polytopes.speed_box]):
with one fingertip contact and no wrench to balance, the TVMS restricted to translations
is the velocity polytope of the fingertip's Jacobian. Both return a [`CapacityPolytope`][mjtvm.polytopes.capacity.CapacityPolytope].
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from itertools import product

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import ConvexHull, QhullError

from mjtvm.errors import ParamError, SolverError
from mjtvm.polytopes.hull import distinct
from mjtvm.polytopes.volume import hull_volume
from mjtvm.polytopes.zonotope import RANK_TOL, zonotope

__all__ = ["DUPLICATE_TOL", "CapacityPolytope", "force_polytope", "velocity_polytope"]

DUPLICATE_TOL = 1e-9  #: force-polytope vertices closer than this x the extent are one


@dataclass(frozen=True, eq=False)
class CapacityPolytope:
    r"""A polytope in $R^m$ with its vertices, facets and volume.

    Attributes
    ----------
    vertices
        ``(v, m)`` the vertices (units of the polytope: m/s and rad/s for velocities, N and
        N m for forces).
    normals, offsets
        ``(f, m)`` unit rows and ``(f,)``: the facets $n^T x \le o$ (inside the affine
        hull when ``dimension < m``).
    dimension
        Dimension of the affine hull.
    known_volume
        The volume inside the affine hull when the construction gives it (a zonotope's sum),
        ``None`` to measure it on first use of `affine_volume` (one Qhull hull).
    """

    vertices: NDArray[np.float64]
    normals: NDArray[np.float64]
    offsets: NDArray[np.float64]
    dimension: int
    known_volume: float | None = None

    @cached_property
    def affine_volume(self) -> float:
        """The volume inside the affine hull (``dimension``-dimensional; the length in 1-D)."""
        if self.known_volume is not None:
            return self.known_volume
        return hull_volume(self.vertices) if self.dimension >= 2 else float(np.ptp(self.vertices))

    @property
    def volume(self) -> float:
        """The m-dimensional volume (0 when ``dimension < m``)."""
        return self.affine_volume if self.dimension == self.vertices.shape[1] else 0.0


def _jacobian(jacobian: ArrayLike) -> NDArray[np.float64]:
    try:
        j = np.asarray(jacobian, dtype=float)
    except (TypeError, ValueError) as e:
        raise ParamError("jacobian", "expected an (m, n) array of numbers", jacobian) from e
    if j.ndim != 2 or 0 in j.shape:
        raise ParamError("jacobian", f"expected an (m, n) array with m, n >= 1, got shape {j.shape}")
    if not np.isfinite(j).all():
        raise ParamError("jacobian", "expected finite numbers")
    return j


def _limits(
    name_min: str, name_max: str, low: ArrayLike, high: ArrayLike, n: int, *, strict: bool
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(n,)`` finite ``low <= high`` (``<`` when ``strict``), one per column of the Jacobian."""
    out = []
    for name, v in ((name_min, low), (name_max, high)):
        try:
            a = np.asarray(v, dtype=float).reshape(-1)
        except (TypeError, ValueError) as e:
            raise ParamError(name, f"expected {n} numbers (one per joint)", v) from e
        if a.shape != (n,) or not np.isfinite(a).all():
            raise ParamError(name, f"expected {n} finite numbers (one per joint)", v)
        out.append(a)
    bad = out[0] >= out[1] if strict else out[0] > out[1]
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        rel = "<" if strict else "<="
        raise ParamError(name_min, f"expected {name_min} {rel} {name_max} for every joint; joint {i} is not")
    return out[0], out[1]


def velocity_polytope(jacobian: ArrayLike, qd_min: ArrayLike, qd_max: ArrayLike) -> CapacityPolytope:
    r"""The velocity polytope $\{J \dot q : \dot q_{min} \le \dot q \le \dot q_{max}\}$.

    A zonotope with centre $J (\dot q_{min} + \dot q_{max}) / 2$ and generators
    $J_i (\dot q_{max,i} - \dot q_{min,i}) / 2$ ([`zonotope()`][mjtvm.polytopes.zonotope.zonotope]):
    the same polytope as pycapacity's ``velocity_polytope`` (hyperplane shifting, then
    Qhull) without an LP or a hull.

    Parameters
    ----------
    jacobian
        ``(m, n)`` the Jacobian ``J`` (task velocity per joint speed).
    qd_min, qd_max
        ``(n,)`` joint speed limits (rad/s or m/s), ``qd_min <= qd_max``.

    Returns
    -------
    CapacityPolytope
        In task units (m/s, rad/s).

    Raises
    ------
    ParamError
        A mis-shaped or non-finite argument, ``qd_min > qd_max``, or too many joints for the
        dimension (`MAX_CANDIDATES`).
    """
    j = _jacobian(jacobian)
    low, high = _limits("qd_min", "qd_max", qd_min, qd_max, j.shape[1], strict=False)
    z = zonotope(j @ ((low + high) / 2), j * ((high - low) / 2))
    return CapacityPolytope(z.vertices, z.normals, z.offsets, z.dimension, z.affine_volume)


def _interior_point(
    rows: NDArray[np.float64], bounds: NDArray[np.float64], j: NDArray[np.float64]
) -> NDArray[np.float64]:
    """A point strictly inside ``rows x <= bounds``: the origin when the torque box holds 0 inside,
    else the Chebyshev centre (one LP)."""
    m = j.shape[0]
    if np.all(bounds > 0.0):
        return np.zeros(m)
    from scipy.optimize import linprog  # imported when needed: 0.1 s

    norm = np.linalg.norm(rows, axis=1)
    res = linprog(
        np.r_[np.zeros(m), -1.0],
        A_ub=np.hstack([rows, norm[:, None]]),
        b_ub=bounds,
        bounds=[(None, None)] * m + [(0.0, None)],
        method="highs",
    )
    empty = ParamError(
        "tau_min", "expected torque limits that some force meets strictly (the polytope is empty or flat)"
    )
    if res.status == 2:  # infeasible
        raise empty
    if res.status != 0:
        raise SolverError("highs", f"the force polytope's Chebyshev centre: {res.message}")
    if res.x[-1] <= RANK_TOL * float(np.max(np.abs(bounds))):
        raise empty
    return np.asarray(res.x[:m])


def force_polytope(jacobian: ArrayLike, tau_min: ArrayLike, tau_max: ArrayLike) -> CapacityPolytope:
    r"""The force polytope $\{f : \tau_{min} \le J^T f \le \tau_{max}\}$ (pycapacity's
    ``force_polytope``): the forces at the end point that the joint torques can resist.

    An intersection of ``n`` slabs. With a point ``p`` strictly inside (the origin when
    $\tau_{min} < 0 < \tau_{max}$, else the Chebyshev centre), its vertices are the
    facets of the hull of the polar points $a_i / (b_i - a_i^T p)$ (one Qhull hull of
    ``2 n`` points), each then solved exactly from its ``m`` active rows. Its volume is
    measured when first asked for ([`CapacityPolytope.affine_volume`][mjtvm.polytopes.capacity.CapacityPolytope.affine_volume]: one more hull).

    Parameters
    ----------
    jacobian
        ``(m, n)`` the Jacobian ``J``, of rank ``m`` (otherwise some force meets no torque and
        the polytope is unbounded).
    tau_min, tau_max
        ``(n,)`` joint torque limits (N m or N), ``tau_min < tau_max``.

    Returns
    -------
    CapacityPolytope
        In force units (N, N m); full-dimensional.

    Raises
    ------
    ParamError
        A mis-shaped or non-finite argument, ``tau_min >= tau_max``, a Jacobian of rank
        below ``m``, or limits that no force meets strictly.
    SolverError
        When Qhull or the LP fails.
    """
    j = _jacobian(jacobian)
    m, n = j.shape
    low, high = _limits("tau_min", "tau_max", tau_min, tau_max, n, strict=True)
    sv = np.linalg.svd(j, compute_uv=False)
    if sv.size < m or sv[m - 1] <= RANK_TOL * sv[0]:
        raise ParamError("jacobian", f"expected rank {m} (a force that no joint feels is unbounded)")
    rows = np.vstack([j.T, -j.T])
    bounds = np.concatenate([high, -low])
    norm = np.sqrt(np.einsum("ij,ij->i", rows, rows))
    if n == m:  # J^-T [tau_min, tau_max]: a parallelepiped, every corner a vertex
        corners = np.array(list(product(*zip(low, high, strict=True))))
        verts = np.linalg.solve(j.T, corners.T).T
        return CapacityPolytope(verts, rows / norm[:, None], bounds / norm, m)
    p = _interior_point(rows, bounds, j)
    slack = bounds - rows @ p
    if m == 1:  # an interval: the tightest bound on each side
        a, b = rows[:, 0], bounds
        ends = np.array([np.max(b[a < 0] / a[a < 0]), np.min(b[a > 0] / a[a > 0])])
        return CapacityPolytope(ends[:, None], np.array([[-1.0], [1.0]]), ends * [-1.0, 1.0], 1)
    try:
        hull = ConvexHull(rows / slack[:, None])
    except QhullError as e:
        raise SolverError("qhull", str(e).splitlines()[0] if str(e) else "QhullError") from e
    active = np.asarray(hull.simplices)
    verts = np.linalg.solve(rows[active], bounds[active][:, :, None])[:, :, 0]
    # A vertex with more than m active rows is one facet of several simplices: keep one.
    tol = DUPLICATE_TOL * float(np.abs(verts - p).max())
    if ((rows @ verts.T >= (bounds - tol * norm)[:, None]).sum(axis=0) > m).any():
        verts = distinct(verts, tol)
    face = hull.vertices  # the polar points on the hull: the rows that are facets
    return CapacityPolytope(verts, rows[face] / norm[face, None], bounds[face] / norm[face], m)
