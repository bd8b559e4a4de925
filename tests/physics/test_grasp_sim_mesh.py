"""``rank --verify`` on a mesh object of DexGraspBench's layout: the sim model carries the grasp's object."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ModelError
from mjtvm.jobs.rank import batch_models
from mjtvm.jobs.rank_inputs import read_datasets
from mjtvm.jobs.rank_sim import sim_columns
from mjtvm.jobs.replay import grasp_defaults
from mjtvm.physics.grasp_sim import dataset_sim_model, motorized_model
from mjtvm.problem2.tvmmp import tvmmp

ROOT = Path(__file__).resolve().parents[2]
GRASP = str(ROOT / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml")
TREE = ROOT / "tests" / "data" / "datasets" / "dexgraspbench" / "output"


def test_a_mesh_object_grasp_is_simulated_on_its_own_object() -> None:
    batch = batch_models(GRASP)
    entry = next(e for e in read_datasets(GRASP, [str(TREE)]) if e.id == "ellipsoid_01/scale009_pose000/0")
    grasp = batch.grasp(entry, max_penetration=math.inf)
    state = grasp.state()
    with pytest.raises(ModelError, match="differs from the grasp"):  # the file's sphere: not this object
        dataset_sim_model(grasp, state, mu=1.0, mg=1.0)
    motorized = motorized_model(grasp, batch.spec(entry))
    mu, mg = grasp_defaults(grasp, None, None)
    model = dataset_sim_model(grasp, state, mu=mu, mg=mg, motorized=motorized)
    ob = int(model.body(grasp.object_body).id)
    pieces = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) == ob]
    # The object folder's two convex pieces, vertex for vertex, at the grasp's pose.
    assert [int(model.geom_type[g]) for g in pieces] == [int(mujoco.mjtGeom.mjGEOM_MESH)] * 2
    assert np.array_equal(model.mesh_vert, grasp.model.mesh_vert) and model.nmeshvert > 0
    assert model.body_subtreemass[ob] * np.linalg.norm(model.opt.gravity) == pytest.approx(mg)
    assert state.transmission is not None  # the coupled hand: one <dcmotor> per actuator added
    assert model.nu == grasp.model.nu + len(state.transmission.actuator_names)
    result = tvmmp(state, witnesses=True, diagnose=True)
    cols = sim_columns(grasp, state, result, hold_time=0.2, batch=batch, entry=entry)
    assert cols["sim_hold"] is not None and cols["sim_speed_dirs"] == 4
    assert not cols["sim_failure"].startswith("not simulated")
