r"""Problem 1: the TVMS :math:`S_{ov}` and the TVMM (eq. 26-29, 34), the ``mjtvm.tvms/1`` document.

:func:`tvms` builds the lifted polytope (:func:`~mjtvm.projection.lifted_polytope`),
projects it onto the twist space (:func:`~mjtvm.projection.project_lp`, or the paper's
vertex enumeration :func:`project_cdd` as the baseline) and measures it: the
D-dimensional volume (eq. 28-29, by Qhull), 0 unless :math:`S_{ov}` is full-dimensional,
and the volume inside its affine hull after scaling the twist by ``scale`` (the paper's
Case 1 figure: diag(10, 10, 10, 1, 1, 1), 1 / 0.1 m on the linear part).

The baseline, like the paper, turns the lifted polytope's H-representation into its
vertices with cddlib, in the paper's variables (:func:`force_form`) and with the
equalities solved first; cddlib runs in a child process that is killed after
``time_limit`` seconds, so that a hand the enumeration cannot handle reports
``"timeout"`` instead of hanging.
"""

from __future__ import annotations

import multiprocessing
import time
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import ConvexHull, QhullError

from .assembly import BoxForm
from .errors import SolverError, StateError
from .projection import (
    CDD_REL_TOL,
    LiftedPolytope,
    Projection,
    ProjectionStatus,
    lifted_polytope,
    project_lp,
    reduce_points,
)
from .solvers import DROP_TOL
from .state import GraspState

__all__ = [
    "CHARACTERISTIC_LENGTH",
    "TVMS_SCHEMA",
    "TvmsResult",
    "TvmsTimings",
    "default_scale",
    "force_form",
    "project_cdd",
    "tvms",
]

TVMS_SCHEMA = "mjtvm.tvms/1"
CHARACTERISTIC_LENGTH = 0.1  #: m: the paper's object radius; linear twist parts are divided by it
Method = Literal["lp", "cdd"]


def _json(values: Any) -> Any:
    """Nested lists of floats, with signed zeros printed as 0.0."""
    return (np.asarray(values, dtype=float) + 0.0).tolist()


# ------------------------------------------------------------------ the cdd baseline
def _cone_facets(gens: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(h, d)`` unit rows ``a`` with cone(gens) = {f : a f >= 0} (cddlib, V- to H-form)."""
    import cdd

    rays = np.column_stack([np.zeros(gens.shape[1]), gens.T]).tolist()
    mat = cdd.matrix_from_array(rays, rep_type=cdd.RepType.GENERATOR)
    ineq = cdd.copy_inequalities(cdd.polyhedron_from_matrix(mat))
    rows = np.array(ineq.array, dtype=float).reshape(-1, gens.shape[0] + 1)[:, 1:]
    return rows / np.linalg.norm(rows, axis=1, keepdims=True)


def force_form(poly: LiftedPolytope) -> LiftedPolytope:
    r"""The lifted polytope with each friction pyramid's edge weights replaced by its force.

    For a contact with more generators than dimensions (an F-point in space) every row
    sees the contact only through :math:`f = E \lambda`, so the assembly's columns of
    :math:`\lambda` are ``M E``; they become the d columns ``M = A_lam E^+`` of ``f``,
    and :math:`\lambda \ge 0` becomes the pyramid's facets :math:`V f \le 0` (eq. 24):
    the paper's variables, fewer and better suited to vertex enumeration. The map
    :math:`\lambda \mapsto f` is onto the pyramid, so the projection is unchanged.
    (``assembly.blocks`` then no longer index the columns.)
    """
    asm = poly.assembly
    a = poly.A.toarray()
    n_x = poly.twist_cols.start
    keep = np.ones(a.shape[1], dtype=bool)
    f_cols: list[NDArray[np.float64]] = []
    cones: list[NDArray[np.float64]] = []
    for i in range(asm.copies):
        lam0 = asm.blocks[f"lam[{i}]"].start
        for gens, sl in zip(asm.generators, asm.generator_slices):
            if gens.shape[1] <= gens.shape[0] or np.linalg.matrix_rank(gens) < gens.shape[0]:
                continue
            cols = np.arange(lam0 + sl.start, lam0 + sl.stop)
            keep[cols] = False
            f_cols.append(a[:, cols] @ np.linalg.pinv(gens))
            cones.append(_cone_facets(gens))
    if not f_cols:
        return poly
    n_f = sum(c.shape[1] for c in f_cols)
    x_keep = np.flatnonzero(keep[:n_x])
    top = np.hstack([a[:, x_keep], *f_cols, a[:, poly.twist_cols]])
    top[np.abs(top) <= DROP_TOL] = 0.0  # round-off of the pseudo-inverse
    facets = sp.block_diag(cones).toarray()
    n_k, n_z = len(x_keep), a.shape[1] - n_x
    bottom = np.hstack([np.zeros((len(facets), n_k)), facets, np.zeros((len(facets), n_z))])
    free = np.full(n_f, np.inf)
    return replace(
        poly,
        A=sp.csc_matrix(np.vstack([top, bottom])),
        row_lower=np.concatenate([poly.row_lower, np.zeros(len(facets))]),
        row_upper=np.concatenate([poly.row_upper, np.full(len(facets), np.inf)]),
        col_lower=np.concatenate([poly.col_lower[x_keep], -free, poly.col_lower[poly.twist_cols]]),
        col_upper=np.concatenate([poly.col_upper[x_keep], free, poly.col_upper[poly.twist_cols]]),
        twist_cols=slice(n_k + n_f, n_k + n_f + n_z),
    )


def _solve_equalities(
    poly: LiftedPolytope, tol: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]] | None:
    r"""``y = y0 + N t`` solving the equalities (``N``: orthonormal null-space basis) and the
    inequalities as cddlib rows ``[c, g]`` (``c + g t >= 0``, normalised); ``None`` when
    infeasible. Case 1 goes from 31 variables to 8."""
    from scipy.linalg import null_space

    a = poly.A.toarray()
    n = a.shape[1]
    eq = np.isfinite(poly.row_lower) & (poly.row_lower == poly.row_upper)
    up, lo = np.isfinite(poly.row_upper) & ~eq, np.isfinite(poly.row_lower) & ~eq
    cu, cl = np.isfinite(poly.col_upper), np.isfinite(poly.col_lower)
    c = np.concatenate([poly.row_upper[up], -poly.row_lower[lo], poly.col_upper[cu], -poly.col_lower[cl]])
    g = np.vstack([-a[up], a[lo], -np.eye(n)[cu], np.eye(n)[cl]])
    y0, null = np.zeros(n), np.eye(n)
    if eq.any():
        y0 = np.linalg.lstsq(a[eq], poly.row_upper[eq], rcond=None)[0]
        if np.max(np.abs(a[eq] @ y0 - poly.row_upper[eq])) > tol * max(1.0, float(np.max(np.abs(a[eq])))):
            return None
        null = null_space(a[eq])
    c, g = c + g @ y0, g @ null
    norm = np.max(np.abs(g), axis=1, initial=0.0)
    zero = norm <= 1e-12 * max(1.0, float(np.max(norm, initial=0.0)))
    if np.any(c[zero] < -tol):
        return None
    return y0, null, np.column_stack([c[~zero], g[~zero]]) / norm[~zero, None]


def _cdd_worker(conn: Any, rows: NDArray[np.float64]) -> None:
    """Child process: cddlib's generators ``[1, t]`` (vertices) and ``[0, r]`` (rays).

    Float cddlib can return points that break its own input by orders of magnitude on
    these degenerate polytopes, depending on the order it adds the rows in; so every
    answer is checked against the rows, and the next order tried when it fails.
    """
    try:
        import cdd

        mat = cdd.matrix_from_array(rows.tolist(), rep_type=cdd.RepType.INEQUALITY)
        orders = (None, cdd.RowOrderType.MAX_INDEX, cdd.RowOrderType.RANDOM_ROW, cdd.RowOrderType.MIN_INDEX)
        for order in orders:
            gen = cdd.copy_generators(cdd.polyhedron_from_matrix(mat, row_order=order))
            out = np.array(gen.array, dtype=float).reshape(-1, rows.shape[1])
            # A "vertex" 1e10 times farther than its homogenising 1 is a ray gone astray.
            out[np.abs(out[:, 0]) <= 1e-10 * np.max(np.abs(out[:, 1:]), axis=1, initial=0.0), 0] = 0.0
            vertex = out[:, 0] != 0.0
            t = out[vertex, 1:] / out[vertex, :1]
            rays = out[~vertex, 1:] / np.max(np.abs(out[~vertex, 1:]), axis=1, keepdims=True)
            if np.all(
                rows[:, 1:] @ t.T + rows[:, :1] >= -1e-9 * (1.0 + np.abs(t).max(axis=1, initial=0.0))
            ) and np.all(rows[:, 1:] @ rays.T >= -1e-9):
                conn.send(("ok", out))
                break
        else:
            conn.send(("error", "numerically inconsistent vertices for every row order"))
    except Exception as e:  # reported to the parent as a SolverError
        conn.send(("error", str(e).strip()))
    conn.close()


def _run_cdd(rows: NDArray[np.float64], time_limit: float) -> NDArray[np.float64] | None:
    """:func:`_cdd_worker` in a child process; ``None`` after ``time_limit`` seconds."""
    methods = multiprocessing.get_all_start_methods()
    ctx: Any = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_cdd_worker, args=(send, rows), daemon=True)
    proc.start()
    send.close()
    try:
        if not recv.poll(time_limit):
            proc.kill()
            return None
        status, out = recv.recv()
    except EOFError as e:
        raise SolverError("cdd", f"the cddlib process died (exit code {proc.exitcode})") from e
    finally:
        proc.join(timeout=5.0)
        recv.close()
    if status != "ok":
        raise SolverError("cdd", out)
    return np.asarray(out)


def project_cdd(
    poly: LiftedPolytope,
    *,
    metric: NDArray[np.float64] | None = None,
    time_limit: float = 120.0,
    rel_tol: float = CDD_REL_TOL,
) -> Projection:
    r"""Projection by vertex enumeration of the lifted polytope (the paper's way, eq. 27).

    cddlib (float) enumerates the vertices and rays of :func:`force_form` with its
    equalities solved; the vertices are mapped to twists and reduced to the vertices of
    their hull (:func:`~mjtvm.projection.reduce_points`); a ray with a non-zero twist makes
    :math:`S_{ov}` unbounded. Status ``"timeout"`` after ``time_limit`` seconds.
    """
    t0 = time.perf_counter()
    big_d = poly.twist_dim
    w = np.ones(big_d) if metric is None else np.asarray(metric, dtype=float)
    empty = np.zeros((0, big_d))

    def result(
        status: ProjectionStatus,
        verts: NDArray[np.float64] = empty,
        basis: NDArray[np.float64] | None = None,
        ray: NDArray[np.float64] | None = None,
        lifted: int | None = None,
    ) -> Projection:
        k = {"empty": -1, "bounded": None if basis is None else basis.shape[0]}.get(status)
        return Projection(status, verts, k, basis, w, ray, 0, time.perf_counter() - t0, "cdd", lifted)

    ff = force_form(poly)
    reduced = _solve_equalities(ff, 1e-9)
    if reduced is None:
        return result("empty", lifted=0)
    y0, null, rows = reduced
    gens = _run_cdd(rows, time_limit) if null.shape[1] else np.ones((1, 1))
    if gens is None:
        return result("timeout")
    is_vertex = gens[:, 0] != 0.0
    if not np.any(is_vertex):
        return result("empty", lifted=0)
    lifted = int(is_vertex.sum())
    for r in gens[~is_vertex, 1:]:  # rays (the reduced polyhedron is pointed: no lines)
        d = ff.twist(null @ r)
        if np.linalg.norm(w * d) > rel_tol * float(np.max(np.abs(r))):
            return result("unbounded", ray=d / np.linalg.norm(d), lifted=lifted)
    verts = w * ff.twist(y0 + (gens[is_vertex, 1:] / gens[is_vertex, :1]) @ null.T)
    v, basis = reduce_points(verts, rel_tol=rel_tol)
    return result("bounded", v / w, basis, lifted=lifted)


# ------------------------------------------------------------------ result and volumes
@dataclass(frozen=True)
class TvmsTimings:
    """Wall-clock seconds: assembling, projecting, measuring, in all; LPs solved."""

    assemble_s: float
    project_s: float
    volume_s: float
    total_s: float
    num_lps: int


@dataclass(frozen=True, eq=False)
class TvmsResult:
    r"""Result of Problem 1 for one state (the ``mjtvm.tvms/1`` document).

    Attributes
    ----------
    status
        ``"bounded"``, ``"unbounded"``, ``"empty"`` (some REFS vertex cannot be balanced)
        or ``"timeout"`` (``method="cdd"`` only).
    bounded
        False when unbounded; ``None`` on timeout.
    dimension
        Dimension of the affine hull of :math:`S_{ov}` (-1 when empty, ``None`` unknown).
    vertices
        ``(n, D)`` the vertices of :math:`S_{ov}`: [v of p_O (m/s); omega (rad/s)]; ``(0, D)``
        unless bounded.
    volume
        D-dimensional volume (TVMM, eq. 29; m^3 rad^3 / s^6 in space), 0 when
        ``dimension < D``; ``None`` unless bounded or empty.
    scale
        ``(D,)`` the factors applied to the twist before measuring ``affine_volume``.
    affine_volume
        Volume inside the affine hull of the scaled :math:`S_{ov}` (``dimension``-dimensional;
        0 for a point or the empty set); ``None`` unless bounded or empty.
    unbounded_direction
        ``(D,)`` a unit twist along which :math:`S_{ov}` is unbounded, or ``None``.
    method, rvds_cone
        The projection (``"lp"`` or ``"cdd"``) and whether the RVDS cone restricted it.
    timings
        :class:`TvmsTimings`.
    lifted_vertices
        Number of vertices of the lifted polytope (``"cdd"`` only).
    """

    status: ProjectionStatus
    bounded: bool | None
    dimension: int | None
    vertices: NDArray[np.float64]
    volume: float | None
    scale: NDArray[np.float64]
    affine_volume: float | None
    unbounded_direction: NDArray[np.float64] | None
    method: Method
    rvds_cone: bool
    timings: TvmsTimings
    lifted_vertices: int | None = None

    def to_dict(self) -> dict[str, Any]:
        """The ``mjtvm.tvms/1`` document; extra keys follow the schema's own."""
        return {
            "schema": TVMS_SCHEMA,
            "bounded": self.bounded,
            "dimension": self.dimension,
            "vertices": _json(self.vertices),
            "volume": self.volume,
            "scale": _json(self.scale),
            "affine_volume": self.affine_volume,
            "status": self.status,
            "feasible": self.status != "empty",
            "unbounded_direction": None
            if self.unbounded_direction is None
            else _json(self.unbounded_direction),
            "method": self.method,
            "rvds_cone": self.rvds_cone,
            "lifted_vertices": self.lifted_vertices,
            "timings": {
                "assemble_s": self.timings.assemble_s,
                "project_s": self.timings.project_s,
                "volume_s": self.timings.volume_s,
                "total_s": self.timings.total_s,
                "num_lps": self.timings.num_lps,
            },
        }


def default_scale(state: GraspState) -> NDArray[np.float64]:
    """``(D,)`` 1 / :data:`CHARACTERISTIC_LENGTH` on the linear part, 1 on the angular part."""
    return np.concatenate(
        [np.full(state.dim, 1.0 / CHARACTERISTIC_LENGTH), np.ones(state.twist_dim - state.dim)]
    )


def _check_scale(scale: ArrayLike, big_d: int) -> NDArray[np.float64]:
    try:
        s = np.array(scale, dtype=float).reshape(-1)
    except (TypeError, ValueError) as e:
        raise StateError("scale", f"expected {big_d} positive numbers", scale) from e
    if s.shape != (big_d,) or not np.all(np.isfinite(s)) or np.any(s <= 0.0):
        raise StateError("scale", f"expected {big_d} positive finite numbers", scale)
    return s


def _hull_volume(points: NDArray[np.float64]) -> float:
    """Volume of the hull of ``(n, k)`` full-dimensional points, k >= 2 (joggled if Qhull needs it)."""
    try:
        return float(ConvexHull(points).volume)
    except QhullError:
        return float(ConvexHull(points, qhull_options="QJ").volume)


def _volumes(
    vertices: NDArray[np.float64], dimension: int, scale: NDArray[np.float64]
) -> tuple[float, float]:
    """The D-dimensional volume and the scaled volume inside the affine hull (eq. 28-29)."""
    big_d = vertices.shape[1]
    if dimension <= 0:
        return 0.0, 0.0
    volume = _hull_volume(vertices) if dimension == big_d else 0.0
    scaled = vertices * scale
    basis = np.linalg.svd(scaled - scaled.mean(axis=0), full_matrices=False)[2][:dimension]
    local = scaled @ basis.T
    if dimension == 1:
        return volume, float(np.ptp(local))
    return volume, _hull_volume(local)


def tvms(
    state: GraspState,
    *,
    method: Method = "lp",
    scale: ArrayLike | None = None,
    rvds_cone: bool = True,
    box: BoxForm = "eliminated",
    time_limit: float = 120.0,
) -> TvmsResult:
    r"""Solve Problem 1 (eq. 26-29, 34): the TVMS of ``state`` and its volume (TVMM).

    Parameters
    ----------
    state
        The grasp state; all its REFS vertices are balanced at once, with one common
        :math:`\dot q` and box.
    method
        ``"lp"`` (support LPs, :func:`~mjtvm.projection.project_lp`, default) or ``"cdd"``
        (vertex enumeration of the lifted polytope, :func:`project_cdd`).
    scale
        ``(D,)`` positive factors for ``affine_volume`` (default :func:`default_scale`:
        diag(10, 10, 10, 1, 1, 1) in space). They also scale the working coordinates of
        the projection, whose tolerances are relative.
    rvds_cone
        Restrict :math:`S_{ov}` to the cone generated by ``state.rvds`` when the state has
        an RVDS (the schema's reading of Problem 1); no restriction without RVDS.
    box
        ``"eliminated"`` (default) or ``"literal"`` (eq. 2's box variables).
    time_limit
        Seconds after which ``method="cdd"`` gives up (status ``"timeout"``).

    Raises
    ------
    StateError
        A malformed ``scale``.
    SolverError
        When HiGHS, Qhull or cddlib fails.
    """
    if method not in ("lp", "cdd"):
        raise ValueError(f"method: expected 'lp' or 'cdd', got {method!r}")
    weights = default_scale(state) if scale is None else _check_scale(scale, state.twist_dim)
    t0 = time.perf_counter()
    poly = lifted_polytope(state, rvds_cone=rvds_cone, box=box)
    t1 = time.perf_counter()
    if method == "lp":
        proj = project_lp(poly, metric=weights)
    else:
        proj = project_cdd(poly, metric=weights, time_limit=time_limit)
    t2 = time.perf_counter()
    volume: float | None = None
    affine: float | None = None
    if proj.status == "empty":
        volume, affine = 0.0, 0.0
    elif proj.status == "bounded" and proj.dimension is not None:
        volume, affine = _volumes(proj.vertices, proj.dimension, weights)
    t3 = time.perf_counter()
    return TvmsResult(
        status=proj.status,
        bounded=None if proj.status == "timeout" else proj.status != "unbounded",
        dimension=proj.dimension,
        vertices=proj.vertices,
        volume=volume,
        scale=weights,
        affine_volume=affine,
        unbounded_direction=proj.unbounded_direction,
        method=method,
        rvds_cone=poly.cone,
        timings=TvmsTimings(t1 - t0, t2 - t1, t3 - t2, t3 - t0, proj.num_lps),
        lifted_vertices=proj.lifted_vertices,
    )
