r"""The paper's projection, the baseline of Problem 1: vertex enumeration with cddlib (eq. 27).

The lifted polytope's H-representation is turned into its vertices with cddlib, in the
paper's variables ([`force_form()`][mjtvm.polytopes.enumeration.force_form]) and with the equalities solved first; the vertices
are mapped to twists and reduced to the vertices of their hull
([`reduce_points()`][mjtvm.polytopes.hull.reduce_points]). cddlib runs in a child process that is killed after
``time_limit`` seconds, so that a hand the enumeration cannot handle reports
``"timeout"`` instead of hanging.
"""

from __future__ import annotations

import multiprocessing
import time
import warnings
from dataclasses import replace
from typing import Any

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from numpy.typing import NDArray

from mjtvm.errors import SolverError
from mjtvm.lp.solvers import DROP_REL
from mjtvm.polytopes.hull import CDD_REL_TOL, cone_facets, reduce_points
from mjtvm.polytopes.lifted import LiftedPolytope, Projection, ProjectionStatus

__all__ = ["force_form", "project_cdd"]


def force_form(poly: LiftedPolytope) -> LiftedPolytope:
    r"""The lifted polytope with each friction pyramid's edge weights replaced by its force.

    For a contact with more generators than dimensions (an F-point in space) every row
    sees the contact only through $f = E \lambda$, so the assembly's columns of
    $\lambda$ are ``M E``; they become the d columns ``M = A_lam E^+`` of ``f``,
    and $\lambda \ge 0$ becomes the pyramid's facets $V f \le 0$ (eq. 24):
    the paper's variables, fewer and better suited to vertex enumeration. The map
    $\lambda \mapsto f$ is onto the pyramid, so the projection is unchanged.
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
            pinv = np.linalg.pinv(gens)
            f = a[:, cols] @ pinv
            # round-off of the pseudo-inverse: relative to the terms of each entry
            f[np.abs(f) <= DROP_REL * (np.abs(a[:, cols]) @ np.abs(pinv))] = 0.0
            f_cols.append(f)
            cones.append(cone_facets(gens))
    if not f_cols:
        return poly
    n_f = sum(c.shape[1] for c in f_cols)
    top = np.hstack([a[:, np.flatnonzero(keep[:n_x])], *f_cols, a[:, poly.twist_cols]])
    # Float cddlib mis-enumerates with round-off kept (Case 1-S: 34 lifted vertices instead
    # of 68): an entry at most DROP_REL times the largest of its row (a half-space, which
    # cddlib normalises) or of its column (a variable, whatever its unit) is dropped, e.g.
    # the 1e-16 of a unit normal or a generator's cos(pi/2). Unit-invariant, unlike the
    # former absolute 1e-12.
    mag = np.abs(top)
    row_max = np.max(mag, axis=1, keepdims=True, initial=0.0)
    col_max = np.max(mag, axis=0, keepdims=True, initial=0.0)
    top[mag <= DROP_REL * np.maximum(row_max, col_max)] = 0.0
    x_keep = np.flatnonzero(keep[:n_x])
    facets = scipy.linalg.block_diag(*cones)  # dense: cdd takes a dense matrix anyway
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
        failures: list[str] = []
        for order in orders:
            try:
                gen = cdd.copy_generators(cdd.polyhedron_from_matrix(mat, row_order=order))
            except RuntimeError as e:  # "Numerical inconsistency is found": another order may not meet it
                failures.append(str(e).strip())
                continue
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
            failures.append("vertices that break the input rows")
        else:
            conn.send(("error", f"numerically inconsistent for every row order: {'; '.join(failures)}"))
    except Exception as e:  # reported to the parent as a SolverError
        conn.send(("error", str(e).strip()))
    conn.close()


def _run_cdd(rows: NDArray[np.float64], time_limit: float) -> NDArray[np.float64] | None:
    """`_cdd_worker()` in a child process; ``None`` after ``time_limit`` seconds."""
    methods = multiprocessing.get_all_start_methods()
    ctx: Any = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_cdd_worker, args=(send, rows), daemon=True)
    with warnings.catch_warnings():
        # Python >= 3.12 warns about fork() beside other threads (OpenBLAS', rerun's in a test
        # session): the child touches none of their locks, only cddlib, numpy and its pipe.
        warnings.filterwarnings("ignore", "This process .* is multi-threaded", DeprecationWarning)
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

    cddlib (float) enumerates the vertices and rays of [`force_form()`][mjtvm.polytopes.enumeration.force_form] with its
    equalities solved; the vertices are mapped to twists and reduced to the vertices of
    their hull ([`reduce_points()`][mjtvm.polytopes.hull.reduce_points]); a ray with a non-zero twist makes
    $S_{ov}$ unbounded. Status ``"timeout"`` after ``time_limit`` seconds.
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
