r"""Problem 1: the lifted polytope of eq. (26) (eq. 34 with S-points) and its projection.

The TVMS is :math:`S_{ov}`, the projection onto the twist space of the lifted polytope

.. math:: \{ (x, \dot r) : \text{row\_lower} \le A x + A_{twist} \dot r \le
          \text{row\_upper},\ \text{col\_lower} \le x \le \text{col\_upper} \}

built by :func:`~mjtvm.assembly.assemble` with one statics copy per REFS vertex
(``statics_bounds`` puts :math:`-w_k` on copy k's balance rows), one common
:math:`\dot q` and one common box (eliminated exactly, :attr:`OperationRange.
mirrored_halfplanes`). With the RVDS cone, :math:`\dot r = \sum_l c_l \hat r_l`,
:math:`c_l \ge 0`, and the variables ``c`` replace :math:`\dot r` (columns
``A_twist @ R^T``). The lifted variables are ``y = [x; z]`` and the twist is
``generators @ z`` (``z`` is :math:`\dot r` itself without the cone).

**The origin.** :math:`S_{ov}` contains :math:`\dot r = 0` whenever it is non-empty:
with :math:`\dot q = 0`, :math:`\rho = 0` every kinematic row holds, and the
operation-range rows :math:`a_\tau |\tau| + a_{qd} |\dot q| \le b` are weakest at
:math:`\dot q = 0`, so the forces and torques of any feasible point still fit. Hence
the affine hull of :math:`S_{ov}` is a linear subspace, and its recession cone is the
projection of the lifted one (obtained from the same rows with zero bounds).

Two exact projections:

* :func:`project_lp` (fast, output-sensitive): support LPs in twist space on one HiGHS
  session (only the cost of ``z`` changes between LPs). First the linear hull: LPs along
  :math:`\pm e_i`, then along directions orthogonal to the points found until each is
  either extended or proved orthogonal to :math:`S_{ov}` (max = min = 0). Inside it, an
  incremental convex hull (Qhull) whose facets are each checked by one LP in the facet's
  normal direction: support = offset makes the facet final, otherwise the LP's point is
  added and the hull rebuilt (Bretl and Lall's projection, generalised to any
  dimension <= 6). The cost grows with the output: the Case 2 hand's 6-D TVMS has about
  2000 vertices and 250 000 simplicial facets, and the rebuilt hulls dominate.
* :func:`~mjtvm.tvms.project_cdd` (the paper's way, the baseline): vertex enumeration
  of the lifted polytope with cddlib, projection of its vertices, convex hull
  (:func:`reduce_points`).

Both work in scaled coordinates ``s = metric * rdot`` (the vertex set does not depend on
the metric, the tolerances do) and return the vertices in twist coordinates.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError, cKDTree

from .assembly import Assembly, BoxForm, assemble
from .errors import SolverError
from .solvers import HighsSession, LinearProgram, LPSolution
from .state import GraspState

__all__ = [
    "REL_TOL",
    "LiftedPolytope",
    "Projection",
    "ProjectionStatus",
    "lifted_polytope",
    "project_lp",
    "reduce_points",
]

ProjectionStatus = Literal["bounded", "unbounded", "empty", "timeout"]
REL_TOL = 1e-9  #: tolerance relative to the extent of S_ov (LP tolerances are 1e-9)
ZERO_TOL = 1e-9  #: an S_ov within this distance of the origin (scaled units) is {0}
SLIVER = 1e-8  #: simplices flatter than this (singular-value ratio) span no facet
TIE_BREAK = 1e-6  #: tilt of the objective that picks a vertex from an optimal face
CDD_REL_TOL = 1e-9  #: round-off of float cddlib relative to the extent


@dataclass(frozen=True, eq=False)
class LiftedPolytope:
    r"""The lifted polytope ``row_lower <= A y <= row_upper``, ``col_lower <= y <= col_upper``.

    Attributes
    ----------
    A
        ``(m, N)`` CSC matrix over ``y = [x; z]``: the assembly's variables, then ``z``.
    row_lower, row_upper, col_lower, col_upper
        Bounds (``±inf`` where absent).
    twist_cols
        The columns of ``z``.
    generators
        ``(D, len(z))``: the twist :math:`\dot r` = ``generators @ z`` (identity without
        the cone, :math:`R^T` with it).
    assembly
        The :class:`~mjtvm.assembly.Assembly` the rows come from.
    cone
        Whether ``z`` are the cone coefficients :math:`c_l \ge 0` of the RVDS vertices.
    """

    A: sp.csc_matrix
    row_lower: NDArray[np.float64]
    row_upper: NDArray[np.float64]
    col_lower: NDArray[np.float64]
    col_upper: NDArray[np.float64]
    twist_cols: slice
    generators: NDArray[np.float64]
    assembly: Assembly
    cone: bool

    @property
    def twist_dim(self) -> int:
        """D."""
        return int(self.generators.shape[0])

    def twist(self, y: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(D,)`` the twist of a lifted point (or ``(n, D)`` of rows of points)."""
        return np.asarray(y)[..., self.twist_cols] @ self.generators.T

    def recession(self) -> LiftedPolytope:
        """Its recession cone (zero bounds), with ``z`` boxed in [-1, 1] ([0, 1] for the cone)."""

        def zero(b: NDArray[np.float64]) -> NDArray[np.float64]:
            return np.where(np.isfinite(b), 0.0, b)

        cl, cu = zero(self.col_lower), zero(self.col_upper)
        cl[self.twist_cols] = 0.0 if self.cone else -1.0
        cu[self.twist_cols] = 1.0
        return replace(
            self, row_lower=zero(self.row_lower), row_upper=zero(self.row_upper), col_lower=cl, col_upper=cu
        )


def lifted_polytope(
    state: GraspState, *, rvds_cone: bool = True, box: BoxForm = "eliminated"
) -> LiftedPolytope:
    r"""The lifted polytope of eq. (26) / (34) for all REFS vertices of ``state`` at once.

    Parameters
    ----------
    state
        The grasp state; every row of ``state.refs`` gets its own forces and torques.
    rvds_cone
        Restrict :math:`\dot r` to the cone generated by ``state.rvds`` (when the state
        has an RVDS; the origin among them adds nothing). Without RVDS, no restriction.
    box
        The operation-range form of :func:`~mjtvm.assembly.assemble`.
    """
    asm = assemble(state, copies=state.refs.shape[0], box=box)
    lower, upper = asm.statics_bounds(state.refs)
    big_d = state.twist_dim
    cone = rvds_cone and state.rvds is not None
    if cone and state.rvds is not None:
        gens = np.asarray(state.rvds[np.any(state.rvds != 0.0, axis=1)], dtype=float).T
        z_lower, z_upper = 0.0, np.inf
    else:
        gens = np.eye(big_d)
        z_lower, z_upper = -np.inf, np.inf
    n, nz = asm.num_variables, gens.shape[1]
    twist_block = sp.csc_matrix(asm.A_twist @ gens) if nz else sp.csc_matrix((asm.A.shape[0], 0))
    return LiftedPolytope(
        A=sp.hstack([asm.A, twist_block], format="csc"),
        row_lower=lower,
        row_upper=upper,
        col_lower=np.concatenate([asm.col_lower, np.full(nz, z_lower)]),
        col_upper=np.concatenate([asm.col_upper, np.full(nz, z_upper)]),
        twist_cols=slice(n, n + nz),
        generators=gens,
        assembly=asm,
        cone=cone,
    )


@dataclass(frozen=True, eq=False)
class Projection:
    r"""The projection :math:`S_{ov}` of a lifted polytope onto the twist space.

    Attributes
    ----------
    status
        ``"bounded"``, ``"unbounded"``, ``"empty"`` (statics infeasible) or ``"timeout"``.
    vertices
        ``(n, D)`` its vertices in twist coordinates; ``(0, D)`` unless bounded.
    dimension
        Dimension of its affine hull (a linear subspace, see the module docstring);
        -1 when empty, ``None`` when unknown.
    basis
        ``(k, D)`` orthonormal basis of that subspace in scaled coordinates.
    metric
        ``(D,)`` the scaling ``s = metric * rdot`` of the working coordinates.
    unbounded_direction
        ``(D,)`` unit twist along which :math:`S_{ov}` is unbounded, or ``None``.
    num_lps, seconds, method
        LPs solved, wall time, ``"lp"`` or ``"cdd"``.
    lifted_vertices
        ``cdd`` only: number of vertices of the lifted polytope.
    """

    status: ProjectionStatus
    vertices: NDArray[np.float64]
    dimension: int | None
    basis: NDArray[np.float64] | None
    metric: NDArray[np.float64]
    unbounded_direction: NDArray[np.float64] | None
    num_lps: int
    seconds: float
    method: str
    lifted_vertices: int | None = None


# ------------------------------------------------------------------ geometry
def _triangulate(
    local: NDArray[np.float64],
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.int64]]:
    r"""Simplicial facets of the hull of ``(n, k)`` full-dimensional points, k >= 2.

    Qhull on joggled points ("QJ"): it never fails on the degenerate point sets a TVMS
    gives (many points on one facet, where Qhull's facet merging gives up). Returns the
    ``(F, k)`` point indices of each simplex, Qhull's ``(F, k)`` outward normals (of the
    joggled simplices) and the indices of the hull's points.
    """
    try:
        hull = ConvexHull(local, qhull_options="QJ")
    except QhullError as e:
        raise SolverError("qhull", str(e).splitlines()[0] if str(e) else "QhullError") from e
    return np.asarray(hull.simplices), hull.equations[:, :-1], np.asarray(hull.vertices)


def _fit_planes(
    local: NDArray[np.float64], simp: NDArray[np.int64], normals: NDArray[np.float64]
) -> NDArray[np.float64]:
    r"""Rows ``[a, b, c]``: the plane ``a^T t = b`` (``|a| = 1``, oriented like ``normals``)
    through each simplex's unperturbed points, which removes the joggle's tilt, and the
    ratio ``c`` of the smallest to the largest singular value of its edge vectors.
    Simplices with ``c <=`` :data:`SLIVER` are slivers: their points span less than a
    hyperplane (they fill lower-dimensional faces in the joggled triangulation), and no
    facet of the hull is made of slivers only."""
    x = local[simp]
    _, sv, vt = np.linalg.svd(x[:, 1:] - x[:, :1])
    a = vt[:, -1] * np.sign(np.einsum("fk,fk->f", vt[:, -1], normals))[:, None]
    return np.column_stack([a, np.einsum("fk,fk->f", a, x[:, 0]), sv[:, -1] / sv[:, 0]])


class _Planes:
    r"""The facet planes met so far, with a flag for those confirmed by an LP.

    Cached by the points spanning a simplex (a 64-bit hash of their sorted ids) and by
    the plane's coefficients (rounded: normal to 1e-8, offset to ``tol``), so that a
    plane is fitted and solved once however often the hull is rebuilt.
    """

    def __init__(self, k: int, tol: float) -> None:
        self.k, self.tol = k, tol
        self.rows = np.zeros((0, k + 2))
        self.confirmed = np.zeros(0, dtype=bool)
        rng = np.random.default_rng(12345)
        self._mult = rng.integers(1, 2**62, size=k + 1, dtype=np.uint64) * np.uint64(2) + np.uint64(1)
        self._by_points = (np.zeros(0, dtype=np.uint64), np.zeros(0, dtype=np.int64))
        self._by_coeffs = (np.zeros(0, dtype=np.uint64), np.zeros(0, dtype=np.int64))

    def _hash(self, keys: NDArray[np.int64]) -> NDArray[np.uint64]:
        with np.errstate(over="ignore"):
            return np.sum(keys.astype(np.uint64) * self._mult[: keys.shape[1]], axis=1, dtype=np.uint64)

    @staticmethod
    def _find(
        table: tuple[NDArray[np.uint64], NDArray[np.int64]], keys: NDArray[np.uint64]
    ) -> tuple[NDArray[np.bool_], NDArray[np.int64]]:
        pos = np.minimum(np.searchsorted(table[0], keys), max(len(table[0]) - 1, 0))
        found = (table[0][pos] == keys) if len(table[0]) else np.zeros(len(keys), dtype=bool)
        return found, np.where(found, table[1][pos] if len(table[1]) else 0, -1)

    @staticmethod
    def _insert(
        table: tuple[NDArray[np.uint64], NDArray[np.int64]],
        keys: NDArray[np.uint64],
        values: NDArray[np.int64],
    ) -> tuple[NDArray[np.uint64], NDArray[np.int64]]:
        k, v = np.concatenate([table[0], keys]), np.concatenate([table[1], values])
        order = np.argsort(k, kind="stable")
        return k[order], v[order]

    def of(
        self,
        local: NDArray[np.float64],
        ids: NDArray[np.int64],
        simp: NDArray[np.int64],
        normals: NDArray[np.float64],
    ) -> NDArray[np.int64]:
        """The plane index of each simplex (fitting and registering the new ones)."""
        point_keys = self._hash(np.sort(ids[simp], axis=1))
        found, plane = self._find(self._by_points, point_keys)
        miss = np.flatnonzero(~found)
        if len(miss):
            fitted = _fit_planes(local, simp[miss], normals[miss])
            rounded = np.round(np.column_stack([fitted[:, : self.k] * 1e8, fitted[:, self.k] / self.tol]))
            coeff_keys = self._hash(rounded.astype(np.int64))
            known, j = self._find(self._by_coeffs, coeff_keys)
            fresh, first, inverse = np.unique(coeff_keys[~known], return_index=True, return_inverse=True)
            index = len(self.rows) + np.arange(len(fresh))
            rows = fitted[~known][first]
            self.rows = np.vstack([self.rows, rows])
            self.confirmed = np.concatenate([self.confirmed, rows[:, -1] <= SLIVER])  # slivers need no LP
            j[~known] = index[inverse.ravel()]
            self._by_coeffs = self._insert(self._by_coeffs, fresh, index)
            self._by_points = self._insert(self._by_points, point_keys[miss], j)
            plane[miss] = j
        return plane


def _vertex_mask(
    local: NDArray[np.float64], simp: NDArray[np.int64], candidates: NDArray[np.int64], tol: float
) -> NDArray[np.bool_]:
    r"""Which ``candidates`` (indices of ``local``) are vertices of the hull triangulated by ``simp``.

    A point inside a face of dimension >= 1 lies in the convex hull of its neighbours
    in the triangulation (its star covers a neighbourhood of it in the face), a vertex
    does not; the distance is measured by non-negative least squares on
    ``[Q - p; 1] mu = [0; 1]``, ``mu >= 0``, and distances up to ``10 tol`` are round-off.
    """
    from scipy.optimize import nnls

    scale = float(np.max(np.abs(local)))
    owner = simp.ravel()
    order = np.argsort(owner, kind="stable")
    starts = np.searchsorted(owner[order], np.arange(len(local) + 1))
    facet = np.repeat(np.arange(len(simp)), simp.shape[1])[order]
    mask = np.zeros(len(candidates), dtype=bool)
    for n, i in enumerate(candidates):
        near = np.setdiff1d(simp[facet[starts[i] : starts[i + 1]]], [i])
        y = np.vstack([((local[near] - local[i]) / scale).T, np.ones(len(near))])
        mask[n] = len(near) == 0 or nnls(y, np.append(np.zeros(local.shape[1]), 1.0))[1] > 10 * tol / scale
    return mask


def _distinct(points: NDArray[np.float64], radius: float) -> NDArray[np.float64]:
    """One point of each cluster of ``points`` closer than ``radius`` (the first one)."""
    near = cKDTree(points).query_ball_point(points, radius)
    return points[[i for i, group in enumerate(near) if min(group) == i]]


def _span(points: NDArray[np.float64], tol: float) -> NDArray[np.float64]:
    """``(k, D)`` orthonormal basis of the linear span of ``(n, D)`` points (round-off ``tol``)."""
    _, sv, vt = np.linalg.svd(points, full_matrices=False)
    return vt[: int(np.sum(sv > tol * np.sqrt(len(points))))]


def reduce_points(
    points: NDArray[np.float64], *, rel_tol: float = CDD_REL_TOL
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Linear hull and vertices of the convex hull of ``(n, D)`` points and the origin.

    Parameters
    ----------
    points
        Points in (scaled) twist coordinates, e.g. the projected lifted vertices.
    rel_tol
        Distances below ``rel_tol`` x extent are round-off.

    Returns
    -------
    vertices, basis
        ``(v, D)`` the vertices, projected onto the span, and the ``(k, D)``
        orthonormal basis of that span.
    """
    big_d = points.shape[1]
    pts = np.vstack([np.zeros((1, big_d)), points])
    extent = float(np.max(np.abs(pts)))
    if extent <= ZERO_TOL:
        return np.zeros((1, big_d)), np.zeros((0, big_d))
    tol = rel_tol * extent
    basis = _span(pts, tol)
    local = _distinct(pts @ basis.T, tol)
    if basis.shape[0] == 1:
        ends = local[[np.argmin(local[:, 0]), np.argmax(local[:, 0])]]
        return ends @ basis, basis
    simp, _, idx = _triangulate(local)
    verts = local[idx[_vertex_mask(local, simp, idx, tol)]]
    return _distinct(verts, 10 * tol) @ basis, basis


# ------------------------------------------------------------------ LP projection
class _Support:
    r"""Support function of :math:`S_{ov}` by LPs on one HiGHS session.

    Only the costs of ``z`` change between LPs, and the primal simplex re-solves from the
    previous optimal basis (which stays primal feasible). An unbounded LP is followed by
    one on the recession cone (:meth:`LiftedPolytope.recession`) for a ray.
    """

    def __init__(self, poly: LiftedPolytope, metric: NDArray[np.float64]) -> None:
        self.poly, self.metric = poly, metric
        self.session = self._session(poly)
        n = poly.A.shape[1]
        self.cols = np.arange(n, dtype=np.int32)[poly.twist_cols]
        self.ray_session: HighsSession | None = None
        self.num_lps = 0

    @staticmethod
    def _session(p: LiftedPolytope) -> HighsSession:
        lp = LinearProgram(np.zeros(p.A.shape[1]), p.A, p.row_lower, p.row_upper, p.col_lower, p.col_upper)
        return HighsSession(lp)

    def _solve(self, session: HighsSession, h: NDArray[np.float64]) -> LPSolution:
        cost = -(self.poly.generators.T @ (self.metric * h))  # max h^T (metric * rdot)
        session.highs.changeColsCost(len(self.cols), self.cols, np.ascontiguousarray(cost))
        session.highs.setOptionValue("simplex_strategy", 4)  # primal: only the costs changed
        self.num_lps += 1
        return session.solve()

    def __call__(self, h: NDArray[np.float64]) -> tuple[str, NDArray[np.float64]]:
        """Maximise ``h^T s``: ``("optimal", s*)``, ``("unbounded", unit ray)`` or ``("infeasible", 0)``."""
        sol = self._solve(self.session, h)
        if sol.status == "optimal" and sol.x is not None:
            return "optimal", self.metric * self.poly.twist(sol.x)
        if sol.status == "infeasible":
            return "infeasible", np.zeros_like(h)
        if self.ray_session is None:
            self.ray_session = self._session(self.poly.recession())
        ray = self._solve(self.ray_session, h)
        s = self.metric * self.poly.twist(ray.x) if ray.x is not None else np.zeros_like(h)
        if ray.status != "optimal" or h @ s <= 1e-7 * np.linalg.norm(h):
            raise SolverError("highs", f"unbounded support LP without a recession ray ({ray.status})")
        return "unbounded", s / np.linalg.norm(s)


def _linear_hull(
    support: _Support, big_d: int, rel_tol: float
) -> tuple[list[NDArray[np.float64]], NDArray[np.float64], float, NDArray[np.float64] | None]:
    r"""Points of :math:`S_{ov}` spanning its linear hull, that hull's basis, the tolerance and a ray.

    LPs along :math:`\pm e_i` give the extent; then, while some direction ``u`` orthogonal
    to the span found so far is left, max and min of :math:`u^T s` either give a point
    off the span or prove ``u`` orthogonal to :math:`S_{ov}` (both 0).
    """
    points: list[NDArray[np.float64]] = []
    ray: NDArray[np.float64] | None = None
    for h in np.vstack([np.eye(big_d), -np.eye(big_d)]):
        status, s = support(h)
        ray = s if status == "unbounded" else ray
        points.append(s)
    extent = float(np.max(np.abs(points)))
    tol = rel_tol * max(extent, 1.0) if ray is not None else rel_tol * extent
    if extent <= ZERO_TOL:
        return [], np.zeros((0, big_d)), tol, None
    basis = _span(np.array(points), tol)
    normal_dirs = np.zeros((0, big_d))
    while basis.shape[0] + normal_dirs.shape[0] < big_d:
        known = np.vstack([basis, normal_dirs])
        u = np.linalg.svd(known, full_matrices=True)[2][known.shape[0]]  # orthogonal to known
        for sign in (1.0, -1.0):
            status, s = support(sign * u)
            ray = s if status == "unbounded" else ray
            if sign * (u @ s) > tol:
                points.append(s)
                basis = _span(np.array(points), tol)
                break
        else:
            normal_dirs = np.vstack([normal_dirs, u])
    return points, basis, tol, ray


def project_lp(
    poly: LiftedPolytope, *, metric: NDArray[np.float64] | None = None, rel_tol: float = REL_TOL
) -> Projection:
    r"""Exact projection of ``poly`` onto the twist space by support LPs (module docstring).

    Parameters
    ----------
    poly
        From :func:`lifted_polytope`.
    metric
        ``(D,)`` positive scaling of the working coordinates (default ones).
    rel_tol
        Facet and linear-hull tolerance, relative to the extent of :math:`S_{ov}`.
    """
    t0 = time.perf_counter()
    big_d = poly.twist_dim
    w = np.ones(big_d) if metric is None else np.asarray(metric, dtype=float)
    support = _Support(poly, w)

    def result(
        status: ProjectionStatus,
        verts: NDArray[np.float64],
        basis: NDArray[np.float64] | None,
        ray: NDArray[np.float64] | None = None,
    ) -> Projection:
        k = -1 if basis is None else basis.shape[0]
        ray_r = None if ray is None else (ray / w) / np.linalg.norm(ray / w)
        seconds = time.perf_counter() - t0
        return Projection(status, verts / w, k, basis, w, ray_r, support.num_lps, seconds, "lp")

    if support(np.zeros(big_d))[0] == "infeasible":
        return result("empty", np.zeros((0, big_d)), None)
    points, basis, tol, ray = _linear_hull(support, big_d, rel_tol)
    k = basis.shape[0]
    if ray is not None:
        return result("unbounded", np.zeros((0, big_d)), basis, ray)
    if k == 0:
        return result("bounded", np.zeros((1, big_d)), basis)
    local = np.vstack([np.zeros((1, k)), np.array(points) @ basis.T])
    if k == 1:
        ends = np.array([support(sign * basis[0])[1] @ basis[0] for sign in (1.0, -1.0)])
        return result("bounded", np.outer(np.unique(ends), basis[0]), basis)
    return _refine(support, _distinct(local, tol), basis, tol, result)


def _refine(
    support: _Support,
    local: NDArray[np.float64],
    basis: NDArray[np.float64],
    tol: float,
    result: Any,
) -> Projection:
    r"""Incremental hull inside the linear hull (``local``: points in its coordinates).

    Each round triangulates the points found (:func:`_triangulate`) and solves one LP per
    facet plane not yet confirmed (:class:`_Planes`; slivers need none). A plane is
    confirmed when the support of :math:`S_{ov}` along its normal exceeds that of the
    points by at most ``tol``; otherwise a slightly tilted objective (:data:`TIE_BREAK`)
    picks a vertex of the optimal face, and the round's new points are added before the
    next round (one Qhull run costs as much as thousands of LPs, so every unconfirmed
    plane of a round gets its LP). When a round adds nothing, every facet of the points'
    hull supports :math:`S_{ov}`: the hull is :math:`S_{ov}`, and its vertices are
    sorted out by :func:`_vertex_mask`.
    """
    k = basis.shape[0]
    big_d = basis.shape[1]
    tie = np.random.default_rng(0).normal(size=k)
    tie *= TIE_BREAK / np.linalg.norm(tie)
    ids = np.arange(len(local))
    planes = _Planes(k, tol)
    while True:
        simp, normals, hull_idx = _triangulate(local)
        todo = np.unique(planes.of(local, ids, simp, normals))
        new = np.zeros((0, k))
        for j in todo[~planes.confirmed[todo]]:
            a = planes.rows[j, :k]
            status, s = support(basis.T @ a)
            if status == "unbounded":
                return result("unbounded", np.zeros((0, big_d)), basis, s)
            t, known = basis @ s, float(np.max(local @ a))
            if a @ t <= known + tol:
                planes.confirmed[j] = True
                continue
            t_vertex = basis @ support(basis.T @ (a + tie))[1]
            t = t_vertex if a @ t_vertex > known + tol else t
            if not len(new) or np.min(np.max(np.abs(new - t), axis=1)) > tol:
                new = np.vstack([new, t])
        if not len(new):
            verts = _distinct(local[hull_idx[_vertex_mask(local, simp, hull_idx, tol)]], 10 * tol)
            return result("bounded", verts @ basis, basis)
        local = np.vstack([local[hull_idx], new])
        ids = np.concatenate([ids[hull_idx], ids.max() + 1 + np.arange(len(new))])
