"""The growing hull of the epsilons (mjtvm.measures.hull), numpy and compiled insertion alike,
against Qhull's hull of the same points."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from mjtvm.measures.hull import GrowingHull


def _planes(eq: np.ndarray) -> np.ndarray:
    """Facet hyperplanes rounded and sorted, to compare two hulls' facet sets."""
    return np.unique(np.round(eq, 9), axis=0)


@pytest.mark.parametrize("compiled", [False, True])
@pytest.mark.parametrize("dim", [3, 4, 6])
def test_inserted_points_give_qhull_facets(dim: int, compiled: bool) -> None:
    """Random points in general position, inserted one by one after a first hull: the facets
    are Qhull's facets of all the points (each hyperplane, none missing), checked by verify()
    without a rebuild."""
    rng = np.random.default_rng(dim)
    for trial in range(5):
        pts = rng.normal(size=(2 * dim + 40, dim))
        hull = GrowingHull(pts[: 2 * dim], compiled=compiled)
        for p in pts[2 * dim :]:
            hull.add(p[None, :])
        assert not hull.verified
        alive = np.isfinite(hull.distances())
        mine = _planes(hull.equations[alive])
        hull.verify()
        assert hull.verified
        # verify() accepted the inserted facets as they were: the same rows are alive
        assert np.array_equal(_planes(hull.equations[np.isfinite(hull.distances())]), mine)
        ref = _planes(ConvexHull(pts).equations)
        assert mine.shape == ref.shape, trial
        assert np.allclose(mine, ref, atol=1e-8), trial


@pytest.mark.parametrize("compiled", [False, True])
def test_interior_and_repeated_points_change_nothing(compiled: bool) -> None:
    rng = np.random.default_rng(3)
    pts = rng.normal(size=(30, 5))
    hull = GrowingHull(pts, compiled=compiled)
    before = hull.equations.copy()
    hull.add(np.vstack([0.01 * pts[:3], pts[:2]]))  # deep inside, and points already vertices
    assert np.array_equal(hull.equations, before)
    assert hull.verified


@pytest.mark.parametrize("compiled", [False, True])
def test_points_on_a_facet_keep_the_distance(compiled: bool) -> None:
    """The cube [-1, 1]^3 and then points on its faces (coplanar with facets: seen by none):
    the nearest facet stays at distance 1, and the checked hull holds every point."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    hull = GrowingHull(corners, compiled=compiled)
    on_faces = np.array([[1.0, 0.2, -0.3], [0.5, -1.0, 0.1], [0.0, 0.0, 1.0]])
    hull.add(on_faces)
    hull.add(np.array([[2.0, 0.0, 0.0]]))  # a real vertex beyond the +x face
    hull.verify()
    d = hull.distances()
    assert float(d[np.isfinite(d)].min()) == pytest.approx(1.0, abs=1e-12)
    ref = ConvexHull(np.vstack([corners, on_faces, [[2.0, 0.0, 0.0]]]))
    assert float(np.min(-ref.equations[:, -1])) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("compiled", [False, True])
def test_a_tampered_facet_fails_the_check_and_is_rebuilt(compiled: bool) -> None:
    """verify() is a test that can fail: a facet hyperplane moved inwards no longer holds the
    points, so the hull is rebuilt by Qhull, and the distances are Qhull's again."""
    rng = np.random.default_rng(5)
    pts = rng.normal(size=(40, 6))
    hull = GrowingHull(pts[:12], compiled=compiled)
    hull.add(pts[12:])
    alive = np.flatnonzero(np.isfinite(hull.distances()))
    hull._eq[alive[0], -1] += 0.5  # the facet's plane moved 0.5 towards the origin
    hull.verify()
    assert hull.verified
    assert float(np.min(hull.distances())) == pytest.approx(
        float(np.min(-ConvexHull(pts).equations[:, -1])), rel=1e-12
    )


@pytest.mark.parametrize("compiled", [False, True])
def test_a_flat_insertion_falls_back_to_qhull(monkeypatch: pytest.MonkeyPatch, compiled: bool) -> None:
    """A point next to a corner of the cube, 1e-11 outside two faces, makes the new facets
    over the edges it sees nearly flat: the insertion is Degenerate, and the hull is Qhull's
    hull of every point (rebuilt once) rather than a wrong one."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    hull = GrowingHull(corners, compiled=compiled)
    rebuilds = []
    rebuild = GrowingHull._rebuild
    monkeypatch.setattr(GrowingHull, "_rebuild", lambda self: (rebuilds.append(1), rebuild(self))[1])
    hull.add(np.array([[1.0 + 1e-11, 1.0, 1.0 + 1e-11]]))
    assert rebuilds == [1] and hull.verified
    ref = ConvexHull(np.vstack([corners, [[1.0 + 1e-11, 1.0, 1.0 + 1e-11]]]))
    d = hull.distances()
    assert float(d[np.isfinite(d)].min()) == pytest.approx(float(np.min(-ref.equations[:, -1])), abs=1e-9)
