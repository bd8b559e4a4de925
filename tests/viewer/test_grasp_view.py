"""The friction cones of ``mjtvm show --rrd`` (mjtvm.viewer.grasp_view.cone_mesh)."""

from __future__ import annotations

import numpy as np
import pytest

from mjtvm.viewer.grasp_view import CONE_SIDES, cone_mesh


@pytest.mark.parametrize("normal", [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.3, -0.5, 0.8]])
def test_cone_is_the_friction_cone(normal: list[float]) -> None:
    """Apex at the contact point; every rim vertex at the height along the unit normal and at
    mu times the height from the axis (tan of the half-angle = mu); outward-consistent fan."""
    apex, mu, h = np.array([0.1, -0.2, 0.3]), 0.6, 0.015
    n = np.array(normal) / np.linalg.norm(normal)
    vertices, triangles = cone_mesh(apex, np.array(normal), mu, height=h)
    assert vertices.shape == (CONE_SIDES + 1, 3) and triangles.shape == (CONE_SIDES, 3)
    np.testing.assert_array_equal(vertices[0], apex)
    rel = vertices[1:] - apex
    np.testing.assert_allclose(rel @ n, h, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(rel - np.outer(rel @ n, n), axis=1), mu * h, rtol=1e-12)
    assert set(triangles[:, 0]) == {0} and sorted(triangles[:, 1]) == list(range(1, CONE_SIDES + 1))
