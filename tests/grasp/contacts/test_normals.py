"""Exact object normals (``mjtvm.grasp.contacts.normals``): closed forms for each primitive, and which pairs
use them (MuJoCo's closed-form pairs keep MuJoCo's normal)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from mjtvm.grasp.contacts.normals import needs_exact_normal, object_normal

XML = """<mujoco><worldbody>
  <geom name="box" type="box" size="0.1 0.2 0.3" pos="1 0 0" euler="0 0 90"/>
  <geom name="cyl" type="cylinder" size="0.1 0.2" pos="0 1 0"/>
  <geom name="ell" type="ellipsoid" size="0.1 0.2 0.3" pos="0 0 1"/>
  <geom name="sph" type="sphere" size="0.1" pos="2 0 0"/>
  <geom name="cap" type="capsule" size="0.1 0.2" pos="3 0 0"/>
  <geom name="pln" type="plane" size="1 1 1" pos="0 0 -1"/>
</worldbody></mujoco>"""


@pytest.fixture(scope="module")
def scene() -> tuple[mujoco.MjModel, mujoco.MjData]:
    m = mujoco.MjModel.from_xml_string(XML)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return m, d


def _n(scene, name, point):
    m, d = scene
    return object_normal(m, d, m.geom(name).id, np.array(point, dtype=float))


def test_closed_forms(scene) -> None:
    # the box turned 90 deg about z: its local +x face (half-size 0.1) faces world +y
    np.testing.assert_allclose(_n(scene, "box", [1.0, 0.1, 0.05]), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(_n(scene, "box", [1.0, 0.0, -0.3]), [0, 0, -1], atol=1e-15)
    assert _n(scene, "box", [1.2, 0.1, 0.3]) is None  # a corner: no unique normal
    np.testing.assert_allclose(_n(scene, "cyl", [0.06, 1.08, 0.0]), [0.6, 0.8, 0], atol=1e-15)  # side: radial
    np.testing.assert_allclose(_n(scene, "cyl", [0.02, 1.0, 0.2]), [0, 0, 1], atol=1e-15)  # cap
    # ellipsoid: gradient (x/a^2, y/b^2, z/c^2) at the surface point along the ray
    p = np.array([0.1, 0.2, 0.3]) / np.sqrt(3.0)
    g = p / np.array([0.1, 0.2, 0.3]) ** 2
    np.testing.assert_allclose(
        _n(scene, "ell", p + np.array([0.0, 0.0, 1.0])), g / np.linalg.norm(g), atol=1e-12
    )
    np.testing.assert_allclose(_n(scene, "sph", [2.0, 0.06, 0.08]), [0, 0.6, 0.8], atol=1e-15)
    np.testing.assert_allclose(_n(scene, "cap", [3.06, 0.0, 0.28]), [0.6, 0, 0.8], atol=1e-12)  # end cap


def test_which_pairs(scene) -> None:
    m, _ = scene
    g = {n: m.geom(n).id for n in ("box", "cyl", "ell", "sph", "cap", "pln")}
    assert needs_exact_normal(m, g["cyl"], g["box"]) and needs_exact_normal(m, g["sph"], g["ell"])
    assert needs_exact_normal(m, g["box"], g["cyl"]) and needs_exact_normal(m, g["cyl"], g["cap"])
    for a, b in (
        ("sph", "sph"),
        ("sph", "cap"),
        ("box", "sph"),
        ("box", "box"),
        ("cap", "box"),
        ("box", "pln"),
        ("cyl", "sph"),
    ):
        assert not needs_exact_normal(m, g[a], g[b]), (a, b)
