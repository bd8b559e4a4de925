"""The face lattice of an outer polytope: volumes in closed form and against Qhull, uniform points.

Closed forms: the cube [-1, 1]^k (2^k, simple), the cross-polytope (2^k / k!, every vertex on
2^(k-1) facets: its joggled polar hull has flat simplices) and the standard simplex (1 / k!);
random polytopes against one Qhull hull of their vertices (an independent computation).
Uniformity: the fraction of points in a sub-body of known volume, within 5 binomial standard
deviations (seeded: the test is deterministic).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull, HalfspaceIntersection

from mjtvm.polytopes.polar import PolarHull


def cube(k: int) -> tuple[np.ndarray, np.ndarray]:
    eye = np.eye(k)
    return np.vstack([eye, -eye]), np.ones(2 * k)


def cross(k: int) -> tuple[np.ndarray, np.ndarray]:
    signs = np.array(list(itertools.product([-1.0, 1.0], repeat=k)))
    return signs, np.ones(len(signs))


def simplex(k: int) -> tuple[np.ndarray, np.ndarray]:
    """``x >= 0``, ``sum x <= 1``."""
    return np.vstack([-np.eye(k), np.ones((1, k))]), np.append(np.zeros(k), 1.0)


@pytest.mark.parametrize("k", [2, 3, 4, 5, 6])
@pytest.mark.parametrize(
    "body,volume,center",
    [
        (cube, lambda k: 2.0**k, lambda k: np.full(k, 0.1)),
        (cross, lambda k: 2.0**k / math.factorial(k), lambda k: np.full(k, 0.05)),
        (simplex, lambda k: 1.0 / math.factorial(k), lambda k: np.full(k, 0.5 / (k + 1))),
    ],
    ids=["cube", "cross", "simplex"],
)
def test_volume_in_closed_form(k, body, volume, center):
    normals, offsets = body(k)
    lattice = PolarHull(normals, offsets, center(k), 1e-12).lattice()
    # 4e-8: the flat simplices' corners of the joggled polytope (bracket.outer_volume)
    assert lattice.volume == pytest.approx(volume(k), rel=1e-7)


@pytest.mark.parametrize("seed", range(4))
def test_volume_of_random_polytopes_against_qhull(seed):
    rng = np.random.default_rng(seed)
    k = 3 + seed  # 3-D to 6-D
    normals = rng.normal(size=(6 * k, k))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    offsets = rng.uniform(0.5, 1.5, len(normals))
    lattice = PolarHull(normals, offsets, np.zeros(k), 1e-12).lattice()
    corners = HalfspaceIntersection(np.column_stack([normals, -offsets]), np.zeros(k)).intersections
    assert lattice.volume == pytest.approx(ConvexHull(corners).volume, rel=1e-7)


@pytest.mark.parametrize("k", [2, 4, 6])
def test_points_are_uniform(k):
    """In the cross-polytope, the scaled copy |x|_1 <= 1/2 holds 2^-k of the volume, the
    orthant x > 0 holds 2^-k, the half x_0 > 0 half."""
    normals, offsets = cross(k)
    lattice = PolarHull(normals, offsets, np.full(k, 0.05), 1e-12).lattice()
    n = 200_000
    x = lattice.sample(n, np.random.default_rng(k))
    assert np.max(x @ normals.T - offsets) <= 1e-9
    for inside, p in [
        (np.abs(x).sum(axis=1) <= 0.5, 0.5**k),
        (np.all(x > 0, axis=1), 0.5**k),
        (x[:, 0] > 0, 0.5),
    ]:
        assert abs(np.mean(inside) - p) <= 5 * math.sqrt(p * (1 - p) / n)


def test_points_are_uniform_in_an_irregular_polytope():
    """A random 5-D polytope: the fraction of points in the half-space through its centroid
    along e_0 against the exact volume of that part (a Qhull hull of its corners)."""
    rng = np.random.default_rng(7)
    k = 5
    normals = rng.normal(size=(30, k))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    offsets = rng.uniform(0.5, 1.5, len(normals))
    lattice = PolarHull(normals, offsets, np.zeros(k), 1e-12).lattice()
    cut_n = np.vstack([normals, np.eye(k)[0]])
    part = HalfspaceIntersection(np.column_stack([cut_n, -np.append(offsets, 0.2)]), np.zeros(k))
    p = ConvexHull(part.intersections).volume / lattice.volume
    n = 100_000
    x = lattice.sample(n, np.random.default_rng(1))
    assert abs(np.mean(x[:, 0] <= 0.2) - p) <= 5 * math.sqrt(p * (1 - p) / n)
