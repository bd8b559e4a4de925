"""Anytime Problem 1: the certified volume bracket, the Hausdorff bound, the alpha brackets and the limits.

Closed forms: the cube [-1, 1]^k (volume 2^k) and the cross-polytope (2^k / k!) measured by the
bracket's own volume routines; on TVMSs the exact volume is cross-checked against one Qhull hull
of the exact vertices (an independent computation) before the bracket is compared with it.
"""

from __future__ import annotations

import itertools
import json
import math
from importlib import resources

import jsonschema
import numpy as np
import pytest
from scipy.spatial import ConvexHull

from benchmarks.synthetic import random_state
from mjtvm import SolverError, tvmmp
from mjtvm.errors import ParamError
from mjtvm.polytopes.bracket import inner_hull, outer_volume, ray_lengths
from mjtvm.polytopes.budget import Budget, LimitReached, Limits
from mjtvm.polytopes.polar import PolarHull
from mjtvm.polytopes.tvms import tvms

STATES = {
    "planar": dict(seed=0, space=2, fingers=3, joints_per_finger=3, num_rvds=5),  # 3-D, 49 vertices
    "spatial": dict(seed=0, space=3, fingers=3, joints_per_finger=3, friction_edges=6),  # 5-D in 6-D
}


def state_of(name: str):
    kw = dict(STATES[name])
    return random_state(kw.pop("seed"), **kw)


def local(result, points: np.ndarray) -> np.ndarray:
    """``points`` (twists) scaled and in coordinates of the linear hull of the exact vertices."""
    scaled = result.vertices * result.scale
    basis = np.linalg.svd(scaled, full_matrices=False)[2][: result.dimension]
    return (points * result.scale) @ basis.T


def exact_hull(result) -> ConvexHull:
    """One Qhull hull of the exact vertices, scaled, inside their linear hull.

    Qhull's ``Q12`` allows the wide merges of duplicated ridges: scipy 1.17.1's Qhull stops on
    the spatial state's 208 vertices (QH6271, "wide merge ... due to dupridge") without it, and
    with it agrees with the TVMS's own volume to 2e-13."""
    return ConvexHull(local(result, result.vertices), qhull_options="Q12")


def qhull_volume(result) -> float:
    """The scaled volume of :func:`exact_hull`."""
    return float(exact_hull(result).volume)


@pytest.fixture(scope="module", params=sorted(STATES))
def exact(request):
    state = state_of(request.param)
    r = tvms(state, rvds_cone=False)
    assert r.status == "bounded" and r.dimension >= 3
    assert r.affine_volume == pytest.approx(qhull_volume(r), rel=1e-7)
    return state, r


@pytest.mark.parametrize("k", [2, 3, 4, 5, 6])
def test_cube_and_cross_polytope_volumes_in_closed_form(k):
    eye = np.eye(k)
    cube = PolarHull(np.vstack([eye, -eye]), np.ones(2 * k), np.full(k, 0.1), 1e-12)
    # The joggled polytope's volume, inflated by the joggle: an upper bound up to the round-off
    # of its ill-conditioned corners (the flat simplices, 4e-8 relative on the cross-polytope).
    volume, lattice = outer_volume(cube, Budget())
    assert volume == pytest.approx(2.0**k, rel=1e-7)
    assert lattice.volume == pytest.approx(2.0**k, rel=1e-8)
    assert len(lattice.vertices) == 2**k
    assert np.abs(np.sort(np.abs(lattice.vertices).ravel()) - 1.0).max() < 1e-8
    # The cross-polytope is not simple (2^(k-1) facets at a vertex): its joggled polar hull has
    # flat simplices, whose flags must not be lost.
    signs = np.array(np.meshgrid(*[[-1.0, 1.0]] * k)).reshape(k, -1).T
    cross = PolarHull(signs, np.ones(len(signs)), np.zeros(k), 1e-12)
    volume, lattice = outer_volume(cross, Budget())
    assert volume == pytest.approx(2.0**k / math.factorial(k), rel=1e-7)
    inner = inner_hull(np.vstack([eye, -eye]), Budget())
    assert inner.volume == pytest.approx(2.0**k / math.factorial(k), rel=1e-7)
    # The cross-polytope's ray lengths: along e_1 it reaches 1, along (1, ..., 1) 1 / k.
    rays = ray_lengths(inner.normals, inner.offsets, np.vstack([eye[0], np.ones(k)]))
    assert rays == pytest.approx([1.0, 1.0 / k], rel=1e-7)


def test_bracket_contains_the_exact_volume(exact):
    state, r = exact
    for tolerance in (0.2, 0.02):
        a = tvms(state, rvds_cone=False, tolerance=tolerance)
        if a.status == "bounded":  # exact before the bracket was narrow enough to stop
            assert a.affine_volume == pytest.approx(r.affine_volume, rel=1e-9)
            continue
        assert a.status == "approximate" and a.stopped_by is not None and a.stopped_by[0] == "tolerance"
        lo, hi = a.affine_volume_bracket
        assert lo <= r.affine_volume * (1 + 1e-7) and r.affine_volume <= hi * (1 + 1e-7)
        assert (hi - lo) / hi <= tolerance
        v_lo, v_hi = a.volume_bracket
        assert v_lo <= r.volume * (1 + 1e-7) and r.volume <= v_hi * (1 + 1e-7)
        if r.dimension < state.twist_dim:
            assert a.volume_bracket.tolist() == [0.0, 0.0]
        assert a.volume is None and a.affine_volume is None and a.hausdorff_gap > 0.0
        # The inner polytope's vertices are points of S_ov: inside the exact hull.
        hull = exact_hull(r)
        slack = local(r, a.vertices) @ hull.equations[:, :-1].T + hull.equations[:, -1]
        assert np.max(slack) <= 1e-7 * np.max(np.abs(r.vertices * r.scale))


def test_exact_result_has_a_point_bracket(exact):
    _, r = exact
    assert r.affine_volume_bracket.tolist() == [r.affine_volume, r.affine_volume]
    assert r.hausdorff_gap == 0.0 and r.stopped_by is None


def test_bracket_narrows_monotonically(exact):
    state, r = exact
    seen: list[dict] = []
    tvms(state, rvds_cone=False, tolerance=1e-9, progress=seen.append)
    assert len(seen) >= 2
    inner = [d["inner"] for d in seen]
    outer = [d["outer"] for d in seen]
    assert all(b >= a * (1 - 1e-9) for a, b in itertools.pairwise(inner))
    assert all(b <= a * (1 + 1e-9) for a, b in itertools.pairwise(outer))
    assert inner[-1] <= r.affine_volume * (1 + 1e-7) <= outer[-1] * (1 + 2e-7)


def test_time_limit_gives_a_bracket(exact):
    state, r = exact
    a = tvms(state, rvds_cone=False, time_limit=1e-4)
    assert a.status == "approximate" and a.stopped_by[0] == "time" and a.bounded is True
    lo, hi = a.affine_volume_bracket
    assert lo <= r.affine_volume * (1 + 1e-7) <= hi * (1 + 2e-7)


def test_memory_budget_far_below_need_gives_a_bracket_or_a_clear_error(exact):
    state, r = exact
    for memory in (1, 2**20):
        try:
            a = tvms(state, rvds_cone=False, memory=memory)
        except SolverError as e:  # not even a bracket fits: said so, never a MemoryError
            assert "memory limit" in str(e) and "no bracket fits" in str(e)
            continue
        assert a.status in ("approximate", "bounded")
        lo, hi = a.affine_volume_bracket
        assert lo <= r.affine_volume * (1 + 1e-7) <= hi * (1 + 2e-7)


def test_budget_reserve_refuses_before_allocating():
    budget = Budget(Limits(memory=2**20))
    with pytest.raises(LimitReached, match="memory limit: a test array needs 1024 MiB"):
        budget.reserve(2**30, "a test array")
    with pytest.raises(ParamError, match=r"^tolerance: "):
        Limits(tolerance=1.0)
    with pytest.raises(ParamError, match=r"^time_limit: "):
        Limits(time_limit=0.0)


@pytest.mark.parametrize("tolerance", [0.0, 0.05])
def test_alpha_brackets_contain_problem2s_alphas(tolerance):
    """One REFS vertex: Problem 2's alpha_l is the ray length into S_ov along r_l, so it lies
    between the ray lengths into the inner and the outer polytope."""
    for name in sorted(STATES):
        state = state_of(name)
        r = tvms(state, rvds_cone=False, tolerance=tolerance)
        p2 = tvmmp(state, witnesses=False)
        assert r.alpha_bracket is not None and r.alpha_bracket.shape == (len(state.rvds), 2)
        for (lo, hi), a, status in zip(r.alpha_bracket, p2.alpha[0], p2.status[0]):
            assert status == "optimal"
            # abs 1e-8: Problem 2 writes alphas below its solver tolerance as 0.0
            assert lo <= a * (1 + 1e-7) + 1e-8 and a <= hi * (1 + 1e-7) + 1e-8
            if r.status == "bounded":
                assert lo == pytest.approx(a, rel=1e-7, abs=1e-8)


def test_approximate_document_matches_the_schema():
    schema = json.loads(
        resources.files("mjtvm.data").joinpath("schema").joinpath("tvms.schema.json").read_text()
    )
    state = state_of("spatial")
    for r in (tvms(state, rvds_cone=False, tolerance=0.2), tvms(state, time_limit=1e-4), tvms(state)):
        doc = json.loads(json.dumps(r.to_dict(), allow_nan=False))
        jsonschema.validate(doc, schema)
    doc = tvms(state, rvds_cone=False, tolerance=0.2).to_dict()
    assert doc["status"] == "approximate" and doc["stopped_by"]["reason"] == "tolerance"
    assert doc["volume"] is None and len(doc["volume_bracket"]) == 2
