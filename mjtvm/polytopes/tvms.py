r"""Problem 1: the TVMS $S_{ov}$ and the TVMM (eq. 26-29, 34), solved by [`tvms()`][mjtvm.polytopes.tvms.tvms].

When no force binds ([`speed_box`][mjtvm.polytopes.speed_box]: no wrench to balance, gravity
torques that leave every joint its full speed, F and L contacts, a twist subspace),
$S_{ov}$ is the image of the joint-speed box, a zonotope, computed directly without an
LP (``method="auto"``, the default). Otherwise [`tvms()`][mjtvm.polytopes.tvms.tvms] builds the lifted polytope
(`lifted_polytope()`),
projects it onto the twist space (`project_lp()`, or the paper's
vertex enumeration `project_cdd()` as the baseline) and measures
it: the D-dimensional volume (eq. 28-29, by Qhull), 0 unless $S_{ov}$ is full-dimensional,
and the volume inside its affine hull after scaling the twist by ``scale`` (the paper's
Case 1 figure: diag(10, 10, 10, 1, 1, 1), 1 / 0.1 m on the linear part).

The baseline, like the paper, enumerates the lifted polytope's vertices with cddlib
(`mjtvm.polytopes.enumeration`). The result, the ``mjtvm.tvms/1`` document, is a
[`TvmsResult`][mjtvm.polytopes.tvms_result.TvmsResult] (`mjtvm.polytopes.tvms_result`; its names are importable here too).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import ParamError
from mjtvm.model.state import GraspState
from mjtvm.polytopes.bracket import ray_lengths
from mjtvm.polytopes.budget import DEFAULT_CONFIDENCE, Limits
from mjtvm.polytopes.enumeration import project_cdd
from mjtvm.polytopes.lifted import Projection, lifted_polytope
from mjtvm.polytopes.projection import REL_TOL, project_lp
from mjtvm.polytopes.speed_box import BoxImage, ray_lengths_in, speed_box_projection
from mjtvm.polytopes.tvms_result import (
    CHARACTERISTIC_LENGTH,
    TVMS_SCHEMA,
    TvmsResult,
    TvmsTimings,
    d_volume,
    default_scale,
)
from mjtvm.polytopes.volume import facet_volume, hull_volume
from mjtvm.problem2.assembly import BoxForm

__all__ = [
    "CHARACTERISTIC_LENGTH",
    "DEFAULT_CONFIDENCE",
    "TVMS_SCHEMA",
    "TvmsResult",
    "TvmsTimings",
    "default_scale",
    "tvms",
]

Method = Literal["auto", "lp", "cdd", "zonotope"]
Facets = tuple[NDArray[np.float64], NDArray[np.float64]]


def _check_scale(scale: ArrayLike, big_d: int) -> NDArray[np.float64]:
    try:
        s = np.array(scale, dtype=float).reshape(-1)
    except (TypeError, ValueError) as e:
        raise ParamError("scale", f"expected {big_d} positive numbers", scale) from e
    if s.shape != (big_d,) or not np.all(np.isfinite(s)) or np.any(s <= 0.0):
        raise ParamError("scale", f"expected {big_d} positive finite numbers", scale)
    return s


def _volumes(
    vertices: NDArray[np.float64],
    dimension: int,
    scale: NDArray[np.float64],
    facets: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> tuple[float, float]:
    """The D-dimensional volume and the scaled volume inside the affine hull (eq. 28-29).

    Both come from one measurement in the scaled coordinates: the D-volume is the scaled
    one divided by the product of ``scale`` when the TVMS is full-dimensional, else 0.
    With the projection's ``facets`` it is a sum of pyramids ([`facet_volume()`][mjtvm.polytopes.volume.facet_volume]),
    otherwise one Qhull hull of the vertices ([`hull_volume()`][mjtvm.polytopes.volume.hull_volume]).
    """
    if dimension <= 0:
        return 0.0, 0.0
    scaled = vertices * scale
    basis = np.linalg.svd(scaled - scaled.mean(axis=0), full_matrices=False)[2][:dimension]
    local = scaled @ basis.T
    if dimension == 1:
        affine = float(np.ptp(local))
    elif facets is not None and dimension > 3:
        # In 2-D and 3-D one Qhull hull of the vertices is cheap and exact; the pyramids over
        # the facets lost 1.5e-3 on the Allegro grasp's 3-D TVMS (facets at ~1e-5 rad whose
        # shared region the band of 10 tol assigns to the wrong one: found by the bracket).
        rows = (facets[0] / scale) @ basis.T  # n^T rdot <= o  ->  (basis (n / scale))^T u <= o
        norm = np.linalg.norm(rows, axis=1)
        # The basis spans the TVMS's linear hull (it contains the origin), so u = local.
        tol = REL_TOL * float(np.max(np.abs(local)))
        affine = facet_volume(local, rows / norm[:, None], facets[1] / norm, tol)
    else:
        affine = hull_volume(local)
    return float(d_volume(np.array(affine), dimension, scale)), affine


def _ray_lengths(proj: Projection, rvds: NDArray[np.float64], facets: Facets | None) -> NDArray[np.float64]:
    """``max alpha`` with ``alpha r`` in the polytope ``facets`` (twist coordinates, inside the
    linear hull of the projection) for each row ``r`` of ``rvds``; ``nan`` for a zero row."""
    basis, w = proj.basis, proj.metric
    out = np.full(len(rvds), np.nan)
    if basis is None:
        return out
    for i, r in enumerate(rvds):
        s = w * r
        norm = float(np.linalg.norm(s))
        if norm == 0.0:
            continue
        inside = basis @ s
        if np.linalg.norm(s - basis.T @ inside) > 1e-9 * norm:
            out[i] = 0.0  # leaves the linear hull of S_ov at once
        elif facets is not None:
            out[i] = ray_lengths(facets[0], facets[1], r[None, :])[0]
        else:  # dimension <= 1: the segment between the vertices (or the origin)
            ends = (proj.vertices * w) @ basis.T @ inside / norm**2
            out[i] = max(float(np.max(ends, initial=0.0)), 0.0)
    return out


def _brackets(
    proj: Projection, weights: NDArray[np.float64], volume: float | None, affine: float | None
) -> tuple[Any, Any, float | None]:
    """``(volume_bracket, affine_volume_bracket, hausdorff_gap)`` of a projection."""
    if proj.status == "bounded" and volume is not None and affine is not None:
        return np.array([volume, volume]), np.array([affine, affine]), 0.0
    approx = proj.approximation
    if proj.status != "approximate" or approx is None or proj.dimension is None:
        return None, None, None
    aff = np.array([approx.inner_volume, approx.outer_volume])
    return d_volume(aff, proj.dimension, weights), aff, approx.hausdorff


def _box_image_result(
    state: GraspState, image: BoxImage, weights: NDArray[np.float64], rvds_cone: bool
) -> TvmsResult:
    """The result of [`tvms()`][mjtvm.polytopes.tvms.tvms] from the image of the joint-speed box: exact, its volume by
    Shephard's sum, the alphas from its facets as on the LP path."""
    t0 = time.perf_counter()
    proj = image.projection
    affine = image.affine_volume
    volume = affine / float(np.prod(weights)) if proj.dimension == len(weights) else 0.0  # eq. 29
    alpha = None
    if state.rvds is not None:
        rays = ray_lengths_in(proj, np.asarray(state.rvds, dtype=float))
        alpha = np.stack([rays, rays], axis=1)
    t1 = time.perf_counter()
    return TvmsResult(
        status="bounded",
        bounded=True,
        dimension=proj.dimension,
        vertices=proj.vertices,
        volume=volume,
        scale=weights,
        affine_volume=affine,
        unbounded_direction=None,
        method="zonotope",
        rvds_cone=rvds_cone and state.rvds is not None,
        timings=TvmsTimings(0.0, proj.seconds, t1 - t0, proj.seconds + t1 - t0, 0),
        volume_bracket=np.array([volume, volume]),
        affine_volume_bracket=np.array([affine, affine]),
        hausdorff_gap=0.0,
        alpha_bracket=alpha,
    )


def tvms(
    state: GraspState,
    *,
    method: Method = "auto",
    scale: ArrayLike | None = None,
    rvds_cone: bool = True,
    box: BoxForm = "eliminated",
    time_limit: float | None = 120.0,
    tolerance: float = 0.0,
    memory: int | None = None,
    progress: Callable[[dict[str, Any]], None] | None = None,
    confidence: float = DEFAULT_CONFIDENCE,
) -> TvmsResult:
    r"""Solve Problem 1 (eq. 26-29, 34): the TVMS of ``state`` and its volume (TVMM).

    Parameters
    ----------
    state
        The grasp state; all its REFS vertices are balanced at once, with one common
        $\dot q$ and box.
    method
        ``"lp"`` (support LPs, `project_lp()`), ``"cdd"``
        (vertex enumeration of the lifted polytope,
        `project_cdd()`), ``"zonotope"`` (the image of the
        joint-speed box when no force binds, [`speed_box_projection()`][mjtvm.polytopes.speed_box.speed_box_projection]:
        no LP) or ``"auto"`` (default): ``"zonotope"`` when its condition holds, else ``"lp"``.
    scale
        ``(D,)`` positive factors for ``affine_volume`` (default [`default_scale()`][mjtvm.polytopes.tvms_result.default_scale]:
        diag(10, 10, 10, 1, 1, 1) in space). They also scale the working coordinates of
        the projection, whose tolerances are relative.
    rvds_cone
        Restrict $S_{ov}$ to the cone generated by ``state.rvds`` when the state has
        an RVDS (the schema's reading of Problem 1); no restriction without RVDS.
    box
        ``"eliminated"`` (default) or ``"literal"`` (eq. 2's box variables).
    time_limit
        Seconds of wall-clock time for the projection (``None``: no limit). ``method="cdd"``
        then gives up (status ``"timeout"``, no bracket); ``method="lp"`` stops refining and
        returns status ``"approximate"`` with the brackets.
    tolerance
        ``method="lp"``: stop once the relative volume gap ``(outer - inner) / outer`` of the
        bracket is at most this (default 0: exact within floating point).
    memory
        ``method="lp"``: bytes the projection may add to the process's resident set (default
        `default_memory_budget()`, a quarter of the available
        memory); reaching it gives status ``"approximate"``.
    progress
        ``method="lp"``: called with the bracket (a dict, see
        `Limits`) whenever it is measured (which it then is
        between rounds, at most half of the time), and with the estimate's interval.
    confidence
        ``method="lp"`` with a ``tolerance``: if the certified bracket is still wider than
        the tolerance when the cutting planes stop (at half of ``time_limit``, or by the
        memory budget), the volume is estimated by uniform points in the outer polytope and
        LPs (`estimate_volume()`) until its interval, which
        holds the volume with this probability, is that narrow or the time is up
        (`TvmsResult.volume_estimate`). 0: no estimate (the cutting planes then have
        all the time).

    Raises
    ------
    ParamError
        A malformed ``scale``, an unknown ``method``, or ``method="zonotope"`` where forces
        bind (the message says which condition fails).
    SolverError
        When HiGHS, Qhull or cddlib fails.
    """
    if method not in ("auto", "lp", "cdd", "zonotope"):
        raise ParamError("method", f"expected 'auto', 'lp', 'cdd' or 'zonotope', got {method!r}", method)
    weights = default_scale(state) if scale is None else _check_scale(scale, state.twist_dim)
    t0 = time.perf_counter()  # the condition's check counts as assembling when it fails
    if method in ("auto", "zonotope"):
        image, why = speed_box_projection(state, weights, rvds_cone)
        if image is not None:
            return _box_image_result(state, image, weights, rvds_cone)
        if method == "zonotope":
            raise ParamError("method", f"expected a state whose forces cannot bind for 'zonotope': {why}")
    poly = lifted_polytope(state, rvds_cone=rvds_cone, box=box)
    t1 = time.perf_counter()
    if method in ("auto", "lp"):
        limits = Limits(
            tolerance=tolerance,
            time_limit=time_limit,
            memory=memory,
            progress=progress,
            confidence=confidence,
        )
        proj = project_lp(poly, metric=weights, limits=limits)
    else:
        proj = project_cdd(poly, metric=weights, time_limit=1e9 if time_limit is None else time_limit)
    t2 = time.perf_counter()
    volume: float | None = None
    affine: float | None = None
    if proj.status == "empty":
        volume, affine = 0.0, 0.0
    elif proj.status == "bounded" and proj.dimension is not None:
        volume, affine = _volumes(proj.vertices, proj.dimension, weights, proj.facets)
    vol_b, aff_b, gap = _brackets(proj, weights, volume, affine)
    alpha = None
    if state.rvds is not None and proj.status in ("bounded", "approximate"):
        approx = proj.approximation
        inner = approx.inner_facets if approx is not None else proj.facets
        outer = approx.outer_facets if approx is not None else proj.facets
        rv = np.asarray(state.rvds, dtype=float)
        alpha = np.column_stack([_ray_lengths(proj, rv, inner), _ray_lengths(proj, rv, outer)])
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
        method="cdd" if method == "cdd" else "lp",
        rvds_cone=poly.cone,
        timings=TvmsTimings(t1 - t0, t2 - t1, t3 - t2, t3 - t0, proj.num_lps),
        lifted_vertices=proj.lifted_vertices,
        volume_bracket=vol_b,
        affine_volume_bracket=aff_b,
        hausdorff_gap=gap,
        alpha_bracket=alpha,
        stopped_by=None
        if proj.approximation is None
        else (proj.approximation.reason, proj.approximation.detail),
        volume_estimate=None if proj.approximation is None else proj.approximation.estimate,
    )
