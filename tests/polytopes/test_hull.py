"""Geometry under Problem 1: facet refitting, volumes by facets, cone facets."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from mjtvm.polytopes.hull import cone_facets, polish_vertices
from mjtvm.polytopes.volume import facet_volume, hausdorff

TOL = 1e-9


def cube_rows(k: int) -> tuple[np.ndarray, np.ndarray]:
    """The cube [-1, 1]^k as a u <= b."""
    return np.vstack([np.eye(k), -np.eye(k)]), np.ones(2 * k)


def cube_vertices(k: int) -> np.ndarray:
    return np.array(list(itertools.product((-1.0, 1.0), repeat=k)))


def test_polish_drops_a_point_on_an_edge_and_a_row_through_a_vertex():
    """Points of the unit square plus a point in the middle of an edge and one inside;
    rows: its four facets, a near copy of one facet, and a row touching one corner only."""
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
    points = np.vstack([square, [[0.5, 0.0]]])
    a = np.array([[1, 0], [-1, 0], [0, 1], [0, -1], [1e-3, -1], [1, 1]], dtype=float)
    a /= np.linalg.norm(a, axis=1)[:, None]
    b = np.max(points @ a.T, axis=0)  # every row supports the points
    verts, normals, offsets = polish_vertices(points, a, b, TOL)
    assert len(verts) == 4 and hausdorff(verts, square) <= 1e-12
    # Four facets: the corner row spans no edge; the near copy of y >= 0 touches (1, 0) only.
    assert len(normals) == 4
    np.testing.assert_allclose(np.sort(offsets), [0.0, 0.0, 1.0, 1.0], atol=1e-12)


def test_polish_merges_near_copies_and_drops_a_stray_point_on_an_edge():
    """A triangle whose corner (1, 0) comes twice (1e-9 apart, as two nearly parallel rows
    leave it) and a stray point 1e-3 along the edge from it, within 10 tol of that edge only
    (tol = 1e-7): one vertex per corner, the stray point is inside the hull."""
    triangle = np.array([[0, 0], [1, 0], [0, 1.0]])
    points = np.vstack([triangle, [[1 + 1e-9, 0.0], [0.999, 0.001]]])
    a = np.array([[0, -1], [-1, 0], [1, 1], [1e-9, -1]], dtype=float)
    a /= np.linalg.norm(a, axis=1)[:, None]
    b = np.max(points @ a.T, axis=0)
    verts, normals, _ = polish_vertices(points, a, b, 1e-7)
    assert len(verts) == 3 and hausdorff(verts, triangle) <= 1e-8
    assert len(normals) == 3  # the near copy of y >= 0 has the same points: one facet


@pytest.mark.parametrize("k", [2, 3, 4, 5])
def test_facet_volume_of_a_cube_and_a_simplex(k):
    a, b = cube_rows(k)
    assert facet_volume(cube_vertices(k), a, b, TOL) == pytest.approx(2.0**k, rel=1e-12)
    simplex = np.vstack([np.zeros(k), np.eye(k)])
    rows = np.vstack([-np.eye(k), np.ones(k) / math.sqrt(k)])
    offsets = np.append(np.zeros(k), 1 / math.sqrt(k))
    assert facet_volume(simplex, rows, offsets, TOL) == pytest.approx(1 / math.factorial(k), rel=1e-12)


def test_facet_volume_of_a_degenerate_polytope_matches_the_closed_form():
    """A prism over a regular 40-gon times a square, in 4-D (many coplanar points per facet,
    which Qhull cannot merge unjoggled): area(40-gon) x 4."""
    angles = 2 * np.pi * np.arange(40) / 40
    polygon = np.column_stack([np.cos(angles), np.sin(angles)])
    points = np.array([[*p, x, y] for p in polygon for x in (-1.0, 1.0) for y in (-1.0, 1.0)])
    mid = angles + np.pi / 40
    rows = [np.array([np.cos(t), np.sin(t), 0, 0]) for t in mid] + [
        s * e for e in np.eye(4)[2:] for s in (1.0, -1.0)
    ]
    offsets = [math.cos(math.pi / 40)] * 40 + [1.0] * 4
    area = 0.5 * 40 * math.sin(2 * math.pi / 40)
    volume = facet_volume(points, np.array(rows), np.array(offsets), TOL)
    assert volume == pytest.approx(4 * area, rel=1e-10)


def test_facet_volume_counts_a_sliver_between_nearly_coplanar_facets_once():
    """The unit cube with a roof of height 3 tol over its top: the roof's four triangles are
    facets at a tiny angle, each within 10 tol of all five top points. Summing their
    pyramids would count the top four times (volume 1.44); measured as one facet the
    error is the sliver, <= 10 tol. Closed form: 1 + (3 tol) / 3."""
    delta = 3 * TOL
    bottom = np.array([[x, y, 0.0] for x, y in itertools.product((0.0, 1.0), repeat=2)])
    top = bottom + np.array([0.0, 0.0, 1.0])
    apex = np.array([0.5, 0.5, 1.0 + delta])
    points = np.vstack([bottom, top, apex])
    rows = [-np.eye(3)[2], np.eye(3)[0], -np.eye(3)[0], np.eye(3)[1], -np.eye(3)[1]]
    offsets = [0.0, 1.0, 0.0, 1.0, 0.0]
    for i, j in [(0, 1), (1, 3), (3, 2), (2, 0)]:  # roof triangles over the top edges
        n = np.cross(top[j] - top[i], apex - top[i])
        n = n / np.linalg.norm(n) * np.sign(n[2])
        rows.append(n)
        offsets.append(float(n @ apex))
    volume = facet_volume(points, np.array(rows), np.array(offsets), TOL)
    assert volume == pytest.approx(1.0 + delta / 3, abs=10 * TOL)


def test_cone_facets_of_an_orthant_a_wedge_and_a_square_pyramid():
    """cone(e1, e2, e3) = {f >= 0}; cone((1, 1), (-1, 1)) = {y >= |x|}; the cone over a square
    {|x| <= z, |y| <= z} has the four facets (+-1, 0, 1)/sqrt(2), (0, +-1, 1)/sqrt(2)."""
    rows = cone_facets(np.eye(3))
    assert sorted(map(tuple, np.round(rows, 12))) == sorted(map(tuple, np.eye(3)))
    rows = cone_facets(np.array([[1.0, -1.0], [1.0, 1.0]]))
    want = np.array([[1.0, 1.0], [-1.0, 1.0]]) / math.sqrt(2)
    assert hausdorff(rows, want) <= 1e-12 and len(rows) == 2
    square = np.array([[1.0, 1.0, 1.0], [1.0, -1.0, 1.0], [-1.0, 1.0, 1.0], [-1.0, -1.0, 1.0]]).T
    rows = cone_facets(square)
    want = np.array([[1, 0, 1], [-1, 0, 1], [0, 1, 1], [0, -1, 1]]) / math.sqrt(2)
    assert len(rows) == 4 and hausdorff(rows, want) <= 1e-12


def test_polish_vertices_never_drops_two_points_that_cover_each_other():
    """A boundary bulging by 15 tol over A=(0,0) .. B=(3,0) through p=(1, h), q=(2, h): p is
    7.5 tol from the segment A-q and q from p-B, so each alone is redundant to 10 tol, but
    dropping both loses 15 tol. One of them must stay, and every point must lie within
    10 tol of the hull of what is kept."""
    tol = 1e-6
    h = 15 * tol
    a, p, q, b = (0.0, 0.0), (1.0, h), (2.0, h), (3.0, 0.0)
    points = np.array([a, p, q, b, (3.0, -1.0), (0.0, -1.0)])

    def edge(u, v):  # outward normal (the polygon is clockwise) and offset of the line u-v
        n = np.array([v[1] - u[1], u[0] - v[0]])
        n = -n / np.linalg.norm(n)
        return n, float(n @ np.array(u))

    rows = [edge(a, p), edge(p, q), edge(q, b), ((1.0, 0.0), 3.0), ((0.0, -1.0), 1.0), ((-1.0, 0.0), 0.0)]
    normals = np.array([r[0] for r in rows], dtype=float)
    offsets = np.array([r[1] for r in rows])
    assert np.all(points @ normals.T - offsets <= 1e-12)  # the rows hold for the polygon
    verts, _, _ = polish_vertices(points, normals, offsets, tol)
    assert any(np.allclose(v, p) or np.allclose(v, q) for v in verts)
    for x in points:  # within 10 tol of the kept hull: distance to the chord through kept points
        kept_top = sorted([tuple(v) for v in verts if v[1] > -0.5])
        xs, ys = zip(*kept_top, strict=True)
        assert x[1] <= np.interp(x[0], xs, ys) + 10 * tol
