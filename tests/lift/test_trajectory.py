"""The scripted lift of Case 2 (mjtvm.lift.trajectory): contacts, the min-norm motion, the reach limit."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Any

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ModelError, StateError
from mjtvm.grasp.resolve.ik import IkTarget, solve_ik
from mjtvm.grasp.resolve.state import detected_contacts
from mjtvm.lift.states import lift_state, slide_directions
from mjtvm.lift.surface import distance_model, witness
from mjtvm.lift.trajectory import TOUCH_TOL, Lift, LiftSpec, scripted_lift

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
        "f1_tip": ("F", 0.5),
        "f2_tip": ("S", 0.5),
        "f3_tip": ("F", 0.5),
        "f4_tip": ("S", 0.5),
    }
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
        ({"num_states": 0}, "num_states"),
        ({"num_states": 2.5}, "num_states"),
        ({"height": -0.01}, "height"),
        ({"max_step": 0.0}, "max_step"),
    ],
)
def test_bad_lift_options(kwargs: dict, field: str) -> None:
    with pytest.raises(StateError) as err:
        scripted_lift(**kwargs)
    assert err.value.field == field


def test_one_state_is_the_grasp_itself(short: Lift) -> None:
    """num_states = 1: the grasp's own state, nothing marched (the physics check of one state)."""
    one = scripted_lift(num_states=1)
    assert one.num_states == 1 and one.marched == 0 and one.s.tolist() == [0.0]
    assert np.array_equal(one.qpos[0], short.qpos[0]) and one.touching[0] == short.touching[0]
    assert np.allclose(one.rates[0], short.rates[0], atol=1e-12)


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


# --- programmatic grasps: any finger geom on a box or a cylinder, any motion -----------------------------

_MOTOR = (
    '<dcmotor joint="{j}" gear="40" nominal="24 0.2044130081 1001.120859" saturation="0.0263 0 0" '
    'input="vel ff" controller="0 0 0.0005 0 0 24"/>'
)


def _finger(name: str, x: float, z: float, sign: float, tip: str) -> str:
    """A planar two-joint finger (hinges about y, links of 0.06 and 0.05 m) pointing along sign * x."""
    a, b = 0.06 * sign, 0.05 * sign
    return (
        f'<body name="{name}0" pos="{x} 0 {z}"><joint name="{name}0" axis="0 1 0"/>'
        f'<geom name="{name}_link0" type="capsule" fromto="0 0 0 {a} 0 0" size="0.004"/>'
        f'<body name="{name}1" pos="{a} 0 0"><joint name="{name}1" axis="0 1 0"/>'
        f'<geom name="{name}_link1" type="capsule" fromto="0 0 0 {b} 0 0" size="0.004"/>'
        f'<body name="{name}2" pos="{b} 0 0">{tip}</body></body></body>'
    )


@dataclass(frozen=True, eq=False)
class _Grasp:
    """The attributes the lift reads of a grasp (as the grasp file's Grasp will have them)."""

    name: str
    model: mujoco.MjModel
    data: mujoco.MjData
    joints: tuple[str, ...]
    contact_types: Mapping[str, str]
    mu: float
    slide_directions: Mapping[str, Any]
    refs: np.ndarray
    rvds: np.ndarray | None
    ignored_geoms: tuple[str, ...]
    object_body: str
    document: Mapping[str, Any]
    lift: LiftSpec | None = None
    ik_bounds: Mapping[str, tuple[float, float]] | None = None


def _settle(model: mujoco.MjModel, data: mujoco.MjData, aims: dict[str, list[float]]) -> None:
    """Each tip geom's centre to its aim, then its witness point onto the object's until they touch."""
    dm, og = distance_model(model), model.geom("obj").id
    first = True
    for _ in range(50):
        mujoco.mj_kinematics(model, data)
        targets, gaps = [], []
        for g, aim in aims.items():
            gid = model.geom(g).id
            body = int(model.geom_bodyid[gid])
            w = witness(dm, data, og, gid)
            gaps.append(abs(w.distance))
            local = data.xmat[body].reshape(3, 3).T @ (w.finger_point - data.xpos[body])
            point, to = (model.geom_pos[gid], aim) if first else (local, w.object_point)
            targets.append(IkTarget(g, model.body(body).name, point, to))
        if not first and max(gaps) < 1e-13:
            break
        data.qpos[:] = solve_ik(model, data, targets, tolerance=1e-14, max_iterations=500, strict=False).qpos
        first = False
    mujoco.mj_forward(model, data)


def _grasp(
    obj: str,
    tips: dict[str, tuple[str, float, float, list[float]]],
    types: dict[str, str],
    centre: float,
    table: bool,
    **extra: Any,
) -> _Grasp:
    fingers = "".join(_finger(n, x, z, 1.0 if x < 0 else -1.0, tip) for n, (tip, x, z, _) in tips.items())
    acts = "".join(_MOTOR.format(j=f"{n}{k}") for n in tips for k in (0, 1))
    floor = '<geom name="table" type="plane" size="0.5 0.5 0.01"/>' if table else ""
    xml = (
        '<mujoco><default><geom margin="1e-3" gap="1e-3"/></default><worldbody>'
        f'{floor}<body name="object"><freejoint/>{obj}</body>{fingers}</worldbody>'
        f"<actuator>{acts}</actuator></mujoco>"
    )
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.qpos[:3] = [0.0, 0.0, centre]
    for n in tips:
        sign = 1.0 if tips[n][1] < 0 else -1.0
        data.qpos[model.joint(f"{n}0").qposadr[0]], data.qpos[model.joint(f"{n}1").qposadr[0]] = (
            0.4 * sign,
            0.4 * sign,
        )
    _settle(model, data, {g: aim for g, (_, _, _, aim) in {f"{n}_tip": v for n, v in tips.items()}.items()})
    return _Grasp(
        "test",
        model,
        data,
        tuple(f"{n}{k}" for n in tips for k in (0, 1)),
        MappingProxyType(types),
        0.5,
        {},
        np.array([[0.0, 0.0, -1.0, 0.0, 0.0, 0.0]]),
        None,
        (),
        "object",
        {},
        **extra,
    )


@pytest.fixture(scope="module")
def box() -> _Grasp:
    """A box on a table between a capsule-tipped F finger and a box-tipped L finger."""
    return _grasp(
        '<geom name="obj" type="box" size="0.03 0.03 0.03" mass="0.1"/>',
        {
            "a": (
                '<geom name="a_tip" type="capsule" zaxis="0 1 0" size="0.006 0.01"/>',
                -0.12,
                0.09,
                [-0.036, 0.0, 0.04],
            ),
            "b": ('<geom name="b_tip" type="box" size="0.006 0.01 0.006"/>', 0.12, 0.09, [0.036, 0.0, 0.04]),
        },
        {"a_tip": "F", "b_tip": "L", "table": "D"},
        0.03,
        True,
    )


@pytest.fixture(scope="module")
def cylinder() -> _Grasp:
    """A cylinder (axis y) in the air between a capsule-tipped F finger and an ellipsoid-tipped L finger."""
    return _grasp(
        '<geom name="obj" type="cylinder" size="0.03 0.02" zaxis="0 1 0" mass="0.1"/>',
        {
            "a": (
                '<geom name="a_tip" type="capsule" zaxis="0 1 0" size="0.006 0.01"/>',
                -0.12,
                0.12,
                [-0.036, 0.0, 0.09],
            ),
            "c": (
                '<geom name="c_tip" type="ellipsoid" size="0.008 0.01 0.005"/>',
                0.12,
                0.12,
                [0.038, 0.0, 0.09],
            ),
        },
        {"a_tip": "F", "c_tip": "L"},
        0.08,
        False,
    )


def _check_contacts(grasp: _Grasp, lift: Lift, f_geom: str, l_geom: str) -> None:
    """The F geom's start contact point (fixed to its body) stays on the object-fixed point (< 1e-8 m)
    and the L geom on the surface (within the lift's tolerance)."""
    model, dm = grasp.model, distance_model(grasp.model)
    og, fa, fl = model.geom("obj").id, model.geom(f_geom).id, model.geom(l_geom).id
    ob, body = model.body("object").id, int(model.geom_bodyid[fa])
    w0, d0 = witness(dm, grasp.data, og, fa), grasp.data
    p0 = 0.5 * (w0.object_point + w0.finger_point)
    local = d0.xmat[body].reshape(3, 3).T @ (p0 - d0.xpos[body])
    rel = d0.xmat[ob].reshape(3, 3).T @ (p0 - d0.xpos[ob])
    for i in range(lift.num_states):
        data = mujoco.MjData(model)
        data.qpos[:] = lift.qpos[i]
        mujoco.mj_kinematics(model, data)
        on_finger = data.xpos[body] + data.xmat[body].reshape(3, 3) @ local
        on_object = data.xpos[ob] + data.xmat[ob].reshape(3, 3) @ rel
        assert np.linalg.norm(on_finger - on_object) < 1e-8, i
        assert abs(witness(dm, data, og, fl).distance) <= 2 * lift.tolerance, i
        assert np.allclose(lift.poses[i], data.qpos[:7], atol=0.0)


def _check_rates(grasp: _Grasp, lift: Lift, tol: float) -> None:
    """The minimum-norm rates are the path's derivative: the finite differences of qpos per unit s
    match the mean of the rates at both ends (second order) within ``tol`` (rad per unit s)."""
    adr = [grasp.model.joint(j).qposadr[0] for j in lift.joints]
    fd = np.diff(lift.qpos[:, adr], axis=0) / np.diff(lift.s)[:, None]
    mean = 0.5 * (lift.rates[1:] + lift.rates[:-1])
    assert np.abs(fd - mean).max() < tol, np.abs(fd - mean).max()


def test_box_lifted_diagonally_by_capsule_and_box_tips(box: _Grasp) -> None:
    d = np.array([0.5, 0.0, 1.0]) / np.sqrt(1.25)
    lift = scripted_lift(box, direction=[0.5, 0.0, 1.0], num_states=8, height=0.02)
    assert lift.geoms == ("a_tip", "b_tip") and lift.roles == ("F", "N") and lift.base == ("table",)
    assert np.allclose(lift.poses[:, :3] - lift.poses[0, :3], lift.s[:, None] * d, atol=1e-15)
    assert np.allclose(lift.twists, [[*d, 0, 0, 0]] * 8, atol=0)
    _check_contacts(box, lift, "a_tip", "b_tip")
    _check_rates(box, lift, 0.05)  # rates ~ 10 rad/m, s steps 2.9 mm
    assert lift.base_contact.tolist() == [True] + [False] * 7  # the table is a D-point until lift-off
    state = lift_state(lift, 0)
    assert {c.name.split("#")[0]: c.type for c in state.contacts} == {
        "table": "D",
        "a_tip": "F",
        "b_tip": "L",
    }
    assert state.refs.tolist() == [[0.0, 0.0, -1.0, 0.0, 0.0, 0.0]]  # mg None: the grasp's REFS
    slides = slide_directions(lift, 3)
    assert set(slides) == {"b_tip"} and slides["b_tip"] @ d > 0  # the object slips up past the finger
    full = scripted_lift(box, direction=[0.5, 0.0, 1.0], num_states=3)
    assert full.limit.startswith("reach limit") and full.s[-1] > 0.02


def test_cylinder_turned_by_a_twist_with_an_ellipsoid_tip(cylinder: _Grasp) -> None:
    twist = [0.0, 0.0, 0.05, 0.0, 1.0, 0.0]  # up 5 cm and 1 rad about y per unit s
    lift = scripted_lift(cylinder, twist=twist, num_states=6, height=0.3)
    _check_contacts(cylinder, lift, "a_tip", "c_tip")
    _check_rates(cylinder, lift, 1e-2)  # rates ~ 1 rad/rad, steps 0.06
    angle = 2 * np.arctan2(lift.poses[:, 5], lift.poses[:, 3])  # quaternion about y
    assert np.allclose(angle, lift.s, atol=1e-12) and np.allclose(
        lift.z - lift.z[0], 0.05 * lift.s, atol=1e-15
    )
    full = scripted_lift(cylinder, twist=twist, num_states=3)
    assert full.limit.startswith("reach limit") and full.s[-1] > 0.3


def test_poses_and_the_grasps_own_lift(cylinder: _Grasp) -> None:
    up = np.array(cylinder.data.qpos[:3]) + np.array([0.0, 0.0, 0.005])
    half = np.array([np.cos(0.1), 0.0, np.sin(0.1), 0.0])  # 0.2 rad about y
    poses = [[*up, 1.0, 0.0, 0.0, 0.0], [*up, *half]]
    lift = scripted_lift(cylinder, poses=poses, num_states=5)
    assert lift.limit == "the last pose" and lift.s[-1] == pytest.approx(0.205, abs=1e-12)
    assert np.allclose(lift.poses[-1], poses[-1], atol=1e-15)
    _check_contacts(cylinder, lift, "a_tip", "c_tip")
    spec = LiftSpec.from_direction([0.0, 0.0, 2.0], height=0.004, bounds={"a0": (-3.0, 3.0)})
    own = scripted_lift(replace(cylinder, lift=spec), num_states=3)
    assert own.s[-1] == pytest.approx(0.004) and np.allclose(own.z - own.z[0], own.s, atol=1e-15)


def test_bad_motions(cylinder: _Grasp) -> None:
    for kwargs, field in (
        ({"direction": [0, 0, 1], "twist": [0, 0, 1, 0, 0, 0]}, "twist"),
        ({"twist": [0, 0, 0, 0, 0, 0]}, "twist"),
        ({"poses": [[0, 0, 0, 2, 0, 0, 0]]}, "poses"),
        ({"direction": [0, 0, 0]}, "direction"),
    ):
        with pytest.raises(StateError) as err:
            scripted_lift(cylinder, **kwargs)  # type: ignore[arg-type]
        assert err.value.field == field
    with pytest.raises(ModelError, match="beyond reach"):
        scripted_lift(cylinder, direction=[1.0, 0.0, 0.0], height=0.5)
