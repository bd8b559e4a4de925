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
* :func:`~mjtvm.enumeration.project_cdd` (the paper's way, the baseline): vertex
  enumeration of the lifted polytope with cddlib, projection of its vertices, convex hull
  (:func:`~mjtvm.hull.reduce_points`).

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

from .assembly import Assembly, BoxForm, assemble
from .errors import SolverError
from .hull import ZERO_TOL, PlaneCache, distinct, span, triangulate, vertex_mask
from .solvers import HighsSession, LinearProgram, LPSolution
from .state import GraspState

__all__ = [
    "REL_TOL",
    "LiftedPolytope",
    "Projection",
    "ProjectionStatus",
    "lifted_polytope",
    "project_lp",
]

ProjectionStatus = Literal["bounded", "unbounded", "empty", "timeout"]
REL_TOL = 1e-9  #: tolerance relative to the extent of S_ov (LP tolerances are 1e-9)
TIE_BREAK = 1e-6  #: tilt of the objective that picks a vertex from an optimal face


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
    basis = span(np.array(points), tol)
    normal_dirs = np.zeros((0, big_d))
    while basis.shape[0] + normal_dirs.shape[0] < big_d:
        known = np.vstack([basis, normal_dirs])
        u = np.linalg.svd(known, full_matrices=True)[2][known.shape[0]]  # orthogonal to known
        for sign in (1.0, -1.0):
            status, s = support(sign * u)
            ray = s if status == "unbounded" else ray
            if sign * (u @ s) > tol:
                points.append(s)
                basis = span(np.array(points), tol)
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
    return _refine(support, distinct(local, tol), basis, tol, result)


def _refine(
    support: _Support,
    local: NDArray[np.float64],
    basis: NDArray[np.float64],
    tol: float,
    result: Any,
) -> Projection:
    r"""Incremental hull inside the linear hull (``local``: points in its coordinates).

    Each round triangulates the points found (:func:`triangulate`) and solves one LP per
    facet plane not yet confirmed (:class:`PlaneCache`; slivers need none). A plane is
    confirmed when the support of :math:`S_{ov}` along its normal exceeds that of the
    points by at most ``tol``; otherwise a slightly tilted objective (:data:`TIE_BREAK`)
    picks a vertex of the optimal face, and the round's new points are added before the
    next round (one Qhull run costs as much as thousands of LPs, so every unconfirmed
    plane of a round gets its LP). When a round adds nothing, every facet of the points'
    hull supports :math:`S_{ov}`: the hull is :math:`S_{ov}`, and its vertices are
    sorted out by :func:`vertex_mask`.
    """
    k = basis.shape[0]
    big_d = basis.shape[1]
    tie = np.random.default_rng(0).normal(size=k)
    tie *= TIE_BREAK / np.linalg.norm(tie)
    ids = np.arange(len(local))
    planes = PlaneCache(k, tol)
    while True:
        simp, normals, hull_idx = triangulate(local)
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
            verts = distinct(local[hull_idx[vertex_mask(local, simp, hull_idx, tol)]], 10 * tol)
            return result("bounded", verts @ basis, basis)
        local = np.vstack([local[hull_idx], new])
        ids = np.concatenate([ids[hull_idx], ids.max() + 1 + np.arange(len(new))])
