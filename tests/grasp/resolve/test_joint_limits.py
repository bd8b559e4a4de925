"""Joint position limits from MuJoCo (mjtvm.grasp.resolve.state.joint_limits_of): the grasp's
jnt_range and qpos, and the Allegro lift's thumb on its limit at states 25-29."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from mjtvm.lift.states import lift_state
from mjtvm.lift.trajectory import scripted_lift
from mjtvm.paper_hand.scenario import load_scenario
from mjtvm.problem2.tvmmp import tvmmp

ALLEGRO = "models/allegro/allegro-ik.toml"


@pytest.fixture(scope="module")
def lift():  # type: ignore[no-untyped-def]
    from pathlib import Path

    root = Path(__file__).resolve().parents[3]
    return scripted_lift(load_scenario(str(root / ALLEGRO)), num_states=30)


def test_state_carries_the_models_ranges_and_qpos(lift) -> None:  # type: ignore[no-untyped-def]
    grasp = lift.scenario
    state = grasp.state()
    lim = state.joint_limits
    assert lim is not None and lim.tolerance == 1e-3 and lim.horizon == 1e-3
    m = grasp.model
    for j, name in enumerate(state.joint_names):
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        assert bool(m.jnt_limited[jid]) == bool(lim.limited[j])
        if lim.limited[j]:
            assert (lim.lower[j], lim.upper[j]) == tuple(m.jnt_range[jid])
            assert lim.position[j] == grasp.data.qpos[m.jnt_qposadr[jid]]


def test_allegro_thumb_on_its_limit_at_states_25_to_29(lift) -> None:  # type: ignore[no-untyped-def]
    """thj1 sits on its upper limit (within 1e-3 rad) at states 25-29 and not before; the RVDS
    vertices that need it to turn further (1 and 5) lose alpha, vertex 0 keeps its own; at
    state 24 the limits change no alpha (the horizon rows do not bind)."""
    for i in range(20, 30):
        state = lift_state(lift, i, variant="L")
        lim = state.joint_limits
        assert lim is not None
        thj1 = state.joint_names.index("thj1")
        assert bool(lim.at_upper[thj1]) == (i >= 25), i
    s25 = lift_state(lift, 25, variant="L")
    with_limits = tvmmp(s25, witnesses=False).alpha[0]
    without = tvmmp(s25.with_(joint_limits=None), witnesses=False).alpha[0]
    assert with_limits[0] == pytest.approx(without[0], rel=1e-9)
    assert with_limits[1] < 0.25 * without[1] and with_limits[5] < without[5]
    s24 = lift_state(lift, 24, variant="L")
    np.testing.assert_allclose(
        tvmmp(s24, witnesses=False).alpha,
        tvmmp(s24.with_(joint_limits=None), witnesses=False).alpha,
        rtol=1e-9,
    )


@pytest.mark.parametrize(
    "grasp",
    ["shadow_hand/shadow_hand_coupled-sphere.toml", "allegro/allegro-ik.toml", "gripper3/gripper3-box.toml"],
)
def test_no_witness_reaches_a_model_limit_within_the_horizon(grasp: str) -> None:
    """Each witness's joints moved for the time the object takes to travel the horizon,
    q + qd H / (alpha s(r_l)), stay inside the MuJoCo model's own jnt_range (read here from the
    model, not from the state's limits): first order, independent of the LP's limit rows."""
    from pathlib import Path

    from mjtvm import load_grasp
    from mjtvm.model.limits import travel_speed

    g = load_grasp(Path(__file__).resolve().parents[3] / "models" / grasp)
    state = g.state()
    assert state.joint_limits is not None and state.rvds is not None
    horizon = state.joint_limits.horizon
    result = tvmmp(state)
    moved = 0
    for l, w in enumerate(result.witnesses[0]):
        assert w is not None
        if w.alpha <= 0.0:
            continue
        t = horizon / (w.alpha * travel_speed(state, state.rvds[l]))
        for name, qd in zip(state.joint_names, w.speeds, strict=True):
            j = g.model.joint(name)
            if g.model.jnt_limited[j.id]:
                lo, hi = g.model.jnt_range[j.id]
                q_end = g.data.qpos[j.qposadr[0]] + qd * t
                assert lo - 1e-9 <= q_end <= hi + 1e-9, (name, l, q_end, lo, hi)
                moved += 1
    assert moved > 0
