"""Contacts: tangent bases, friction pyramids, S-point generators, validation."""

from __future__ import annotations

import numpy as np
import pytest

from mjtvm import Contact, StateError
from mjtvm.model import force_generators, tangent_basis

Z3 = np.zeros((3, 1))


@pytest.mark.parametrize(
    ("normal", "t1"),
    [
        ([0, 0, 1], [1, 0, 0]),  # tie between x and y: lowest index
        ([1, 0, 0], [0, 1, 0]),
        ([0.6, 0.8, 0], [0, 0, 1]),
        ([0, 0.6, 0.8], [1, 0, 0]),
        ([0.8, 0, 0.6], [0, 1, 0]),
    ],
)
def test_default_tangent_is_the_least_aligned_axis(normal, t1):
    basis = tangent_basis(np.array(normal, float))
    assert basis[0] == pytest.approx(t1)
    assert basis[1] == pytest.approx(np.cross(normal, t1))


def test_default_tangent_is_orthogonalised():
    n = np.array([0.6, 0.0, 0.8])
    t1 = tangent_basis(n)[0]  # least aligned: y (|0| < ...)
    assert t1 == pytest.approx([0, 1, 0])
    n = np.array([1.0, 2.0, 3.0]) / np.sqrt(14)
    t1 = tangent_basis(n)[0]  # x, made orthogonal: (1,0,0) - n_x n, normalised
    expected = np.array([1.0, 0, 0]) - n[0] * n
    assert t1 == pytest.approx(expected / np.linalg.norm(expected))


def test_pyramid_edges_lie_on_the_cone_at_the_schema_angles():
    mu = 0.3
    c = Contact("c", "F", [0, 0, 0], [0, 0, 1], Z3, mu=mu)
    e = force_generators(c, 16)
    assert e.shape == (3, 16)
    assert e[2] == pytest.approx(np.ones(16))
    theta = 2 * np.pi * np.arange(16) / 16
    assert e[0] == pytest.approx(mu * np.cos(theta)) and e[1] == pytest.approx(mu * np.sin(theta))


def test_given_tangent_orients_the_pyramid():
    c = Contact("c", "F", [0, 0, 0], [0, 0, 1], Z3, mu=0.5, tangent=[0, 1, 0])
    assert force_generators(c, 4)[:, 0] == pytest.approx([0, 0.5, 1])
    assert force_generators(c, 4)[:, 1] == pytest.approx([-0.5, 0, 1])  # t2 = n x t1 = -x


def test_planar_cone_is_two_edges_and_other_types():
    c = Contact("c", "F", [0, 0], [0, 1], [[0.0], [0.0]], mu=0.2)
    assert force_generators(c).T == pytest.approx(np.array([[-0.2, 1], [0.2, 1]]))
    assert force_generators(Contact("l", "L", [0, 0, 0], [0, 0, 1], Z3)).T == pytest.approx(
        np.array([[0, 0, 1.0]])
    )
    assert force_generators(Contact("d", "D", [0, 0, 0], [0, 0, 1], Z3)).shape == (3, 0)
    s = Contact("s", "S", [0, 0, 0], [0, 0, 1], Z3, mu=0.4, slide_direction=[3, 0, 5])
    assert force_generators(s).T == pytest.approx(
        np.array([[-0.4, 0, 1.0]])
    )  # n - mu s, s = +x (normal part dropped)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"type": "X"}, "type: expected one of F, L, S, D"),
        ({"normal": [0, 0, 0.9]}, "normal: expected a unit vector"),
        ({"normal": [0, 0, float("nan")]}, "normal: expected finite"),
        ({"position": [0, 0]}, "normal: expected 2 numbers"),
        ({"jacobian": [[0.0], [0.0]]}, "jacobian: expected 3 rows"),
        ({"mu": None}, "mu: required for a F contact"),
        ({"mu": -0.1}, "mu: expected a finite number >= 0"),
        ({"tangent": [0, 0, 1]}, "tangent: expected a non-zero direction orthogonal"),
        ({"type": "S"}, "slide_direction: required for an S contact"),
        (
            {"type": "S", "slide_direction": [0, 0, 2]},
            "slide_direction: has no component in the tangent plane",
        ),
        ({"slide_direction": [1, 0, 0]}, "slide_direction: only S contacts slide"),
        ({"name": ""}, "name"),
    ],
)
def test_invalid_contacts(kwargs, match):
    base = {"name": "c", "type": "F", "position": [0, 0, 0], "normal": [0, 0, 1], "jacobian": Z3, "mu": 0.3}
    with pytest.raises(StateError, match=match):
        Contact(**{**base, **kwargs})


def test_tangent_basis_second_row_is_numpys_cross_product():
    """tangent_basis writes n x t1 out (np.cross is slow): the very same bits, except where
    the difference is round-off of its terms (at most 1e-12 of them), which is exactly 0."""
    rng = np.random.default_rng(3)
    for _ in range(200):
        n = rng.normal(size=3) * 10.0 ** rng.integers(-6, 6)
        n /= np.linalg.norm(n)
        basis = tangent_basis(n)
        cross = np.cross(n, basis[0])
        t1 = basis[0]  # component i of n x t1 is n[i+1] t1[i+2] - n[i+2] t1[i+1]
        terms = np.abs(np.roll(n, -1) * np.roll(t1, -2)) + np.abs(np.roll(n, -2) * np.roll(t1, -1))
        cancelled = np.abs(cross) <= 1e-12 * terms
        np.testing.assert_array_equal(basis[1][~cancelled], cross[~cancelled])
        assert np.all(basis[1][cancelled] == 0.0)


def test_tangent_basis_has_exact_zeros_where_the_exact_tangent_has():
    """A normal with a zero-free direction: its default t1 is e_z made orthogonal, so
    t2 = n x t1 is parallel to n x e_z = (n_y, -n_x, 0): its z component is 0 exactly
    (1.7e-18 before the round-off rule, which put 1e12 coefficients into an S-point's LP)."""
    n = np.array([-0.17647411084705222, 0.9810715791269544, -0.07972104383465155])
    n /= np.linalg.norm(n)
    t1, t2 = tangent_basis(n)
    assert t2[2] == 0.0
    np.testing.assert_allclose(t2, np.cross(n, t1), rtol=0, atol=1e-16)
    np.testing.assert_allclose([t1 @ n, t2 @ n, t1 @ t2], 0.0, atol=1e-16)
