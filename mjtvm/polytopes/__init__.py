r"""The velocity polytopes of Problem 1 without MuJoCo: the TVMS ([`mjtvm.polytopes.tvms`][mjtvm.polytopes.tvms]),
its projection and enumeration, the polar vertex enumeration ([`mjtvm.polytopes.polar`][mjtvm.polytopes.polar]),
the velocity and force polytopes of a Jacobian ([`mjtvm.polytopes.capacity`][mjtvm.polytopes.capacity], zonotopes:
[`mjtvm.polytopes.zonotope`][mjtvm.polytopes.zonotope]),
the point-set geometry ([`mjtvm.polytopes.hull`][mjtvm.polytopes.hull]), volumes, estimates and brackets.

The names below are imported on first use, so that importing one module does not load the others.
The functions named like their modules, [`tvms()`][mjtvm.polytopes.tvms.tvms],
[`refine()`][mjtvm.polytopes.refine.refine] and [`zonotope()`][mjtvm.polytopes.zonotope.zonotope], are not among them (``mjtvm.polytopes.tvms`` is the module).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mjtvm._lazy import lazy_attributes

if TYPE_CHECKING:
    from mjtvm.polytopes.bracket import (
        Bracket,
        InnerHull,
        hausdorff_bound,
        inner_hull,
        outer_volume,
        ray_lengths,
    )
    from mjtvm.polytopes.budget import (
        DEFAULT_CONFIDENCE,
        DEFAULT_MEMORY_FRACTION,
        Budget,
        LimitReached,
        Limits,
        available_memory,
        default_memory_budget,
        rss_bytes,
    )
    from mjtvm.polytopes.capacity import DUPLICATE_TOL, CapacityPolytope, force_polytope, velocity_polytope
    from mjtvm.polytopes.enumeration import force_form, project_cdd
    from mjtvm.polytopes.estimate import (
        FIRST_BATCH,
        MIN_INSIDE,
        VolumeEstimate,
        clopper_pearson,
        estimate_volume,
    )
    from mjtvm.polytopes.hull import (
        CDD_REL_TOL,
        ZERO_TOL,
        cone_facets,
        distinct,
        incidence,
        polish_vertices,
        reduce_points,
        span,
        triangulate,
        vertex_mask,
    )
    from mjtvm.polytopes.lattice import FaceLattice
    from mjtvm.polytopes.lifted import (
        Approximation,
        LiftedPolytope,
        Projection,
        ProjectionStatus,
        lifted_polytope,
    )
    from mjtvm.polytopes.oracles import DistanceOracle, RayShooter, SupportOracle
    from mjtvm.polytopes.polar import FLAT, PolarHull, polar_vertices
    from mjtvm.polytopes.projection import REL_TOL, project_lp, twist_rows
    from mjtvm.polytopes.refine import GROWTH, REFINE_SHARE, Cutter, Meter
    from mjtvm.polytopes.tvms import (
        CHARACTERISTIC_LENGTH,
        TVMS_SCHEMA,
        TvmsResult,
        TvmsTimings,
        default_scale,
    )
    from mjtvm.polytopes.volume import facet_volume, hausdorff, hull_volume
    from mjtvm.polytopes.zonotope import MAX_CANDIDATES, PLANE_TOL, RANK_TOL, Zonotope

_HOMES = {
    "Bracket": "bracket",
    "InnerHull": "bracket",
    "hausdorff_bound": "bracket",
    "inner_hull": "bracket",
    "outer_volume": "bracket",
    "ray_lengths": "bracket",
    "CapacityPolytope": "capacity",
    "DUPLICATE_TOL": "capacity",
    "force_polytope": "capacity",
    "velocity_polytope": "capacity",
    "DEFAULT_CONFIDENCE": "budget",
    "DEFAULT_MEMORY_FRACTION": "budget",
    "Budget": "budget",
    "LimitReached": "budget",
    "Limits": "budget",
    "available_memory": "budget",
    "default_memory_budget": "budget",
    "rss_bytes": "budget",
    "force_form": "enumeration",
    "project_cdd": "enumeration",
    "FIRST_BATCH": "estimate",
    "MIN_INSIDE": "estimate",
    "VolumeEstimate": "estimate",
    "clopper_pearson": "estimate",
    "estimate_volume": "estimate",
    "CDD_REL_TOL": "hull",
    "ZERO_TOL": "hull",
    "cone_facets": "hull",
    "distinct": "hull",
    "incidence": "hull",
    "polish_vertices": "hull",
    "reduce_points": "hull",
    "span": "hull",
    "triangulate": "hull",
    "vertex_mask": "hull",
    "FaceLattice": "lattice",
    "Approximation": "lifted",
    "LiftedPolytope": "lifted",
    "Projection": "lifted",
    "ProjectionStatus": "lifted",
    "lifted_polytope": "lifted",
    "DistanceOracle": "oracles",
    "RayShooter": "oracles",
    "SupportOracle": "oracles",
    "FLAT": "polar",
    "PolarHull": "polar",
    "polar_vertices": "polar",
    "REL_TOL": "projection",
    "project_lp": "projection",
    "twist_rows": "projection",
    "GROWTH": "refine",
    "REFINE_SHARE": "refine",
    "Cutter": "refine",
    "Meter": "refine",
    "CHARACTERISTIC_LENGTH": "tvms",
    "TVMS_SCHEMA": "tvms",
    "TvmsResult": "tvms",
    "TvmsTimings": "tvms",
    "default_scale": "tvms",
    "facet_volume": "volume",
    "hausdorff": "volume",
    "hull_volume": "volume",
    "MAX_CANDIDATES": "zonotope",
    "PLANE_TOL": "zonotope",
    "RANK_TOL": "zonotope",
    "Zonotope": "zonotope",
}

__all__ = [
    "CDD_REL_TOL",
    "CHARACTERISTIC_LENGTH",
    "DEFAULT_CONFIDENCE",
    "DEFAULT_MEMORY_FRACTION",
    "DUPLICATE_TOL",
    "FIRST_BATCH",
    "FLAT",
    "GROWTH",
    "MAX_CANDIDATES",
    "MIN_INSIDE",
    "PLANE_TOL",
    "RANK_TOL",
    "REFINE_SHARE",
    "REL_TOL",
    "TVMS_SCHEMA",
    "ZERO_TOL",
    "Approximation",
    "Bracket",
    "Budget",
    "CapacityPolytope",
    "Cutter",
    "DistanceOracle",
    "FaceLattice",
    "InnerHull",
    "LiftedPolytope",
    "LimitReached",
    "Limits",
    "Meter",
    "PolarHull",
    "Projection",
    "ProjectionStatus",
    "RayShooter",
    "SupportOracle",
    "TvmsResult",
    "TvmsTimings",
    "VolumeEstimate",
    "Zonotope",
    "available_memory",
    "clopper_pearson",
    "cone_facets",
    "default_memory_budget",
    "default_scale",
    "distinct",
    "estimate_volume",
    "facet_volume",
    "force_form",
    "force_polytope",
    "hausdorff",
    "hausdorff_bound",
    "hull_volume",
    "incidence",
    "inner_hull",
    "lifted_polytope",
    "outer_volume",
    "polar_vertices",
    "polish_vertices",
    "project_cdd",
    "project_lp",
    "ray_lengths",
    "reduce_points",
    "rss_bytes",
    "span",
    "triangulate",
    "twist_rows",
    "velocity_polytope",
    "vertex_mask",
]


__getattr__ = lazy_attributes(__name__, _HOMES)
