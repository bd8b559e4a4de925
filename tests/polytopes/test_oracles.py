"""LP oracles on S_ov: support, ray shooting and distance on a TVMS derived by hand."""

from __future__ import annotations

import numpy as np
import pytest

from mjtvm.polytopes.lifted import lifted_polytope
from mjtvm.polytopes.oracles import DistanceOracle, RayShooter, SupportOracle

from ..helpers import max_speed
from .test_projection import G_F, MG, J, gripper


@pytest.fixture(scope="module")
def parallelogram():
    r"""The gripper of test_projection's hand-derived case: S_ov = {(J qd, 0) : |qd_j| <= s_j}.

    Working coordinates u = (v_x, v_y) (the linear hull is the plane w = 0)."""
    state = gripper(J, [[0.0, -MG, 0.0]])
    tau = J.T @ [0.0, MG] + G_F
    s = np.array([max_speed(tau[0]), max_speed(tau[1])])
    basis = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    poly = lifted_polytope(state)
    rows = basis @ poly.generators
    return poly, basis, rows, s


def test_support_is_the_parallelogram_support(parallelogram):
    poly, basis, _, s = parallelogram
    oracle = SupportOracle(poly, np.ones(3))
    for h in ([1.0, 0.0], [0.3, -2.0], [-1.0, 1.0]):
        status, point = oracle(basis.T @ np.array(h))
        # max over |qd_j| <= s_j of h^T J qd = sum_j s_j |(J^T h)_j|
        assert status == "optimal"
        assert np.dot(h, point[:2]) == pytest.approx(np.sum(s * np.abs(J.T @ h)), rel=1e-9)


def test_a_ray_leaves_through_the_expected_edge(parallelogram):
    """From the centre towards J (2 s_1, 0): the ray meets the edge qd_1 = s_1 at t = 1/2,
    whose outward normal is J^{-T} e_1 (normalised)."""
    poly, _, rows, s = parallelogram
    shooter = RayShooter(poly, rows, np.zeros(2))
    t, normal = shooter(J @ [2 * s[0], 0.0])
    expected = np.linalg.inv(J).T @ [1.0, 0.0]
    assert t == pytest.approx(0.5, abs=1e-9)
    np.testing.assert_allclose(normal, expected / np.linalg.norm(expected), atol=1e-9)
    t, _ = shooter(J @ [0.5 * s[0], -0.5 * s[1]])  # inside: the ray reaches its end
    assert t == pytest.approx(1.0, abs=1e-12)


def test_a_ray_is_measured_in_the_length_of_its_direction(parallelogram):
    """The t column is rescaled for each direction (a power of 2 per ray): the same ray through
    the edge qd_1 = s_1, asked with directions 1e-9 to 1e9 times as long and alternating so that
    each LP starts from the last one's factor, leaves at t = 1 / (2 lambda) for J (2 lambda s_1, 0)
    and reaches the end of every direction that stays inside."""
    poly, _, rows, s = parallelogram
    shooter = RayShooter(poly, rows, np.zeros(2))
    expected = np.linalg.inv(J).T @ [1.0, 0.0]
    for length in (1.0, 1e-9, 1e9, 3.0, 1e-3, 1e6, 1.0):
        t, normal = shooter(J @ [2 * s[0] * length, 0.0])
        if length >= 1.0:
            assert t == pytest.approx(0.5 / length, rel=1e-9)
            np.testing.assert_allclose(normal, expected / np.linalg.norm(expected), atol=1e-9)
        else:  # the end J (2 length s_1, 0) lies inside
            assert t == pytest.approx(1.0, abs=1e-12)


def test_distance_and_separating_hyperplane(parallelogram):
    """A point beyond the corner J (s_1, s_2): its max-norm distance to the parallelogram,
    computed independently by a grid over the boundary, and a hyperplane that separates it
    by at least that much."""
    poly, basis, rows, s = parallelogram
    oracle = DistanceOracle(poly, rows)
    corner = J @ s
    point = corner + np.array([0.3, -0.1])
    delta, g = oracle(point)
    grid = np.linspace(-1.0, 1.0, 2001)
    edges = np.vstack(
        [J @ np.array([a * s[0], b * s[1]]) for a in grid for b in (-1.0, 1.0)]
        + [J @ np.array([a * s[0], b * s[1]]) for b in grid for a in (-1.0, 1.0)]
    )
    brute = np.min(np.max(np.abs(edges - point), axis=1))
    assert delta == pytest.approx(brute, rel=1e-3)
    support = SupportOracle(poly, np.ones(3))(basis.T @ g)[1][:2]
    assert g @ point - g @ support >= delta - 1e-9
    assert DistanceOracle(poly, rows)(J @ (0.5 * s))[0] == pytest.approx(0.0, abs=1e-9)
