r"""Problem 1: the TVMS :math:`S_{ov}` and the TVMM (eq. 26-29, 34), the ``mjtvm.tvms/1`` document.

:func:`tvms` builds the lifted polytope (:func:`~mjtvm.polytopes.lifted.lifted_polytope`),
projects it onto the twist space (:func:`~mjtvm.polytopes.projection.project_lp`, or the paper's
vertex enumeration :func:`~mjtvm.polytopes.enumeration.project_cdd` as the baseline) and measures
it: the D-dimensional volume (eq. 28-29, by Qhull), 0 unless :math:`S_{ov}` is full-dimensional,
and the volume inside its affine hull after scaling the twist by ``scale`` (the paper's
Case 1 figure: diag(10, 10, 10, 1, 1, 1), 1 / 0.1 m on the linear part).

The baseline, like the paper, enumerates the lifted polytope's vertices with cddlib
(:mod:`mjtvm.polytopes.enumeration`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.assembly import BoxForm
from ..core.state import GraspState
from ..core.tvmmp import finite_floats, finite_or_none
from ..errors import StateError
from .enumeration import project_cdd
from .lifted import ProjectionStatus, lifted_polytope
from .projection import REL_TOL, project_lp
from .volume import facet_volume, hull_volume

__all__ = [
    "CHARACTERISTIC_LENGTH",
    "TVMS_SCHEMA",
    "TvmsResult",
    "TvmsTimings",
    "default_scale",
    "tvms",
]

TVMS_SCHEMA = "mjtvm.tvms/1"
CHARACTERISTIC_LENGTH = 0.1  #: m: the paper's object radius; linear twist parts are divided by it
Method = Literal["lp", "cdd"]


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
            "vertices": finite_floats(self.vertices),
            "volume": finite_or_none(self.volume),
            "scale": finite_floats(self.scale),
            "affine_volume": finite_or_none(self.affine_volume),
            "status": self.status,
            "feasible": self.status != "empty",
            "unbounded_direction": None
            if self.unbounded_direction is None
            else finite_floats(self.unbounded_direction),
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


def _volumes(
    vertices: NDArray[np.float64],
    dimension: int,
    scale: NDArray[np.float64],
    facets: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> tuple[float, float]:
    """The D-dimensional volume and the scaled volume inside the affine hull (eq. 28-29).

    Both come from one measurement in the scaled coordinates: the D-volume is the scaled
    one divided by the product of ``scale`` when the TVMS is full-dimensional, else 0.
    With the projection's ``facets`` it is a sum of pyramids (:func:`facet_volume`),
    otherwise one Qhull hull of the vertices (:func:`hull_volume`).
    """
    big_d = vertices.shape[1]
    if dimension <= 0:
        return 0.0, 0.0
    scaled = vertices * scale
    basis = np.linalg.svd(scaled - scaled.mean(axis=0), full_matrices=False)[2][:dimension]
    local = scaled @ basis.T
    if dimension == 1:
        affine = float(np.ptp(local))
    elif facets is not None:
        rows = (facets[0] / scale) @ basis.T  # n^T rdot <= o  ->  (basis (n / scale))^T u <= o
        norm = np.linalg.norm(rows, axis=1)
        # The basis spans the TVMS's linear hull (it contains the origin), so u = local.
        tol = REL_TOL * float(np.max(np.abs(local)))
        affine = facet_volume(local, rows / norm[:, None], facets[1] / norm, tol)
    else:
        affine = hull_volume(local)
    volume = affine / float(np.prod(scale)) if dimension == big_d else 0.0
    return volume, affine


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
        ``"lp"`` (support LPs, :func:`~mjtvm.polytopes.projection.project_lp`, default) or ``"cdd"``
        (vertex enumeration of the lifted polytope,
        :func:`~mjtvm.polytopes.enumeration.project_cdd`).
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
        volume, affine = _volumes(proj.vertices, proj.dimension, weights, proj.facets)
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
