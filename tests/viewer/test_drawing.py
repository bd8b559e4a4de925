"""What the rerun recording draws (mjtvm.viewer.drawing): the convex-hull meshes of the velocity polytopes."""

from __future__ import annotations

import numpy as np

from mjtvm.viewer.drawing import hull_mesh


def test_hull_mesh_solid_flat_and_degenerate() -> None:
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    verts, tris = hull_mesh(np.vstack([cube, [[0.5, 0.5, 0.5]]]))  # type: ignore[misc]
    assert len(verts) == 8 and len(tris) == 12
    centre = verts.mean(axis=0)
    for t in tris:  # outward
        a, b, c = verts[t]
        assert np.cross(b - a, c - a) @ (a - centre) > 0
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], dtype=float)
    verts, tris = hull_mesh(square)  # type: ignore[misc]
    assert len(verts) == 4 and len(tris) == 2
    assert hull_mesh(np.array([[0, 0, 0], [1, 1, 1], [2, 2, 2]], dtype=float)) is None
