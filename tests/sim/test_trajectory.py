"""The scripted lift of Case 2 (mjtvm.sim.trajectory): contacts, the min-norm motion, the reach limit."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ModelError, StateError
from mjtvm.sim.grasp import detected_contacts
from mjtvm.sim.trajectory import TOUCH_TOL, Lift, lift_state, scripted_lift, slide_directions

EZ = np.array([0.0, 0.0, 1.0])
RADIUS, TIP = 0.1, 0.005  # sphere and fingertip radii (m), from the scenario and the hand model


@pytest.fixture(scope="module")
def full() -> Lift:
    return scripted_lift()  # to the reach limit, 30 states


@pytest.fixture(scope="module")
def short() -> Lift:
    return scripted_lift(num_states=5, height=0.002)  # 0.5 mm apart: the palm stays within MuJoCo's gap


def _forward(lift: Lift, i: int) -> mujoco.MjData:
    data = mujoco.MjData(lift.scenario.model)
    data.qpos[:] = lift.qpos[i]
    mujoco.mj_forward(lift.scenario.model, data)
    return data


def _contacts(lift: Lift, i: int) -> tuple[dict, np.ndarray]:
    """MuJoCo's contacts (geom -> DetectedContact) and the object centre at state i."""
    data = _forward(lift, i)
    return {c.geom: c for c in detected_contacts(lift.scenario.model, data)}, np.array(data.xpos[-1])


def test_full_lift_has_at_least_25_evenly_spaced_states_up_to_the_reach_limit(full: Lift) -> None:
    assert full.num_states >= 25
    assert full.z[0] == pytest.approx(0.1, abs=1e-12)
    assert np.allclose(np.diff(full.z), (full.z[-1] - full.z[0]) / (full.num_states - 1), atol=1e-12)
    assert full.z[-1] > 0.2 and "f1_tip" in full.limit  # finger 1 stretches out first
    assert np.all(full.residual < 1e-9)
    # the last state is the last reachable one: 0.1 mm higher (10 bisection widths) is out of reach
    with pytest.raises(ModelError, match="beyond reach"):
        scripted_lift(height=float(full.z[-1] - full.z[0]) + 1e-4, num_states=2)


@pytest.mark.parametrize("which", ["full", "short"])
def test_f_contacts_stay_fixed_on_the_object(which: str, request: pytest.FixtureRequest) -> None:
    lift: Lift = request.getfixturevalue(which)
    start, centre0 = _contacts(lift, 0)
    for i in range(lift.num_states):
        found, centre = _contacts(lift, i)
        assert centre == pytest.approx([0.0, 0.0, lift.z[i]], abs=1e-12)
        for geom in ("f1_tip", "f3_tip"):
            moved = found[geom].position - centre
            assert np.linalg.norm(moved - (start[geom].position - centre0)) < 1e-8, (i, geom)


@pytest.mark.parametrize("which", ["full", "short"])
def test_l_s_contacts_stay_on_the_surface(which: str, request: pytest.FixtureRequest) -> None:
    lift: Lift = request.getfixturevalue(which)
    model = lift.scenario.model
    for i in range(lift.num_states):
        data = _forward(lift, i)
        found = {c.geom: c for c in detected_contacts(model, data)}
        for geom in ("f2_tip", "f4_tip"):
            gap = np.linalg.norm(data.geom_xpos[model.geom(geom).id] - data.xpos[-1]) - (RADIUS + TIP)
            assert abs(gap) < 1e-6 and abs(found[geom].distance) < 1e-6, (i, geom, gap)
        assert lift.residual[i].max() < 1e-6
    assert lift.drift[0].max() == 0.0 and lift.drift[1:].max() > 0.0  # the correction did remove drift


def test_min_norm_motion_meets_the_contact_constraints(full: Lift) -> None:
    """Finite differences: moving the joints by rates * h and the object by h e_z moves each
    finger-side contact point (fixed to the tip body) by h e_z (F, eq. 7) or by the same normal
    component (L/S, eq. 8); the L/S motion is the min-norm one, a multiple of (n^T J)^T."""
    model, h = full.scenario.model, 1e-6
    adr = np.array([model.joint(j).qposadr[0] for j in full.joints])
    for i in (0, full.num_states // 2, full.num_states - 2):
        base = _forward(full, i)
        found, _ = _contacts(full, i)
        moved = []
        for sign in (-1.0, 1.0):
            data = mujoco.MjData(model)
            data.qpos[:] = full.qpos[i]
            data.qpos[adr] += sign * h * full.rates[i]
            mujoco.mj_kinematics(model, data)
            moved.append(data)
        for k, geom in enumerate(full.geoms):
            body = model.geom(geom).bodyid[0]
            local = base.xmat[body].reshape(3, 3).T @ (found[geom].position - base.xpos[body])
            p = [d.xpos[body] + d.xmat[body].reshape(3, 3) @ local for d in moved]
            v = (p[1] - p[0]) / (2 * h)  # velocity of the finger point per unit lift (m/m)
            n = found[geom].normal
            if full.roles[k] == "F":
                assert np.linalg.norm(v - EZ) < 1e-6, (i, geom, v)
            else:
                assert n @ v == pytest.approx(n @ EZ, abs=1e-6), (i, geom)
                jacp = np.zeros((3, model.nv))
                mujoco.mj_jac(model, base, jacp, None, found[geom].position, body)
                cols = [full.joints.index(j) for j in full.joints if j.startswith(geom[:3])]
                jn = n @ jacp[:, [model.joint(full.joints[c]).dofadr[0] for c in cols]]
                rate = full.rates[i, cols]
                assert np.linalg.norm(rate - (rate @ jn) * jn / (jn @ jn)) < 1e-9 * np.linalg.norm(rate)


@pytest.mark.parametrize("which", ["full", "short"])
def test_base_d_point_only_while_the_object_rests_on_the_palm(
    which: str, request: pytest.FixtureRequest
) -> None:
    lift: Lift = request.getfixturevalue(which)
    assert lift.base_contact.tolist() == [True] + [False] * (lift.num_states - 1)
    for i in (0, 1, lift.num_states - 1):
        types = {c.name: c.type for c in lift_state(lift, i).contacts}
        expected = {"f1_tip": "F", "f2_tip": "L", "f3_tip": "F", "f4_tip": "L"}
        assert types == ({"palm": "D", **expected} if i == 0 else expected)
    if which == "short":  # the palm is within MuJoCo's contact gap yet no contact: it does not touch
        found, _ = _contacts(lift, 1)
        assert TOUCH_TOL < found["palm"].distance < 1e-3


def test_slide_directions_of_the_two_readings_are_opposite(full: Lift) -> None:
    for i in range(full.num_states):
        phys, lit = slide_directions(full, i), slide_directions(full, i, reading="literal")
        assert set(phys) == {"f2_tip", "f4_tip"}
        state = lift_state(full, i, variant="S")
        by_name = {c.name: c for c in state.contacts}
        for geom, s in phys.items():
            assert np.allclose(lit[geom], -s, atol=0.0) and np.linalg.norm(s) == pytest.approx(1.0)
            assert abs(s @ by_name[geom].normal) < 1e-6  # tangential
            assert np.allclose(by_name[geom].slide_direction, s)
            # physical: the object slips along +z relative to the finger (the finger lags the lift)
            assert s @ EZ > 0
        literal = lift_state(full, i, variant="S", reading="literal")
        for c in literal.contacts:
            if c.type == "S":
                assert np.allclose(c.slide_direction, -by_name[c.name].slide_direction)


def test_lift_state_contacts_refs_and_cheap_retyping(short: Lift) -> None:
    state = lift_state(short, 2, variant="S", reading="literal", mu=0.5, mg=2.0)
    assert {c.name: (c.type, c.mu) for c in state.contacts} == {
        "f1_tip": ("F", 0.5), "f2_tip": ("S", 0.5), "f3_tip": ("F", 0.5), "f4_tip": ("S", 0.5),
    }  # fmt: skip
    assert state.refs.tolist() == [[0.0, 0.0, -2.0, 0.0, 0.0, 0.0]]
    assert np.array_equal(state.rvds, short.scenario.rvds)
    again = lift_state(short, 2, variant="S", reading="literal", mu=0.5, mg=2.0, base=lift_state(short, 2))
    for a, b in zip(state.contacts, again.contacts, strict=True):
        assert a.name == b.name and np.array_equal(a.jacobian, b.jacobian)
        assert np.array_equal(a.slide_direction, b.slide_direction)


def test_humanlike_hand_lifts_too() -> None:
    lift = scripted_lift(variant="humanlike", num_states=3, height=0.01)
    assert lift.residual.max() < 1e-6 and len(lift.joints) == 16
    assert lift.scenario.name == "case2-humanlike"


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"num_states": 1}, "num_states"),
        ({"num_states": 2.5}, "num_states"),
        ({"height": -0.01}, "height"),
        ({"max_step": 0.0}, "max_step"),
    ],
)
def test_bad_lift_options(kwargs: dict, field: str) -> None:
    with pytest.raises(StateError) as err:
        scripted_lift(**kwargs)
    assert err.value.field == field


def test_bad_state_options(short: Lift) -> None:
    for kwargs, field in (
        ({"variant": "F"}, "variant"),
        ({"reading": "backwards"}, "reading"),
        ({"mu": -0.1}, "mu"),
        ({"mg": float("nan")}, "mg"),
    ):
        with pytest.raises(StateError) as err:
            lift_state(short, 0, **kwargs)
        assert err.value.field == field
    with pytest.raises(StateError, match="index"):
        lift_state(short, short.num_states)
    with pytest.raises(ModelError, match="no variant"):
        scripted_lift(variant="nohand")
