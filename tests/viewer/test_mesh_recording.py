"""A mesh object in the replay's rerun recording (``/scene/meshes/<k>``): its pieces' triangles
under a transform to each piece's pose, read back with rerun's own query API and compared
with the vertices written in the model file moved by the object body's pose."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import datafusion  # noqa: F401  # the rerun-sdk[catalog] extra (part of .[test]); read-back needs it
import mujoco
import numpy as np
import pytest
from rerun.server import Server

from mjtvm.cli import main
from mjtvm.grasp.resolve.file import shipped_grasps
from mjtvm.grasp.scene import scene_geometry, scene_poses
from mjtvm.lift.trajectory import scripted_lift

NAME = "allegro-jenga"
STATES = 2


def _source_vertices() -> dict[str, np.ndarray]:
    """Each mesh's ``vertex`` attribute as written in the model file (the object's frame, m)."""
    text = shipped_grasps()[NAME].with_name("allegro_jenga.xml").read_text(encoding="utf-8")
    root = ET.fromstring(re.sub(r"<include [^>]*/>", "", text))
    return {
        m.get("name", ""): np.array(m.get("vertex", "").split(), dtype=float).reshape(-1, 3)
        for m in root.iter("mesh")
    }


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    out = np.zeros(9)
    mujoco.mju_quat2Mat(out, np.asarray(q, dtype=float))
    return out.reshape(3, 3)


def _same_points(a: np.ndarray, b: np.ndarray, atol: float) -> None:
    assert a.shape == b.shape
    for p in a:  # every point of a has one of b within atol (MuJoCo may reorder vertices)
        assert float(np.min(np.linalg.norm(b - p, axis=1))) < atol


def test_scene_meshes_are_the_source_vertices_at_the_object_pose() -> None:
    lift = scripted_lift(NAME, num_states=STATES)
    model = lift.scenario.model
    geo = scene_geometry(model, "jenga")
    assert geo.meshes.names == tuple(f"jenga_piece{k}" for k in (3, 9, 10, 11, 13, 15))
    poses = scene_poses(model, geo, lift.qpos)
    source = _source_vertices()
    data = mujoco.MjData(model)
    for i in range(STATES):
        data.qpos[:] = lift.qpos[i]
        mujoco.mj_kinematics(model, data)
        body_rot, body_pos = data.xmat[geo.object_body].reshape(3, 3), data.xpos[geo.object_body]
        np.testing.assert_array_equal(poses.object_origin[i], body_pos)
        for k, name in enumerate(geo.meshes.names):
            drawn = geo.meshes.vertices[k] @ _quat_matrix(poses.mesh_quat[i, k]).T + poses.mesh_pos[i, k]
            _same_points(drawn, source[name] @ body_rot.T + body_pos, atol=1e-7)  # float32 storage
            assert geo.meshes.triangles[k].max() < len(geo.meshes.vertices[k])


def _read(path: Path) -> Any:
    with Server(host="127.0.0.1", datasets={"lift": [str(path)]}) as server:
        client = server.client()  # kept alive until the query has run
        return client.get_dataset("lift").reader(index="state").to_pandas()


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_replay_recording_draws_the_pieces(tmp_path: Path) -> None:
    rrd = tmp_path / "lift.rrd"
    args = ["replay", "--grasp", NAME, "--states", str(STATES), "--no-sweeps", "--no-plots", "--quiet"]
    assert main([*args, "--out", str(tmp_path), "--rrd", str(rrd), "--tvms-every", "0"]) == 0
    frame = _read(rrd)
    lift = scripted_lift(NAME, num_states=STATES)
    model = lift.scenario.model
    geo = scene_geometry(model, "jenga")
    poses = scene_poses(model, geo, lift.qpos)
    for k in range(len(geo.meshes)):
        path = f"/scene/meshes/{k}"
        for i in range(STATES):
            row = frame[frame["state"] == i]
            verts = np.stack(row[f"{path}:Mesh3D:vertex_positions"].iloc[0]).astype(float)
            tris = np.stack(row[f"{path}:Mesh3D:triangle_indices"].iloc[0]).astype(np.int64)
            np.testing.assert_allclose(verts, geo.meshes.vertices[k], atol=1e-7)  # rerun: float32
            np.testing.assert_array_equal(tris, geo.meshes.triangles[k])
            translation = np.asarray(row[f"{path}:Transform3D:translation"].iloc[0][0], dtype=float)
            quaternion = np.asarray(row[f"{path}:Transform3D:quaternion"].iloc[0][0], dtype=float)
            np.testing.assert_allclose(translation, poses.mesh_pos[i, k], atol=1e-7)
            np.testing.assert_allclose(quaternion, poses.mesh_quat[i, k][[1, 2, 3, 0]], atol=1e-7)
