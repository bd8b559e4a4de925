"""Polar vertex enumeration under Problem 1: all at once and as cutting planes are added."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull, QhullError

import mjtvm.polytopes.polar as polar_module
from mjtvm.errors import SolverError
from mjtvm.polytopes.polar import PolarHull, polar_vertices
from mjtvm.polytopes.volume import hausdorff

TOL = 1e-9


def cube_rows(k: int) -> tuple[np.ndarray, np.ndarray]:
    """The cube [-1, 1]^k as a u <= b."""
    return np.vstack([np.eye(k), -np.eye(k)]), np.ones(2 * k)


def cube_vertices(k: int) -> np.ndarray:
    return np.array(list(itertools.product((-1.0, 1.0), repeat=k)))


@pytest.mark.parametrize("k", [2, 3, 4, 6])
def test_polar_vertices_of_a_cube(k):
    a, b = cube_rows(k)
    rng = np.random.default_rng(k)
    # Redundant rows (a shifted copy of each facet, rows through vertices only) change nothing.
    corner = np.ones(k) / math.sqrt(k)
    a = np.vstack([a, a, corner])
    b = np.concatenate([b, b + 0.5, [math.sqrt(k)]])
    verts = polar_vertices(a, b, 0.1 * rng.uniform(-1, 1, k), TOL)
    assert len(verts) == 2**k
    assert hausdorff(verts, cube_vertices(k)) <= 1e-12


@pytest.mark.parametrize("k", [3, 6])
def test_polar_hull_adds_cuts_and_returns_only_new_vertices(k):
    """Cutting the corner (1, ..., 1) off [-1, 1]^k by sum(u) <= k - 1 leaves the other
    2^k - 1 corners and adds the k points where the cut meets the corner's edges; a second
    cut through the opposite corner the same way. new_vertices() gives only the new ones."""
    a, b = cube_rows(k)
    hull = PolarHull(a, b, np.full(k, -0.01), TOL)
    assert len(hull.new_vertices()) == 2**k
    assert len(hull.new_vertices()) == 0  # nothing added
    hull.add(np.ones((1, k)) / math.sqrt(k), np.array([(k - 1) / math.sqrt(k)]))
    new = hull.new_vertices()
    assert hausdorff(new, np.ones(k) - np.eye(k)) <= 1e-12  # (1, .., 1, 0, 1, .., 1)
    hull.add(-np.ones((1, k)) / math.sqrt(k), np.array([(k - 1) / math.sqrt(k)]))
    assert hausdorff(hull.new_vertices(), -np.ones(k) + np.eye(k)) <= 1e-12
    corners = cube_vertices(k)
    kept = corners[np.abs(corners.sum(axis=1)) < k]
    expected = np.vstack([kept, np.ones(k) - np.eye(k), -np.ones(k) + np.eye(k)])
    assert len(hull.vertices()) == len(expected)
    assert hausdorff(hull.vertices(), expected) <= 1e-12


def test_polar_vertices_of_a_degenerate_pyramid():
    """The square pyramid over [-1, 1]^2 x {0} with apex (0, 0, 1): four facets meet at
    the apex (a non-simple vertex, whose polar facet Qhull must triangulate)."""
    s = 1.0 / math.sqrt(2.0)
    a = np.array([[0, 0, -1.0], [s, 0, s], [-s, 0, s], [0, s, s], [0, -s, s]])
    b = np.array([0.0, s, s, s, s])
    verts = polar_vertices(a, b, np.array([0.0, 0.0, 0.2]), TOL)
    expected = np.array([[1, 1, 0], [1, -1, 0], [-1, 1, 0], [-1, -1, 0], [0, 0, 1.0]])
    assert len(verts) == 5 and hausdorff(verts, expected) <= 1e-12


class _FlakyQhull:
    """scipy's ConvexHull where incremental hulls (all of them) and the first ``scratch``
    hulls made from scratch stop on a QhullError, as Qhull's incremental mode can (scipy
    issue #4974) and as a from-scratch hull can on unlucky points."""

    def __init__(self, scratch: int) -> None:
        self.scratch, self.calls = scratch, 0

    def __call__(self, points, incremental=False, **kwargs):
        self.calls += 1
        if incremental or self.scratch > 0:
            self.scratch -= 0 if incremental else 1
            raise QhullError("QH6106 qhull precision error: Vertex sets are the same")
        return ConvexHull(points, **kwargs)


@pytest.mark.parametrize("scratch", [0, 1, 2])
def test_polar_hull_survives_qhull_errors(monkeypatch, scratch):
    """Incremental hulls that always fail, and from-scratch hulls that fail ``scratch`` times
    (the points are then joggled anew, 10 and 100 times as much): the same vertices as
    without errors (solved on the exact rows), before and after a cut, and the face lattice
    of the joggled points still gives the cube's volume 2^k (the joggle's order, relative)."""
    k = 4
    a, b = cube_rows(k)
    flaky = _FlakyQhull(scratch)
    monkeypatch.setattr(polar_module, "ConvexHull", flaky)
    hull = PolarHull(a, b, np.full(k, -0.01), TOL)
    assert hausdorff(hull.new_vertices(), cube_vertices(k)) <= 1e-12
    hull.add(np.ones((1, k)) / math.sqrt(k), np.array([(k - 1) / math.sqrt(k)]))
    assert hausdorff(hull.new_vertices(), np.ones(k) - np.eye(k)) <= 1e-12
    assert flaky.calls >= 4  # an incremental attempt and a hull from scratch each time
    monkeypatch.setattr(polar_module, "ConvexHull", _FlakyQhull(scratch))
    cube = PolarHull(a, b, np.full(k, -0.01), TOL)
    assert cube.lattice().volume == pytest.approx(2.0**k, rel=1e-6)


def test_polar_hull_reports_qhull_failing_on_every_joggle(monkeypatch):
    monkeypatch.setattr(polar_module, "ConvexHull", _FlakyQhull(3))
    a, b = cube_rows(3)
    with pytest.raises(SolverError, match="qhull"):
        PolarHull(a, b, np.zeros(3), TOL).vertices()
