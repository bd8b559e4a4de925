"""The drawable geometry for the viewer (mjtvm.grasp.scene): plain arrays, MuJoCo's poses."""

from __future__ import annotations

import numpy as np

from mjtvm.grasp.scene import scene_geometry, scene_poses
from mjtvm.paper_hand.scenario import load_scenario


def test_case1_geometry_and_poses_match_mujoco() -> None:
    sc = load_scenario("case1")
    model, data = sc.model, sc.data
    geo = scene_geometry(model, sc.object_body)
    assert len(geo.links) > 0 and len(geo.tips) > 0 and len(geo.object) == 1 and len(geo.planes) >= 1
    ob = model.body(sc.object_body).id
    assert all(model.geom_bodyid[g] == ob for g in geo.object.ids)
    assert not any(model.geom_bodyid[g] == ob for g in geo.tips.ids)
    np.testing.assert_array_equal(geo.links.size, model.geom_size[geo.links.ids])
    poses = scene_poses(model, geo, np.vstack([data.qpos, data.qpos]))
    assert poses.link_pos.shape == (2, len(geo.links), 3) and poses.link_quat.shape == (2, len(geo.links), 4)
    np.testing.assert_array_equal(poses.link_pos[0], poses.link_pos[1])
    np.testing.assert_allclose(poses.tip_pos[0], data.geom_xpos[geo.tips.ids], atol=1e-12)
    np.testing.assert_allclose(poses.object_pos[0], data.geom_xpos[geo.object.ids], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(poses.link_quat, axis=2), 1.0, atol=1e-12)
