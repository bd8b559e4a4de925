r"""The velocity polytopes of Problem 1 without MuJoCo, rerun or matplotlib.

The TVMS ([`mjtvm.polytopes.tvms`][mjtvm.polytopes.tvms], its result:
[`mjtvm.polytopes.tvms_result`][mjtvm.polytopes.tvms_result]), the lifted polytope
([`mjtvm.polytopes.lifted`][mjtvm.polytopes.lifted]) and its projection (support LPs, or cdd's
vertex enumeration), the velocity and force polytopes of a Jacobian
([`mjtvm.polytopes.capacity`][mjtvm.polytopes.capacity], zonotopes:
[`mjtvm.polytopes.zonotope`][mjtvm.polytopes.zonotope]), the point-set geometry
([`mjtvm.polytopes.hull`][mjtvm.polytopes.hull]), volumes, estimates and brackets. This room
imports only the rooms below it: ``problem2``, ``formats``, ``model``, ``lp`` and ``errors``.

The names below are imported on first use: ``mjtvm solve`` imports
``mjtvm.polytopes.budget``, and so this package, but needs neither scipy's Qhull nor cdd.
Every other name lives in its module. The function [`tvms()`][mjtvm.polytopes.tvms.tvms] is
``mjtvm.tvms`` (here ``mjtvm.polytopes.tvms`` is its module).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mjtvm._lazy import lazy_attributes

if TYPE_CHECKING:
    from mjtvm.polytopes.capacity import CapacityPolytope, force_polytope, velocity_polytope
    from mjtvm.polytopes.estimate import VolumeEstimate
    from mjtvm.polytopes.lifted import LiftedPolytope, lifted_polytope
    from mjtvm.polytopes.projection import project_lp
    from mjtvm.polytopes.tvms_result import TvmsResult, TvmsTimings, default_scale
    from mjtvm.polytopes.volume import hausdorff, hull_volume
    from mjtvm.polytopes.zonotope import Zonotope

__all__ = [
    "CapacityPolytope",
    "LiftedPolytope",
    "TvmsResult",
    "TvmsTimings",
    "VolumeEstimate",
    "Zonotope",
    "default_scale",
    "force_polytope",
    "hausdorff",
    "hull_volume",
    "lifted_polytope",
    "project_lp",
    "velocity_polytope",
]

__getattr__ = lazy_attributes(
    __name__,
    {
        "CapacityPolytope": "capacity",
        "force_polytope": "capacity",
        "velocity_polytope": "capacity",
        "VolumeEstimate": "estimate",
        "LiftedPolytope": "lifted",
        "lifted_polytope": "lifted",
        "project_lp": "projection",
        "TvmsResult": "tvms_result",
        "TvmsTimings": "tvms_result",
        "default_scale": "tvms_result",
        "hausdorff": "volume",
        "hull_volume": "volume",
        "Zonotope": "zonotope",
    },
)
