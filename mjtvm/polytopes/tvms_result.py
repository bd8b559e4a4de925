r"""The result of Problem 1: [`TvmsResult`][mjtvm.polytopes.tvms_result.TvmsResult], the ``mjtvm.tvms/1`` document.

Also its timings, the default twist scale ([`default_scale()`][mjtvm.polytopes.tvms_result.default_scale])
and the D-dimensional volume of a scaled one ([`d_volume()`][mjtvm.polytopes.tvms_result.d_volume]).
[`tvms()`][mjtvm.polytopes.tvms.tvms] computes the result; ``mjtvm.polytopes.tvms`` imports these names too.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from mjtvm.model.state import GraspState
from mjtvm.polytopes.estimate import VolumeEstimate
from mjtvm.polytopes.lifted import ProjectionStatus
from mjtvm.problem2.tvmmp import finite_floats, finite_or_none

__all__ = ["CHARACTERISTIC_LENGTH", "TVMS_SCHEMA", "TvmsResult", "TvmsTimings", "d_volume", "default_scale"]

TVMS_SCHEMA = "mjtvm.tvms/1"
CHARACTERISTIC_LENGTH = 0.1  #: m: the paper's object radius; linear twist parts are divided by it
Solved = Literal["lp", "cdd", "zonotope"]  #: how a result was computed


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
        ``"bounded"``, ``"approximate"`` (``method="lp"`` stopped by a limit: the brackets
        hold the answer), ``"unbounded"``, ``"empty"`` (some REFS vertex cannot be balanced)
        or ``"timeout"`` (``method="cdd"`` only).
    bounded
        False when unbounded; ``None`` on timeout.
    dimension
        Dimension of the affine hull of $S_{ov}$ (-1 when empty, ``None`` unknown).
    vertices
        ``(n, D)`` the vertices of $S_{ov}$: [v of p_O (m/s); omega (rad/s)]; ``(0, D)``
        unless bounded.
    volume
        D-dimensional volume (TVMM, eq. 29; m^3 rad^3 / s^6 in space), 0 when
        ``dimension < D``; ``None`` unless bounded or empty.
    scale
        ``(D,)`` the factors applied to the twist before measuring ``affine_volume``.
    affine_volume
        Volume inside the affine hull of the scaled $S_{ov}$ (``dimension``-dimensional;
        0 for a point or the empty set); ``None`` unless bounded or empty.
    unbounded_direction
        ``(D,)`` a unit twist along which $S_{ov}$ is unbounded, or ``None``.
    method, rvds_cone
        How $S_{ov}$ was computed (``"lp"``, ``"cdd"``, or ``"zonotope"``: the image of
        the joint-speed box, [`speed_box`][mjtvm.polytopes.speed_box]) and whether the RVDS cone
        restricted it.
    timings
        [`TvmsTimings`][mjtvm.polytopes.tvms_result.TvmsTimings].
    lifted_vertices
        Number of vertices of the lifted polytope (``"cdd"`` only).
    volume_bracket, affine_volume_bracket
        ``(2,)`` [inner, outer]: certified bounds of ``volume`` and ``affine_volume`` (both
        equal to it when exact); ``None`` unless bounded or approximate.
    hausdorff_gap
        Upper bound of the Hausdorff distance between the inner and outer polytopes, in the
        scaled coordinates of ``affine_volume`` (0 when exact); ``None`` unless bounded or
        approximate.
    alpha_bracket
        ``(R, 2)`` [inner, outer] ray lengths along each RVDS vertex ``r_l``: bounds of
        ``max alpha`` with ``alpha r_l`` in $S_{ov}$ (Problem 2's $\alpha_l$ when
        the state has one REFS vertex); a row of ``nan`` for a zero vertex, ``inf`` where the
        ray does not leave. ``None`` without RVDS or unless bounded or approximate.
    stopped_by
        ``None`` when exact; else ``(reason, detail)``: ``"tolerance"``, ``"time"`` or
        ``"memory"`` and one line on it.
    volume_estimate
        The randomized volume (`VolumeEstimate`, in the
        units of ``affine_volume``; statistical, not certified) when the bracket stopped wider
        than the tolerance and a ``confidence`` was asked for; else ``None``.
    """

    status: ProjectionStatus
    bounded: bool | None
    dimension: int | None
    vertices: NDArray[np.float64]
    volume: float | None
    scale: NDArray[np.float64]
    affine_volume: float | None
    unbounded_direction: NDArray[np.float64] | None
    method: Solved
    rvds_cone: bool
    timings: TvmsTimings
    lifted_vertices: int | None = None
    volume_bracket: NDArray[np.float64] | None = None
    affine_volume_bracket: NDArray[np.float64] | None = None
    hausdorff_gap: float | None = None
    alpha_bracket: NDArray[np.float64] | None = None
    stopped_by: tuple[str, str] | None = None
    volume_estimate: VolumeEstimate | None = None

    def _estimate_dict(self) -> dict[str, Any] | None:
        e = self.volume_estimate
        if e is None:
            return None
        lower, value, upper = d_volume(np.array([e.lower, e.value, e.upper]), self.dimension, self.scale)
        return {
            "value": float(value),
            "interval": [float(lower), float(upper)],
            "affine_value": e.value,
            "affine_interval": [e.lower, e.upper],
            "confidence": e.confidence,
            "samples": e.samples,
            "inside": e.inside,
            "lps": e.lps,
            "seconds": e.seconds,
            "stopped_by": e.stopped_by,
        }

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
            "volume_bracket": None if self.volume_bracket is None else finite_floats(self.volume_bracket),
            "affine_volume_bracket": None
            if self.affine_volume_bracket is None
            else finite_floats(self.affine_volume_bracket),
            "hausdorff_gap": finite_or_none(self.hausdorff_gap),
            "alpha_bracket": None if self.alpha_bracket is None else finite_floats(self.alpha_bracket),
            "stopped_by": None
            if self.stopped_by is None
            else {"reason": self.stopped_by[0], "detail": self.stopped_by[1]},
            "volume_estimate": self._estimate_dict(),
            "timings": {
                "assemble_s": self.timings.assemble_s,
                "project_s": self.timings.project_s,
                "volume_s": self.timings.volume_s,
                "total_s": self.timings.total_s,
                "num_lps": self.timings.num_lps,
            },
        }


def default_scale(state: GraspState) -> NDArray[np.float64]:
    """``(D,)`` 1 / `CHARACTERISTIC_LENGTH` on the linear part, 1 on the angular part."""
    return np.concatenate(
        [np.full(state.dim, 1.0 / CHARACTERISTIC_LENGTH), np.ones(state.twist_dim - state.dim)]
    )


def d_volume(
    affine: NDArray[np.float64], dimension: int | None, scale: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The D-dimensional volumes (eq. 29) of volumes measured in the scaled coordinates.

    Parameters
    ----------
    affine
        Volumes inside the affine hull of the TVMS scaled by ``scale``.
    dimension
        Dimension of the TVMS's affine hull (``None``: unknown).
    scale
        ``(D,)`` the factors applied to the twist.

    Returns
    -------
    numpy.ndarray
        ``affine`` divided by the product of ``scale`` when the TVMS is full-dimensional,
        else 0 (same shape as ``affine``).
    """
    return affine / float(np.prod(scale)) if dimension == len(scale) else np.zeros_like(affine)
