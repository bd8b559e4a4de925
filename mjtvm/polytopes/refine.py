r"""Cutting planes of `project_lp()`, anytime (Problem 1).

[`refine()`][mjtvm.polytopes.refine.refine] keeps an outer polytope O (valid inequalities) and an inner one I (the hull of
points the LPs proved to lie in $S_{ov}$, [`bracket`][mjtvm.polytopes.bracket]) and refines O
until every vertex is certified (then O = $S_{ov}$), or until a limit of
`Limits` stops it: the relative volume gap of the bracket
[vol(I), vol(O)] at most ``tolerance``, the time limit or the memory budget. It then
returns ``status: "approximate"`` with the bracket instead of failing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from mjtvm.errors import SolverError
from mjtvm.polytopes.bracket import Bracket, InnerHull, hausdorff_bound, inner_hull, outer_volume
from mjtvm.polytopes.budget import Budget, LimitReached, Limits
from mjtvm.polytopes.estimate import VolumeEstimate, estimate_volume
from mjtvm.polytopes.hull import polish_vertices
from mjtvm.polytopes.lattice import FaceLattice
from mjtvm.polytopes.lifted import Approximation, Projection
from mjtvm.polytopes.oracles import DistanceOracle, RayShooter, SupportOracle
from mjtvm.polytopes.polar import PolarHull

__all__ = ["GROWTH", "REFINE_SHARE", "Cutter", "Meter", "refine"]

GROWTH = 4.0
"""A round of cuts may take this many times the last one: O's vertices grow so (the Allegro
grasp's 6-D TVMS: rounds of 0.5, 1.5 and 5.8 s with 8k, 41k and 179k vertices); a round that
would end past the deadline is not started (Qhull cannot be interrupted once it runs)."""
INNER_GROWTH = 1.6
"""Qhull's time for the hull of n proven points grows about as n to this power (the Allegro
grasp's 6-D TVMS: 0.30 s for 450 points, 8.3 s for 3795, 58 s for 11,441)."""
REFINE_SHARE = 0.5
"""Of the time limit, for the cutting planes when a randomized estimate may follow (a
``tolerance`` and a ``confidence``); the estimate has the rest."""


class Cutter:
    """The LPs of `_refine()` (ray shooting, support, distance; one HiGHS session each),
    which certify vertices of O or cut them off."""

    def __init__(
        self, support: SupportOracle, basis: NDArray[np.float64], center: NDArray[np.float64], tol: float
    ) -> None:
        self.support, self.basis, self.center, self.tol = support, basis, center, tol
        self.rows = basis @ (support.metric[:, None] * support.poly.generators)
        self.shoot = RayShooter(support.poly, self.rows, center)
        self.nearest: DistanceOracle | None = None  # the distance LP only when needed
        self.found: set[tuple[float, ...]] = set()  # support LP solutions, on a grid of 10 tol
        self.proven: list[NDArray[np.float64]] = []  # points of S_ov met by the LPs (the inner hull)
        self.budget: Budget | None = None
        self.certified: list[NDArray[np.float64]] = []  # of the last settle()
        self.new_n, self.new_b, self.cuts = np.zeros((0, basis.shape[0])), np.zeros(0), 0

    def _cell(self, u: NDArray[np.float64]) -> tuple[float, ...]:
        return tuple(np.round(u / (10 * self.tol)).tolist())

    @property
    def num_lps(self) -> int:
        return self.support.num_lps + self.shoot.num_lps + (self.nearest.num_lps if self.nearest else 0)

    def cut(self, a: NDArray[np.float64]) -> float:
        """The support value $h(a)$ of $S_{ov}$ along ``a`` (local coordinates)."""
        status, s = self.support(self.basis.T @ a)
        if status != "optimal":  # bounded after _linear_hull: a solver fault
            raise SolverError("highs", f"support LP inside a bounded TVMS: {status}")
        self.found.add(self._cell(self.basis @ s))
        self.proven.append(self.basis @ s)
        return float(a @ (self.basis @ s))

    def settle(self, verts: NDArray[np.float64]) -> None:
        """Certify the vertices among ``verts`` (appended to `certified`) or cut them off
        (rows ``(normals, offsets)`` in `new_n`, `new_b`, the first `cuts`).
        A [`LimitReached`][mjtvm.polytopes.budget.LimitReached] from the budget (checked every 32 vertices) leaves both as far as
        they got."""
        k, tol, center = self.basis.shape[0], self.tol, self.center
        certified: list[NDArray[np.float64]] = []
        self.certified = certified
        new_n, new_b = self.new_n, self.new_b = np.zeros((len(verts), k)), np.zeros(len(verts))
        self.cuts = 0
        # What each vertex needs, at once: its grid cell, its ray and that ray's length.
        cells = [tuple(c) for c in np.round(verts / (10 * tol)).tolist()]
        rays = verts - center
        lengths = np.sqrt(np.einsum("ij,ij->i", rays, rays)).tolist()
        for i, v in enumerate(verts):
            cuts = self.cuts
            if self.budget is not None and i % 32 == 31:
                self.budget.check()
            if cuts and float(np.max(new_n[:cuts] @ v - new_b[:cuts])) > tol:
                continue  # cut off by a row of this round already
            if cells[i] in self.found:  # a support LP's solution: a point of S_ov
                certified.append(v)
                continue
            t, a = self.shoot(rays[i])
            self.proven.append(center + t * rays[i])
            if (1.0 - t) * lengths[i] <= 10 * tol:  # as close as distinct() merges
                certified.append(v)
                continue
            b = self.cut(a)
            if a @ v <= b + tol:
                # The ray left S_ov far from v, but v lies within tol of that hyperplane (a ray
                # nearly along a facet, or duals picked at a lower-dimensional face): measure the
                # distance itself and cut with the dual's hyperplane.
                self.nearest = self.nearest or DistanceOracle(self.support.poly, self.rows)
                delta, a = self.nearest(v)
                if delta <= tol:
                    certified.append(v)
                    continue
                b = self.cut(a)
                if a @ v <= b + tol:
                    raise SolverError("highs", "no cutting plane separates a vertex outside the TVMS")
            new_n[cuts], new_b[cuts], self.cuts = a, b, cuts + 1


def _chain(points: NDArray[np.float64], center: NDArray[np.float64]) -> NDArray[np.int64]:
    """An order of ``points`` that keeps neighbours together, so that consecutive LPs
    warm-start from a nearby basis: lexicographic in their directions from ``center``
    rounded to a grid of 1/4 (Case 2's rays: 4.5 simplex iterations instead of 7 in the
    order Qhull gives, 16 in a random one; a greedy nearest-neighbour tour, 3.3, costs
    more in Python than it saves)."""
    d = points - center
    d = np.round(4.0 * d / np.linalg.norm(d, axis=1)[:, None])
    return np.lexsort(d.T[::-1])


@dataclass
class Meter:
    """The bracket's measurements (`measure()`) with the last of each part and its cost.

    A part whose predicted cost does not fit in the time left is not measured again: the last
    inner hull stays valid (I only gains points, an older I is inside the newer), and so does
    the last outer lattice (O only gains rows). The predictions: Qhull's hull of the proven
    points grows as their number to the power [`INNER_GROWTH`][mjtvm.polytopes.refine.INNER_GROWTH], the face lattice linearly
    with the simplices of the polar hull ([`PolarHull.predicted_size()`][mjtvm.polytopes.polar.PolarHull.predicted_size]).
    """

    inner: InnerHull | None = None
    inner_points: int = 0
    inner_s: float = 0.0
    lattice: FaceLattice | None = None
    outer: float = math.inf
    outer_s: float = 0.0
    outer_simplices: int = 0
    bracket: Bracket | None = None

    def measure(
        self,
        cutter: Cutter,
        polar: PolarHull,
        seeds: NDArray[np.float64],
        budget: Budget,
        until: float | None = None,
    ) -> Bracket:
        """The bracket now: I = hull of ``seeds`` and the points the LPs proved, O = ``polar``'s
        rows. A part predicted to end past ``until`` (seconds of ``budget``) keeps its last value;
        the inner hull is then made of as many of the points (a seeded random subset) as fit."""
        pts = np.vstack([seeds, np.array(cutter.proven).reshape(-1, seeds.shape[1])])
        left = math.inf if until is None else until - budget.elapsed
        if self.inner is not None and self.inner_s > 0.0:
            # The hull of a subset is inside S_ov too: as many points as the time left allows
            # (half of it, the lattice needs its share), drawn at random (seeded).
            fit = self.inner_points * (0.5 * max(left, 0.0) / self.inner_s) ** (1.0 / INNER_GROWTH)
            if fit < len(pts):
                pts = pts[np.sort(np.random.default_rng(len(pts)).permutation(len(pts))[: int(fit)])]
        if self.inner is None or len(pts) > self.inner_points:
            t = budget.elapsed
            self.inner = inner_hull(pts, budget)
            self.inner_s, self.inner_points = budget.elapsed - t, len(pts)
            left = math.inf if until is None else until - budget.elapsed
        size = polar.predicted_size()
        if self.lattice is None or (
            size != self.outer_simplices and self.outer_s * size / self.outer_simplices <= left
        ):
            t = budget.elapsed
            self.outer, self.lattice = outer_volume(polar, budget)
            self.outer_s, self.outer_simplices = budget.elapsed - t, max(polar.size, 1)
        gap = hausdorff_bound(self.lattice.vertices, self.inner, cutter.center, budget)
        # Round-off (the joggles) can leave vol(I) a hair above vol(O).
        inner, outer = self.inner.volume, self.outer
        new = Bracket(min(inner, outer), max(inner, outer), gap)
        if new != self.bracket:
            self.bracket = new
        return self.bracket


def refine(
    support: SupportOracle,
    local: NDArray[np.float64],
    basis: NDArray[np.float64],
    tol: float,
    result: Any,
    bounds: tuple[NDArray[np.float64], NDArray[np.float64]],
    budget: Budget | None = None,
) -> Projection:
    r"""Outer approximation refined by cutting planes inside the linear hull (module docstring).

    ``local``: points of $S_{ov}$ spanning its linear hull, in its coordinates ``u``.
    ``O`` = $\{u : a_j^T u \le b_j\}$ starts as ``bounds`` (the support LPs along
    $\pm e_i$ of the twist and the RVDS cone's facets, in these coordinates) or, where
    they leave O unbounded, as the box of support LPs along $\pm e_i$ of ``u``; every
    row is a support LP's value or a facet of a cone that holds $S_{ov}$, so
    $O \supseteq S_{ov}$. Each round enumerates O's vertices ([`PolarHull`][mjtvm.polytopes.polar.PolarHull], which
    keeps Qhull's hull of the polar points between rounds) and shoots a ray from the centre
    ``c`` of the points to each vertex not yet certified ([`RayShooter`][mjtvm.polytopes.oracles.RayShooter]): a ray that
    reaches it (to ``10 tol``) certifies the vertex as a point of $S_{ov}$, hence one of
    its vertices; otherwise the duals give the normal ``a`` of a hyperplane supporting
    $S_{ov}$ where the ray leaves it, and the support LP along ``a`` adds the row
    $a^T u \le h(a)$, which cuts the vertex off. A vertex within ``tol`` of that row is
    settled by its distance to $S_{ov}$ ([`DistanceOracle`][mjtvm.polytopes.oracles.DistanceOracle]): within ``tol``,
    certified; otherwise cut off by the dual's separating hyperplane. When a round certifies
    every vertex, O = $S_{ov}$ (to ``10 tol``); [`polish_vertices()`][mjtvm.polytopes.hull.polish_vertices] then refits the
    facets and sorts out the vertices. The rays of a round go in an order that keeps
    neighbours together (`_chain()`), and a vertex that is a support LP's solution needs none.

    With a ``tolerance`` or a ``progress`` callback in ``budget.limits`` the bracket is
    measured between rounds ([`Meter`][mjtvm.polytopes.refine.Meter]), at most as often as it keeps its cost below the
    time spent refining; a limit reached stops the loop, the cuts found so far are kept and
    the result is ``"approximate"``, with the bracket measured then (only the memory budget
    applies to a first measurement; if even it does not fit, a [`SolverError`][mjtvm.errors.SolverError]). A round
    predicted ([`GROWTH`][mjtvm.polytopes.refine.GROWTH]) to end past the time limit is not started. With a tolerance and
    a ``confidence``, the cutting planes stop at [`REFINE_SHARE`][mjtvm.polytopes.refine.REFINE_SHARE] of the time limit and,
    if the bracket is still wider than the tolerance, a randomized estimate
    (`estimate_volume()`) uses the rest.
    """
    budget = budget or Budget()
    limits: Limits = budget.limits
    k = basis.shape[0]
    center = local.mean(axis=0)
    cutter = Cutter(support, basis, center, tol)
    cutter.budget = budget
    normals, offsets = bounds
    if np.linalg.matrix_rank(normals) < k:  # O would be unbounded (not met: basis rows span)
        normals = np.vstack([np.eye(k), -np.eye(k)])
        offsets = np.array([cutter.cut(a) for a in normals])
    seeds = np.vstack([np.zeros((1, k)), local])  # the origin and the first points: in S_ov
    certified: list[NDArray[np.float64]] = []
    polar = PolarHull(normals, offsets, center, tol)
    watch = limits.tolerance > 0.0 or limits.progress is not None
    estimating = limits.tolerance > 0.0 and limits.confidence > 0.0
    until = limits.time_limit
    if until is not None and estimating:
        until *= REFINE_SHARE
    budget.deadline = until
    # Measuring may go on past the rounds' deadline, leaving the estimate half of the rest.
    measure_until = None if until is None or limits.time_limit is None else (until + limits.time_limit) / 2
    meter = Meter()
    cost, since, rounds, round_s = 0.0, 0.0, 0, 0.0
    stop: LimitReached | None = None
    try:
        while True:
            budget.check()
            if until is not None and rounds and budget.elapsed + GROWTH * round_s > until:
                raise LimitReached(
                    "time",
                    f"the next round of cuts would end past {until:g} s (the last took {round_s:.1f} s)",
                )
            started = budget.elapsed
            verts = polar.new_vertices(budget)
            if certified:
                verts = verts[cKDTree(certified).query(verts)[0] > 10 * tol]
            try:
                cutter.settle(verts[_chain(verts, center)])
            finally:  # also when a limit interrupts the round: keep what it found
                certified.extend(cutter.certified)
                cutter.certified = []
                if cutter.cuts:
                    polar.add(cutter.new_n[: cutter.cuts], cutter.new_b[: cutter.cuts])
            rounds += 1
            round_s = budget.elapsed - started
            if not cutter.cuts:
                break
            cutter.cuts = 0
            # Progress alone (no tolerance) waits 2 s: quick exact runs are not slowed down.
            if watch and budget.elapsed - since >= cost and (limits.tolerance > 0.0 or budget.elapsed > 2.0):
                t = budget.elapsed
                bracket = meter.measure(cutter, polar, seeds, budget, measure_until)
                cost, since = budget.elapsed - t, budget.elapsed
                _report(limits, rounds, cutter, bracket, budget)
                if bracket.gap <= limits.tolerance:
                    stop = LimitReached("tolerance", f"relative volume gap {bracket.gap:.3g}")
                    break
        # polish_vertices and the volume hold (vertices x rows) booleans: that must fit too.
        budget.reserve(2.0 * len(certified) * len(polar.offsets), "the incidences of the exact TVMS")
    except LimitReached as e:
        stop = e
    finally:
        budget.deadline = limits.time_limit
    support.num_lps = cutter.num_lps
    if stop is not None:
        return _approximate(stop, cutter, polar, seeds, budget, meter, result, basis, rounds, measure_until)
    verts, facet_n, facet_b = polish_vertices(np.array(certified), polar.normals, polar.offsets, tol)
    return result("bounded", verts @ basis, basis, facets=(facet_n, facet_b))


def _report(limits: Limits, rounds: int, cutter: Cutter, bracket: Bracket, budget: Budget) -> None:
    if limits.progress is not None:
        limits.progress(
            {
                "round": rounds,
                "lps": cutter.num_lps,
                "inner": bracket.inner,
                "outer": bracket.outer,
                "gap": bracket.gap,
                "hausdorff": bracket.hausdorff,
                "seconds": budget.elapsed,
            }
        )


def _approximate(
    stop: LimitReached,
    cutter: Cutter,
    polar: PolarHull,
    seeds: NDArray[np.float64],
    budget: Budget,
    meter: Meter,
    result: Any,
    basis: NDArray[np.float64],
    rounds: int,
    until: float | None,
) -> Projection:
    """The ``"approximate"`` result: the bracket (measured again where that fits in the time
    left, see [`Meter`][mjtvm.polytopes.refine.Meter]), then the randomized estimate where it is asked for."""
    limits = budget.limits
    before = meter.bracket
    if stop.reason != "tolerance":
        final = Budget(Limits(memory=budget.memory))  # the time limit is applied by `until`
        final.base_rss, final.start = budget.base_rss, budget.start
        try:
            meter.measure(cutter, polar, seeds, final, until)
        except LimitReached as e:
            if meter.bracket is None:
                raise SolverError(
                    "budget", f"{stop.reason} limit reached ({stop.detail}) and no bracket fits: {e.detail}"
                ) from e
    bracket, inner = meter.bracket, meter.inner
    if bracket is None or inner is None:  # measure() sets both or raises
        raise SolverError("budget", f"{stop.reason} limit reached ({stop.detail}) before a bracket")
    if bracket is not before:  # (the loop reported the others)
        _report(limits, rounds, cutter, bracket, budget)
    estimate: VolumeEstimate | None = None
    left = None if limits.time_limit is None else limits.time_limit - budget.elapsed
    if (
        limits.tolerance > 0.0
        and limits.confidence > 0.0
        and bracket.gap > limits.tolerance
        and meter.lattice is not None
        and (left is None or left > 0.0)
    ):
        center = cutter.center
        sampling = Budget(Limits(time_limit=left, memory=budget.memory))
        estimate = estimate_volume(
            meter.lattice,
            cutter.shoot,
            center,
            cutter.tol,
            (bracket.inner, bracket.outer),
            sampling,
            tolerance=limits.tolerance,
            confidence=limits.confidence,
            order=lambda points: _chain(points, center),
            progress=None if limits.progress is None else _estimate_report(limits, cutter, budget),
            tighten=lambda normals, offsets: _tighten(polar, meter, normals, offsets, sampling),
        )
        if estimate.outer < bracket.outer:  # O was cut down on the way: a narrower bracket
            bracket = replace(bracket, outer=max(estimate.outer, bracket.inner))
    approx = Approximation(
        stop.reason,
        stop.detail,
        bracket.inner,
        bracket.outer,
        bracket.hausdorff,
        (inner.normals, inner.offsets),
        (polar.normals, polar.offsets),
        estimate,
    )
    return result("approximate", inner.vertices @ basis, basis, approximation=approx)


def _tighten(
    polar: PolarHull, meter: Meter, normals: NDArray[np.float64], offsets: NDArray[np.float64], budget: Budget
) -> tuple[float, FaceLattice] | None:
    """O with the rows ``normals @ u <= offsets`` added (supporting hyperplanes of S_ov found by
    the estimate's LPs): its volume bound and lattice; ``None`` (the rows kept, the lattice
    not made) where its predicted cost ([`Meter`][mjtvm.polytopes.refine.Meter]) exceeds the time left."""
    polar.add(normals, offsets)
    t = budget.limits.time_limit
    if t is not None and meter.outer_simplices:
        predicted = meter.outer_s * polar.predicted_size() / meter.outer_simplices
        if budget.elapsed + predicted > t:
            return None
    return outer_volume(polar, budget)


def _estimate_report(limits: Limits, cutter: Cutter, budget: Budget) -> Any:
    """The ``progress`` callback of the estimate: its interval after each batch."""

    def report(d: dict[str, Any]) -> None:
        if limits.progress is not None:
            limits.progress(d | {"lps": cutter.num_lps, "seconds": budget.elapsed})

    return report
