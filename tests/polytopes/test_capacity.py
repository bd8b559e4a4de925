"""Zonotopes, velocity and force polytopes (mjtvm.polytopes.zonotope, mjtvm.polytopes.capacity).

Every expected value is independent of the code under test: the velocity polytope against
the hull of all 2^n images of the box's corners (scipy's Qhull) and Shephard's volume
sum over all m-subsets of generators, the force polytope against the brute-force
enumeration of every choice of m active torque limits, closed forms for square Jacobians,
and pycapacity when it is installed.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from mjtvm.errors import ParamError
from mjtvm.polytopes.capacity import force_polytope, velocity_polytope
from mjtvm.polytopes.hull import distinct
from mjtvm.polytopes.volume import hausdorff
from mjtvm.polytopes.zonotope import zonotope

SIZES = [(2, 2), (2, 5), (3, 3), (3, 4), (3, 7), (3, 12), (4, 7), (5, 8), (6, 9)]


def corner_images(center: np.ndarray, gens: np.ndarray) -> np.ndarray:
    """All 2^n images c + G s, s in {-1, 1}^n."""
    return center + np.array(list(itertools.product((-1.0, 1.0), repeat=gens.shape[1]))) @ gens.T


def hull_vertices(points: np.ndarray) -> tuple[np.ndarray, float]:
    """The vertices of the hull of full-dimensional points and its volume (Qhull)."""
    h = ConvexHull(points)
    return points[h.vertices], float(h.volume)


def shephard_volume(gens: np.ndarray) -> float:
    """2^m sum over the m-subsets S of |det G_S| (a full-dimensional (m, n) G)."""
    m, n = gens.shape
    return 2.0**m * sum(abs(np.linalg.det(gens[:, list(s)])) for s in itertools.combinations(range(n), m))


def assert_same_points(a: np.ndarray, b: np.ndarray, rel: float = 1e-9) -> None:
    assert len(a) == len(b)
    assert hausdorff(a, b) <= rel * float(np.max(np.abs(b)))


@pytest.mark.parametrize(("m", "n"), SIZES)
def test_zonotope_matches_the_hull_of_the_corner_images(m: int, n: int) -> None:
    rng = np.random.default_rng(10 * m + n)
    c, g = rng.normal(size=m), rng.normal(size=(m, n))
    z = zonotope(c, g)
    verts, vol = hull_vertices(corner_images(c, g))
    assert z.dimension == m
    assert_same_points(z.vertices, verts)
    assert z.affine_volume == pytest.approx(vol, rel=1e-9)
    assert z.volume == pytest.approx(shephard_volume(g), rel=1e-9)
    assert np.allclose(z.vertices, c + (g @ z.signs.T).T)  # no merge happened: same generators
    # Every facet supports the vertices and touches at least m of them.
    slack = z.offsets[:, None] - z.normals @ z.vertices.T
    assert slack.min() >= -1e-12 * np.abs(z.vertices).max()
    assert np.all(np.sum(slack <= 1e-9 * np.abs(z.vertices).max(), axis=1) >= m)


def test_degenerate_generators_coplanar_parallel_and_zero() -> None:
    """In 3-D: three coplanar generators (a hexagonal facet), two parallel ones (merged: 2 e_x
    beside e_x), a zero one (dropped)."""
    g = np.array([[1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [2, 0, 0], [0, 0, 0], [1, -1, 0.0]]).T
    c = np.array([0.5, -1.0, 2.0])
    z = zonotope(c, g)
    verts, vol = hull_vertices(corner_images(c, g))
    assert z.generators.shape == (3, 5)
    assert_same_points(z.vertices, verts)
    assert z.affine_volume == pytest.approx(vol, rel=1e-12)
    assert z.affine_volume == pytest.approx(shephard_volume(g), rel=1e-12)


def test_rank_deficient_generators_span_a_plane() -> None:
    """Six generators in a plane of R^3: a 2-D zonogon of 12 vertices, volume 0, its area inside
    the plane as the 2-D hull of the corner images (in the plane's coordinates)."""
    rng = np.random.default_rng(4)
    g = rng.normal(size=(3, 2)) @ rng.normal(size=(2, 6))
    z = zonotope(np.zeros(3), g)
    assert z.dimension == 2 and z.volume == 0.0
    plane = np.linalg.svd(g)[0][:, :2].T
    local, area = hull_vertices(corner_images(np.zeros(3), g) @ plane.T)
    assert_same_points(z.vertices @ plane.T, local)
    assert z.affine_volume == pytest.approx(area, rel=1e-9)
    assert np.allclose(z.vertices - (z.vertices @ plane.T) @ plane, 0.0, atol=1e-12)


def test_segment_and_point() -> None:
    z = zonotope([1.0, 2.0], [[1.0, -2.0, 0.0], [0.5, -1.0, 0.0]])  # parallel: one segment
    assert z.dimension == 1
    assert_same_points(z.vertices, np.array([[1.0 + 3.0, 2.0 + 1.5], [1.0 - 3.0, 2.0 - 1.5]]))
    assert z.affine_volume == pytest.approx(2.0 * math.hypot(3.0, 1.5), rel=1e-12)
    p = zonotope([1.0, 2.0], np.zeros((2, 3)))
    assert p.dimension == 0 and p.vertices.tolist() == [[1.0, 2.0]] and p.affine_volume == 0.0


def test_velocity_polytope_of_a_square_jacobian_is_a_parallelepiped() -> None:
    """J [qd_min, qd_max] for square J: 2^m vertices J corner, volume |det J| prod(qd_max - qd_min)."""
    rng = np.random.default_rng(7)
    j = rng.normal(size=(3, 3))
    low, high = -rng.uniform(0.5, 2, 3), rng.uniform(0.5, 2, 3)
    p = velocity_polytope(j, low, high)
    corners = np.array(list(itertools.product(*zip(low, high, strict=True)))) @ j.T
    assert_same_points(p.vertices, corners)
    assert p.volume == pytest.approx(abs(np.linalg.det(j)) * np.prod(high - low), rel=1e-12)
    assert p.dimension == 3 and p.affine_volume == p.volume


@pytest.mark.parametrize("n", [3, 4, 7, 12])
def test_velocity_polytope_against_brute_force(n: int) -> None:
    rng = np.random.default_rng(n)
    j = rng.normal(size=(3, n))
    low, high = -rng.uniform(0.5, 2, n), rng.uniform(0.5, 2, n)
    p = velocity_polytope(j, low, high)
    pts = np.array(list(itertools.product(*zip(low, high, strict=True)))) @ j.T
    verts, vol = hull_vertices(pts)
    assert_same_points(p.vertices, verts)
    assert p.volume == pytest.approx(vol, rel=1e-9)


def force_brute_force(j: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Every choice of m active limits J_i^T f = tau_i, kept where all limits hold."""
    m, n = j.shape
    rows, bounds = np.vstack([j.T, -j.T]), np.concatenate([high, -low])
    pts = []
    for s in itertools.combinations(range(2 * n), m):
        a = rows[list(s)]
        if abs(np.linalg.det(a)) < 1e-12:
            continue
        x = np.linalg.solve(a, bounds[list(s)])
        if np.all(rows @ x <= bounds + 1e-9 * np.abs(bounds).max()):
            pts.append(x)
    pts_a = np.array(pts)
    return distinct(pts_a, 1e-9 * np.abs(pts_a).max())


@pytest.mark.parametrize(("m", "n"), [(1, 3), (2, 4), (3, 3), (3, 4), (3, 7), (3, 12), (6, 9)])
def test_force_polytope_against_brute_force(m: int, n: int) -> None:
    rng = np.random.default_rng(100 + 10 * m + n)
    j = rng.normal(size=(m, n))
    low, high = -rng.uniform(1, 3, n), rng.uniform(1, 3, n)
    p = force_polytope(j, low, high)
    assert_same_points(p.vertices, force_brute_force(j, low, high))
    if m > 1:
        assert p.volume == pytest.approx(ConvexHull(force_brute_force(j, low, high)).volume, rel=1e-9)
    slack = p.offsets[:, None] - p.normals @ p.vertices.T
    assert slack.min() >= -1e-9 * np.abs(p.vertices).max()


def test_force_polytope_off_the_origin_and_square_closed_form() -> None:
    """Limits that exclude f = 0 (the Chebyshev centre is used); for square J the polytope is
    J^-T [tau_min, tau_max], volume prod(tau_max - tau_min) / |det J|."""
    rng = np.random.default_rng(3)
    j = rng.normal(size=(3, 3))
    low, high = rng.uniform(0.5, 1, 3), rng.uniform(1.5, 2, 3)
    p = force_polytope(j, low, high)
    corners = np.linalg.solve(j.T, np.array(list(itertools.product(*zip(low, high, strict=True)))).T).T
    assert_same_points(p.vertices, corners)
    assert p.volume == pytest.approx(np.prod(high - low) / abs(np.linalg.det(j)), rel=1e-9)


def test_bad_arguments_name_the_field() -> None:
    j = np.eye(3)
    with pytest.raises(ParamError, match=r"jacobian.*expected an \(m, n\) array"):
        velocity_polytope(np.ones(3), -np.ones(3), np.ones(3))
    with pytest.raises(ParamError, match=r"qd_max.*expected 3 finite numbers"):
        velocity_polytope(j, -np.ones(3), [1.0, np.nan, 1.0])
    with pytest.raises(ParamError, match=r"qd_min.*qd_min <= qd_max.*joint 1"):
        velocity_polytope(j, [-1.0, 2.0, -1.0], np.ones(3))
    with pytest.raises(ParamError, match=r"tau_min.*tau_min < tau_max"):
        force_polytope(j, np.ones(3), np.ones(3))
    with pytest.raises(ParamError, match=r"jacobian.*expected rank 3"):
        force_polytope(
            np.array([[1.0, 0, 0], [0, 1, 0], [1, 1, 0]]).T @ np.diag([1, 1, 0]), -np.ones(3), np.ones(3)
        )
    with pytest.raises(ParamError, match=r"tau_min.*meets strictly"):
        force_polytope(np.array([[1.0, 1.0]]), [1.0, -3.0], [2.0, -2.0])
    with pytest.raises(ParamError, match=r"generators.*enumeration entries"):
        zonotope(np.zeros(6), np.random.default_rng(0).normal(size=(6, 60)))


def test_same_vertices_as_pycapacity() -> None:
    import pycapacity.robot as pycapacity  # a test dependency ([test] extra): never skipped

    for n in (3, 4, 7, 12):
        rng = np.random.default_rng(200 + n)
        j = rng.normal(size=(3, n))
        low, high = -rng.uniform(0.5, 2, n), rng.uniform(0.5, 2, n)
        theirs = pycapacity.velocity_polytope(j, high, low).vertices.T
        ours = velocity_polytope(j, low, high).vertices
        # pycapacity's vertices come from Qhull's halfspace intersection, one per simplicial
        # facet of its dual: the same points, some repeated.
        assert hausdorff(ours, theirs) <= 1e-9 * np.abs(ours).max()
        assert len(distinct(theirs, 1e-9 * np.abs(ours).max())) == len(ours)
        tmin, tmax = -rng.uniform(1, 3, n), rng.uniform(1, 3, n)
        theirs_f = pycapacity.force_polytope(j, tmax, tmin).vertices.T
        ours_f = force_polytope(j, tmin, tmax).vertices
        # pycapacity rounds the torques of its vertices to 1e-7.
        assert len(theirs_f) == len(ours_f)
        assert hausdorff(ours_f, theirs_f) <= 1e-6 * np.abs(ours_f).max()


def test_force_polytope_with_a_vertex_on_three_limits() -> None:
    """|f_x| <= 1, |f_y| <= 1, |f_x + f_y| <= 2: the square, whose corners +-(1, 1) lie on three
    limits each (Qhull's two simplices there give one vertex)."""
    p = force_polytope(np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]), [-1.0, -1.0, -2.0], [1.0, 1.0, 2.0])
    assert_same_points(p.vertices, np.array([[1.0, 1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, -1.0]]))
    assert p.volume == pytest.approx(4.0, rel=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_degenerate_integer_generators_against_the_corner_images(seed: int) -> None:
    """Small integer generators: zero, parallel and coplanar ones everywhere, spans of every
    dimension. Vertices (as many), facets and volume against the hull of the corner images
    inside their span."""
    rng = np.random.default_rng(seed)
    for _ in range(25):
        m, n = int(rng.integers(2, 5)), int(rng.integers(1, 8))
        g = rng.integers(-2, 3, size=(m, n)).astype(float)
        c = rng.integers(-2, 3, size=m).astype(float)
        z = zonotope(c, g)
        assert z.dimension == (np.linalg.matrix_rank(g) if g.any() else 0)
        if z.dimension == 0:
            assert z.vertices.tolist() == [c.tolist()]
            continue
        local = (corner_images(c, g) - c) @ z.basis.T
        ours = (z.vertices - c) @ z.basis.T
        if z.dimension == 1:
            assert np.sort(ours[:, 0]) == pytest.approx([local.min(), local.max()], abs=1e-12)
            continue
        verts, vol = hull_vertices(local)
        assert_same_points(ours, verts)
        assert z.affine_volume == pytest.approx(vol, rel=1e-9)
        assert (z.offsets[:, None] - z.normals @ z.vertices.T).min() >= -1e-9


@pytest.mark.parametrize("seed", range(3))
def test_degenerate_integer_jacobians_force_polytope(seed: int) -> None:
    rng = np.random.default_rng(50 + seed)
    for _ in range(20):
        m = int(rng.integers(2, 4))
        n = int(rng.integers(m, 7))
        j = rng.integers(-2, 3, size=(m, n)).astype(float)
        low, high = -rng.integers(1, 4, size=n).astype(float), rng.integers(1, 4, size=n).astype(float)
        if np.linalg.matrix_rank(j) < m:
            with pytest.raises(ParamError, match=r"^jacobian: expected rank"):
                force_polytope(j, low, high)
            continue
        p = force_polytope(j, low, high)
        expected = force_brute_force(j, low, high)
        assert_same_points(p.vertices, expected)
        assert p.volume == pytest.approx(ConvexHull(expected).volume, rel=1e-9)
