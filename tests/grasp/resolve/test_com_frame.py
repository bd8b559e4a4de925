"""The object's frame at its centre of mass (``mjtvm rank --com-frame``; docs/datasets.md)."""

from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np
import pytest

from mjtvm.grasp.document.dataset import read_dataset
from mjtvm.grasp.resolve.batch import BatchModels, hand_joints

DATA = Path(__file__).resolve().parents[2] / "data" / "datasets" / "dexgraspbench"
GRASP = Path(__file__).resolve().parents[3] / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml"


def test_the_frame_moves_to_the_centre_of_mass_and_the_object_stays(tmp_path: Path) -> None:
    # One half of an ellipsoid: its centre of mass is well off its frame's origin.
    tree = tmp_path / "bench"
    shutil.copytree(DATA, tree)
    shutil.rmtree(tree / "assets/object/ellipsoid_00/urdf/meshes")
    (tree / "assets/object/ellipsoid_00/urdf/meshes").mkdir()
    shutil.copy(
        DATA / "assets/object/ellipsoid_00/urdf/meshes/convex_piece_000.obj",
        tree / "assets/object/ellipsoid_00/urdf/meshes/convex_piece_000.obj",
    )
    batch = BatchModels.from_file(GRASP)
    base = batch.model()
    names = hand_joints(base, "ball")
    source = tree / "output/shadow/graspdata/ellipsoid_00/scale009_pose000/0.npy"
    (entry,) = read_dataset(source, nq=int(base.nq), num_joints=len(names), joint_names=names)
    plain, com = batch.grasp(entry), batch.grasp(replace(entry, com_frame=True))
    ob = int(plain.model.body("ball").id)
    offset = np.array(plain.model.body_ipos[ob])
    assert np.linalg.norm(offset) > 0.005  # the half's centre of mass, some mm above its base
    assert np.allclose(com.model.body_ipos[int(com.model.body("ball").id)], 0.0, atol=1e-9)
    rot = np.zeros(9)
    assert entry.obj_pose is not None
    mujoco.mju_quat2Mat(rot, entry.obj_pose[3:])
    assert np.allclose(com.data.xpos[ob], plain.data.xpos[ob] + rot.reshape(3, 3) @ offset, atol=1e-9)
    geoms = [g for g in range(plain.model.ngeom) if int(plain.model.geom_bodyid[g]) == ob]
    assert geoms and np.allclose(com.data.geom_xpos[geoms], plain.data.geom_xpos[geoms], atol=1e-9)
    assert com.model.body_mass[ob] == pytest.approx(plain.model.body_mass[ob]) == pytest.approx(0.08)
