"""DexGraspBench's hold test (mjtvm.physics.disturb) on a dataset grasp (mjtvm.physics.grasp_sim)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mjtvm.errors import ParamError
from mjtvm.grasp.document.dataset import read_dataset
from mjtvm.grasp.resolve.batch import BatchModels, hand_joints
from mjtvm.jobs.replay import grasp_defaults
from mjtvm.physics.disturb import DIRECTIONS, DISTURB_ACCEL, disturb_test
from mjtvm.physics.grasp_sim import dataset_sim_model
from mjtvm.physics.squeeze import squeeze_drive
from mjtvm.physics.witness import witness_drive
from mjtvm.problem2.tvmmp import tvmmp

ROOT = Path(__file__).resolve().parents[2]
GRASP = ROOT / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml"
DATASET = ROOT / "mjtvm" / "data" / "examples" / "shadow-sphere-dataset.npz"


def test_pushes_along_six_directions_with_the_benchmark_force() -> None:
    batch = BatchModels.from_file(GRASP)
    model = batch.model()
    entry = read_dataset(DATASET, nq=model.nq, num_joints=len(hand_joints(model, "ball")))[1]
    grasp = batch.grasp(entry, max_penetration=math.inf)
    state = grasp.state()
    res = tvmmp(state, witnesses=True)
    mu, mg = grasp_defaults(grasp, None, None)
    sim = dataset_sim_model(grasp, state, mu=mu, mg=mg)
    ball = sim.body("ball").id
    assert float(sim.body_mass[ball]) * 9.81 == pytest.approx(mg, rel=1e-3)
    # the dataset's scale and the posed base are the grasp's, not the grasp file's
    assert np.allclose(
        sim.geom_size[sim.body_geomadr[ball]], grasp.model.geom_size[grasp.model.body_geomadr[ball]]
    )
    assert entry.obj_scale != 1.0
    rest = witness_drive(state, 0, 0, float(res.alpha[0, 0]), 0.0, witness="central")
    qpos = grasp.data.qpos.copy()
    # the least forces on speed-0 dampers and torsionless contacts (the drive before the squeeze)
    r = disturb_test(sim, qpos, rest, object_body="ball", duration=0.4, servo=0.0, torsional=0.0)
    assert r.force == pytest.approx(DISTURB_ACCEL * mg / 9.81, rel=1e-3)
    held = dict(zip(DIRECTIONS, r.directions, strict=True))
    # pushed up, the fingers carry less than the weight they hold; pushed along -x, the
    # witness's least forces let go and the ball leaves the 5 cm bound
    assert held["+z"] and not held["-x"] and not r.held
    assert r.first_failure == "-x" and r.translation[0] >= 0.05 and r.translation[5] < 0.05
    early = disturb_test(
        sim, qpos, rest, object_body="ball", duration=0.4, stop_early=True, servo=0.0, torsional=0.0
    )
    assert early.directions == (False,) * 6 and math.isnan(early.translation[1])
    # the protocol's drive: the squeeze and its position loop hold every push
    sq = squeeze_drive(state, res)
    assert sq is not None
    r = disturb_test(sim, qpos, sq, object_body="ball", duration=0.4)
    assert r.held and max(r.translation) < 5e-3 and max(r.rotation) < 5.0, r
    with pytest.raises(ParamError, match="duration"):
        disturb_test(sim, qpos, rest, object_body="ball", duration=0.0)
    with pytest.raises(ParamError, match="torsional"):
        disturb_test(sim, qpos, rest, object_body="ball", duration=0.2, torsional=-1.0)
