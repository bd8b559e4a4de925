"""DexGraspBench's hold test (mjtvm.physics.disturb) on a dataset grasp (mjtvm.physics.grasp_sim)."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ParamError
from mjtvm.grasp.document.dataset import read_dataset
from mjtvm.grasp.resolve.batch import BatchModels, hand_joints
from mjtvm.jobs.replay import grasp_defaults
from mjtvm.physics.disturb import (
    DIRECTIONS,
    DISTURB_ACCEL,
    DISTURB_CHECK_EVERY,
    HOLD_SETTINGS,
    disturb_test,
)
from mjtvm.physics.grasp_sim import dataset_sim_model
from mjtvm.physics.rig import Rig
from mjtvm.physics.settings import SimSettings, with_integration
from mjtvm.physics.simulate import held
from mjtvm.physics.squeeze import (
    SERVO_GAIN,
    TORSIONAL_FRICTION,
    squeeze_drive,
    with_position_loop,
    with_torsion,
)
from mjtvm.physics.witness import witness_drive
from mjtvm.problem2.tvmmp import tvmmp
from tests.physics.test_squeeze import pinch

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


def _fresh_per_direction(model, qpos, drive, st, duration):  # type: ignore[no-untyped-def]
    """The hold test as the benchmark runs it, one direction after the other: a fresh reset and
    settle for every direction, ``mj_step`` on the native loop (`with_position_loop`, its
    feedforward ``tau + k_p l_0``), the pose read at each check (``mj_kinematics``), the solver's
    warm start dropped at each check after the first (as a new ``mujoco.rollout`` call starts)."""
    base = with_integration(with_torsion(model, TORSIONAL_FRICTION), st)
    rig = Rig(base, drive, "object")
    m = with_position_loop(base, rig.acts, SERVO_GAIN)
    force = DISTURB_ACCEL * float(m.body_subtreemass[rig.ob])
    every = st.steps(DISTURB_CHECK_EVERY)
    moved, turned, ok = [], [], []
    for i in range(len(DIRECTIONS)):
        d = held(m, qpos, rig, drive)
        p0, r0 = d.xpos[rig.ob].copy(), d.xmat[rig.ob].reshape(3, 3).copy()
        d.ctrl[rig.cadr + 1] += SERVO_GAIN * rig.kd * d.actuator_length[rig.acts]
        mujoco.mj_step(m, d, nstep=st.steps(st.settle))
        d.xfrc_applied[rig.ob, i // 2] = force * (1.0 if i % 2 else -1.0)
        worst_t = worst_r = 0.0
        passed = True
        for c in range(math.ceil(st.steps(duration) / every)):
            if c > 0:
                d.qacc_warmstart[:] = 0.0
            mujoco.mj_step(m, d, nstep=every)
            mujoco.mj_kinematics(m, d)
            rot = d.xmat[rig.ob].reshape(3, 3) @ r0.T
            t = float(np.linalg.norm(d.xpos[rig.ob] - p0))
            r = math.degrees(math.acos(max(-1.0, min(1.0, 0.5 * (float(np.trace(rot)) - 1.0)))))
            worst_t, worst_r = max(worst_t, t), max(worst_r, r)
            if not (t < 0.05 and r < 15.0):
                passed = False
                break
        ok.append(passed)
        moved.append(worst_t)
        turned.append(worst_r)
    return tuple(ok), tuple(moved), tuple(turned)


@pytest.mark.parametrize("settings", [SimSettings(), HOLD_SETTINGS], ids=["euler-0.25ms", "hold"])
def test_the_batched_pushes_are_a_fresh_reset_and_settle_per_direction(settings: SimSettings) -> None:
    # the hand-built pinch (tests/physics/test_squeeze.py), held by its least forces (share 0)
    # and by the squeeze: pushes that hold and pushes that fail are both compared
    model, qpos, state = pinch()
    res = tvmmp(state, witnesses=True)
    outcomes: set[bool] = set()
    for share in (0.0, 0.5):
        drive = squeeze_drive(state, res, share=share)
        assert drive is not None
        got = disturb_test(model, qpos, drive, settings=settings, duration=0.6)
        ok, moved, turned = _fresh_per_direction(model, qpos, drive, settings, 0.6)
        # the same steps from the same state: equal to the last bit, direction by direction
        assert got.directions == ok and got.translation == moved and got.rotation == turned
        # threads run the same rollouts (each from its own initial state)
        assert disturb_test(model, qpos, drive, settings=settings, duration=0.6, threads=2) == got
        # stopping early: the directions up to the first failure as without, then not run
        early = disturb_test(model, qpos, drive, settings=settings, duration=0.6, stop_early=True)
        f = ok.index(False) if False in ok else len(ok)
        assert early.directions == ok[: f + 1] + (False,) * (len(ok) - f - 1)
        assert early.translation[: f + 1] == moved[: f + 1]
        assert all(math.isnan(x) for x in early.translation[f + 1 :] + early.rotation[f + 1 :])
        outcomes |= set(ok)
    assert outcomes == {True, False}
    with pytest.raises(ParamError, match="threads"):
        disturb_test(model, qpos, drive, duration=0.2, threads=0)


def test_a_push_that_mujoco_stops_with_a_warning_does_not_hold(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # negative joint damping makes the implicit integrator's matrix singular: MuJoCo warns
    # (mjWARN_INERTIA) and mujoco.rollout stops the rollout there, its state frozen near the
    # start (the object moves < 1e-12 m): a frozen state is not a hold
    monkeypatch.chdir(tmp_path)  # MuJoCo writes its warning to MUJOCO_LOG.TXT in the cwd
    model, qpos, state = pinch()
    drive = squeeze_drive(state, tvmmp(state, witnesses=True))
    assert drive is not None
    assert disturb_test(model, qpos, drive, duration=0.4).held  # the same grasp, a sound model
    broken = copy.deepcopy(model)
    broken.dof_damping[:] = -1e12
    r = disturb_test(broken, qpos, drive, duration=0.4)
    assert r.directions == (False,) * 6 and max(r.translation) < 1e-12
