r"""A randomized volume of the TVMS with a confidence interval, inside the certified bracket.

When the certified bracket [vol(I), vol(O)] of [`refine`][mjtvm.polytopes.refine] stays wider than
the tolerance (a 6-D TVMS with hundreds of thousands of vertices: every round of cutting planes
multiplies O's vertices, and I's hull grows as fast), the volume is estimated by Monte Carlo:

* points uniform in O, drawn exactly from its face lattice
  ([`sample()`][mjtvm.polytopes.lattice.FaceLattice.sample]; no Markov chain, no burn-in);
* each classified in or out of $S_{ov}$ exactly: out if it breaks a supporting
  hyperplane already found, else by the ray-shooting LP from the centre
  ([`RayShooter`][mjtvm.polytopes.oracles.RayShooter]: in when the ray reaches it, to ``10 tol``;
  otherwise the LP's supporting hyperplane joins the list);
* $\mathrm{vol}(S_{ov}) = \mathrm{vol}(O)\, p$, ``p`` the fraction of O in
  $S_{ov}$, with the exact (Clopper-Pearson) binomial interval of ``p``.

The sample grows in doubling batches (1024, 2048, ...) until the interval's relative width
``(upper - lower) / upper`` is at most the tolerance. Where O is much larger than
$S_{ov}$ (fewer than half of a batch's points inside), the hyperplanes found cut O down
first and the sampling starts again in the smaller O. Looking after every batch would spend
the confidence more than once: look ``j`` (from 0) uses the level
$1 - \alpha / ((j + 1)(j + 2))$ (``alpha = 1 - confidence``), whose misses sum to at most
``alpha`` over all looks (a union bound), so the interval reported holds with probability at
least ``confidence`` whenever the sampling stops. The interval is intersected with the certified
bracket. Unlike the bracket it is a statistical statement, and it is reported apart from it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError
from mjtvm.polytopes.budget import Budget, LimitReached
from mjtvm.polytopes.lattice import FaceLattice

__all__ = ["FIRST_BATCH", "MIN_INSIDE", "VolumeEstimate", "clopper_pearson", "estimate_volume"]

FIRST_BATCH = 1024  #: points in the first batch; each next batch doubles the sample
MIN_INSIDE = 0.5  #: below this fraction of points inside, O is cut down by the hyperplanes found


@dataclass(frozen=True)
class VolumeEstimate:
    """A randomized volume (scaled units, as the bracket's) and its confidence interval.

    Attributes
    ----------
    value
        ``vol(O) * inside / samples``.
    lower, upper
        The interval, within the certified bracket.
    confidence
        Probability (at least) that the interval holds the volume.
    samples, inside
        Points drawn uniformly in O, and those in the TVMS.
    lps
        Ray-shooting LPs solved (the other points broke a hyperplane already found).
    seconds
        Wall time of the sampling.
    stopped_by
        ``"tolerance"`` (the interval is narrow enough), ``"time"`` or ``"memory"``.
    outer
        The certified outer volume after the sampling (lower than the bracket's when O was cut
        down on the way).
    """

    value: float
    lower: float
    upper: float
    confidence: float
    samples: int
    inside: int
    lps: int
    seconds: float
    stopped_by: str
    outer: float = np.inf

    def __post_init__(self) -> None:
        if not (0.0 < self.confidence < 1.0):
            raise ParamError(
                "confidence", f"expected a number in (0, 1), got {self.confidence!r}", self.confidence
            )

    @property
    def width(self) -> float:
        """``(upper - lower) / upper`` (0 when both are 0)."""
        return (self.upper - self.lower) / self.upper if self.upper > 0 else 0.0


def clopper_pearson(inside: int, samples: int, alpha: float) -> tuple[float, float]:
    """The exact two-sided binomial interval of ``p`` at level ``1 - alpha`` (Clopper and Pearson, 1934)."""
    from scipy.stats import beta  # imported when needed: 0.3 s

    lo = 0.0 if inside == 0 else float(beta.ppf(alpha / 2, inside, samples - inside + 1))
    hi = 1.0 if inside == samples else float(beta.ppf(1 - alpha / 2, inside + 1, samples - inside))
    return lo, hi


class _Classifier:
    """Points in or out of $S_{ov}$: the hyperplanes found, then the ray-shooting LP."""

    def __init__(
        self,
        shoot: Callable[[NDArray[np.float64]], tuple[float, NDArray[np.float64]]],
        center: NDArray[np.float64],
        tol: float,
    ) -> None:
        self.shoot, self.center, self.tol = shoot, center, tol
        self.normals = np.zeros((64, len(center)))
        self.offsets = np.zeros(64)
        self.count = 0
        self.lps = 0

    def _cut(self, a: NDArray[np.float64], b: float) -> None:
        if self.count == len(self.offsets):
            self.normals = np.vstack([self.normals, np.zeros_like(self.normals)])
            self.offsets = np.concatenate([self.offsets, np.zeros_like(self.offsets)])
        self.normals[self.count], self.offsets[self.count] = a, b
        self.count += 1

    def __call__(self, x: NDArray[np.float64]) -> bool:
        n = self.count
        if n and np.any(self.normals[:n] @ x > self.offsets[:n] + self.tol):
            return False
        d = x - self.center
        t, a = self.shoot(d)
        self.lps += 1
        if (1.0 - t) * float(np.linalg.norm(d)) <= 10 * self.tol:
            return True
        # The LP's hyperplane supports S_ov where the ray leaves it: max_S a^T s = a^T (c + t d).
        self._cut(a, float(a @ (self.center + t * d)))
        return False


def estimate_volume(
    lattice: FaceLattice,
    shoot: Callable[[NDArray[np.float64]], tuple[float, NDArray[np.float64]]],
    center: NDArray[np.float64],
    tol: float,
    bracket: tuple[float, float],
    budget: Budget,
    *,
    tolerance: float,
    confidence: float,
    order: Callable[[NDArray[np.float64]], NDArray[np.int64]] | None = None,
    seed: int = 0,
    progress: Callable[[dict[str, Any]], None] | None = None,
    tighten: Callable[[NDArray[np.float64], NDArray[np.float64]], tuple[float, FaceLattice] | None]
    | None = None,
) -> VolumeEstimate:
    r"""Estimate $\mathrm{vol}(S_{ov})$ by uniform points in O (module docstring).

    Parameters
    ----------
    lattice
        O's face lattice (its ``volume`` and sampler), scaled coordinates of dimension ``k``.
    shoot
        ``shoot(d) -> (t, a)``: the ray-shooting LP from ``center`` along ``d`` (``t`` in
        [0, 1], ``a`` the unit normal of a hyperplane supporting $S_{ov}$ at ``center + t d``).
    center, tol
        ``(k,)`` the point the rays start from (inside $S_{ov}$), and the tolerance of
        the projection (absolute, scaled units).
    bracket
        The certified ``(inner, outer)`` volumes: the interval is clipped to them.
    budget
        Its time limit and memory budget stop the sampling (checked every 64 points).
    tolerance
        Stop when ``(upper - lower) / upper`` is at most this.
    confidence
        In (0, 1): the probability that the interval holds the volume.
    order
        ``order(points) -> permutation``: the order of each batch's LPs (neighbours together
        warm-start each other, see `_chain()`).
    seed
        Of the random points (the estimate is reproducible).
    progress
        Called after each batch with ``phase: "estimate"``, ``samples``, ``lower``, ``upper``
        and ``width``.
    tighten
        ``tighten(normals, offsets) -> (outer volume, lattice)``: O with the hyperplanes
        ``normals @ u <= offsets`` added (``None`` when that would cost too much: the sampling
        then goes on in the O it has). Called when fewer than [`MIN_INSIDE`][mjtvm.polytopes.estimate.MIN_INSIDE] of the
        points of a batch are inside (then the sampling starts again in the smaller O, and the
        certified bracket's outer volume comes down with it: `VolumeEstimate.outer`).
    """
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    classify = _Classifier(shoot, center, tol)
    alpha = 1.0 - confidence
    volume = lattice.volume
    samples = inside = look = lps = 0
    batch = FIRST_BATCH
    stopped = "tolerance"
    lower, upper = bracket
    while True:
        points = lattice.sample(batch, rng)
        if order is not None:
            points = points[order(points)]
        try:
            for i, x in enumerate(points):
                if i % 64 == 63:
                    budget.check()
                inside += classify(x)
                samples += 1
        except LimitReached as e:
            stopped = e.reason
        if samples:
            lo, hi = clopper_pearson(inside, samples, alpha / ((look + 1) * (look + 2)))
            lower, upper = max(volume * lo, bracket[0]), min(volume * hi, bracket[1])
            look += 1
            if progress is not None:
                width = (upper - lower) / upper if upper > 0 else 0.0
                progress(
                    {"phase": "estimate", "samples": samples, "lower": lower, "upper": upper, "width": width}
                )
        if stopped != "tolerance" or (upper > 0 and (upper - lower) / upper <= tolerance):
            break
        if tighten is not None and classify.count and inside < samples * MIN_INSIDE:
            # Most points fall outside: O is loose. The hyperplanes found cut it down (a new,
            # smaller lattice), and the sampling starts again; the looks go on counting, so the
            # union bound still covers every interval (each from points drawn after the cut).
            try:
                budget.check()
                smaller = tighten(classify.normals[: classify.count], classify.offsets[: classify.count])
            except LimitReached as e:
                stopped = e.reason
                break
            if smaller is None:  # too costly now: go on sampling the O there is
                tighten = None
                batch = samples
                continue
            volume, lattice = smaller
            bracket = (bracket[0], min(bracket[1], volume))
            lps += classify.lps
            classify = _Classifier(shoot, center, tol)
            samples = inside = 0
            batch = FIRST_BATCH
            continue
        batch = samples  # the sample doubles
    value = volume * inside / samples if samples else 0.5 * (bracket[0] + bracket[1])
    return VolumeEstimate(
        value=min(max(value, lower), upper),
        lower=lower,
        upper=upper,
        confidence=confidence,
        samples=samples,
        inside=inside,
        lps=lps + classify.lps,
        seconds=time.perf_counter() - start,
        stopped_by=stopped,
        outer=bracket[1],
    )
