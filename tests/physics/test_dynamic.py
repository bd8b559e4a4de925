"""The MuJoCo layer of the dynamic alpha (mjtvm.physics.dynamic) on the one-joint pusher.

A hinge about +y at the origin carries a link of length l = 0.1 m ending in a tip sphere at
(l sin q, 0, l cos q); a free block to its +x is pushed along +x at speed v by the frictionless
(L) tip. Tip speed l cos q qd = v gives qd = v / (l c) and qdd = v^2 s / (l^2 c^3); with the
rotor's reflected inertia I = armature x gear^2 = 1.08e-6 x 40^2 = 1.728e-3 kg m^2 (and a
link of negligible mass) the demand is I qdd. Gravity is off.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from mjtvm.model.contacts import Contact
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.physics.dynamic import demand_of, dynamic_pair, joint_demand, window_demand
from mjtvm.physics.witness import Drive
from mjtvm.problem2.dynamic import dynamic_alpha, quadratic

L, R_TIP, HALF = 0.1, 0.005, 0.02
I_ROTOR = 1.08e-6 * 40**2


def model(
    q: float, armature: float = 1.08e-6, *, gravity: str = "0 0 0", block_mass: float = 0.1
) -> tuple[mujoco.MjModel, np.ndarray]:
    """The pusher at ``q`` (module docstring); ``gravity`` and the block's mass (kg) as given."""
    tip = np.array([L * math.sin(q), 0.0, L * math.cos(q)])
    centre = tip + np.array([R_TIP + HALF, 0.0, 0.0])
    xml = f"""
<mujoco>
  <option timestep="0.00025" gravity="{gravity}"/>
  <worldbody>
    <body name="link">
      <joint name="q" type="hinge" axis="0 1 0"/>
      <geom name="bar" type="capsule" fromto="0 0 0 0 0 {L}" size="0.002" mass="1e-6" contype="0" conaffinity="0"/>
      <geom name="tip" type="sphere" pos="0 0 {L}" size="{R_TIP}" mass="1e-6"/>
    </body>
    <body name="object" pos="{centre[0]} 0 {centre[2]}">
      <freejoint/>
      <geom name="block" type="box" size="{HALF} {HALF} {HALF}" mass="{block_mass}"/>
    </body>
  </worldbody>
  <actuator>
    <dcmotor name="q" joint="q" gear="40" nominal="24 0.2044130081 1001.120859" saturation="0.0263 0 0"
             armature="{armature}" input="vel ff" controller="0 0 0.0005 0 0 24"/>
  </actuator>
</mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    qpos = m.qpos0.copy()
    qpos[0] = q
    return m, qpos


def closed_form_h(q: float, inertia: float) -> float:
    return inertia * math.sin(q) / (L**2 * math.cos(q) ** 3)  # N m per (m/s)^2


def drive(q: float, v: float) -> Drive:
    return Drive(
        ("q",),
        np.array([v / (L * math.cos(q))]),
        np.zeros(1),
        np.array([v, 0, 0, 0, 0, 0.0]),
        (("tip", "L"),),
    )


@pytest.mark.parametrize("q", [0.3, 0.6, 0.9])
def test_joint_demand_is_the_rotor_inertia_times_the_closed_form_acceleration(q: float) -> None:
    m, qpos = model(q)
    v = 0.5
    dem = joint_demand(m, qpos, drive(q, v))
    assert dem.speeds[0] == pytest.approx(v / (L * math.cos(q)), rel=1e-9)
    assert dem.acceleration[0] == pytest.approx(v**2 * math.sin(q) / (L**2 * math.cos(q) ** 3), rel=1e-5)
    assert dem.total[0] == pytest.approx(closed_form_h(q, I_ROTOR) * v**2, rel=2e-3)  # link ~1e-8 kg m^2
    assert abs(dem.bias[0]) < 1e-9  # one joint: no Coriolis term


def test_joint_demand_is_quadratic_in_speed_and_zero_without_inertia() -> None:
    m, qpos = model(0.6)
    d1, d2 = (joint_demand(m, qpos, drive(0.6, v)).total[0] for v in (0.3, 0.6))
    assert d2 == pytest.approx(4 * d1, rel=1e-5)  # the central difference: O((v dt)^2)
    m0, _ = model(0.6, armature=0.0)
    assert abs(joint_demand(m0, qpos, drive(0.6, 0.6)).total[0]) < 1e-4 * d2


def state(q: float, f0: float = 2.0) -> GraspState:
    tip = np.array([L * math.sin(q), 0.0, L * math.cos(q)])
    contact = Contact(
        "tip",
        "L",
        tip + np.array([R_TIP, 0, 0]),
        [1.0, 0.0, 0.0],
        [[L * math.cos(q)], [0.0], [-L * math.sin(q)]],
    )
    return GraspState(
        space=3,
        object_position=tip + np.array([R_TIP + HALF, 0, 0]),
        joint_names=("q",),
        operation_ranges=(OperationRange([[0, 0], [1.0, 0], [0, 30.0]]),),
        gravity_torque=[0.0],
        contacts=(contact,),
        refs=[[-f0, 0, 0, 0, 0, 0]],
        rvds=[[1.0, 0, 0, 0, 0, 0]],
    )


def test_dynamic_pair_matches_the_closed_form_alpha() -> None:
    q = 0.6
    m, qpos = model(q)
    st = state(q)
    dyn = dynamic_pair(m, qpos, st, 0, 0, object_body="object", rtol=1e-6)
    c = math.cos(q)
    qa, qb, qc = closed_form_h(q, I_ROTOR), 1 / (L * c * 30.0), L * c * 2.0 - 1
    expected = (-qb + math.sqrt(qb * qb - 4 * qa * qc)) / (2 * qa)
    assert dyn.alpha_static == pytest.approx(L * c * 30 * (1 - 2 * L * c), rel=1e-9)
    assert dyn.alpha == pytest.approx(expected, rel=3e-3)
    assert (dyn.joint, dyn.term) == (0, "speed")  # 1.728e-3 kg m^2 is small against 30 rad/s
    # and the demand of the drive equals the fixed quadratic of the closed form
    dem = demand_of(m, qpos, st, 0, 0, dyn.alpha_static, object_body="object")
    assert dem(1.0)[0] == pytest.approx(qa, rel=3e-3)
    ref = dynamic_alpha(st, 0, 0, quadratic([qa]), rtol=1e-6)
    assert dyn.alpha == pytest.approx(ref.alpha, rel=3e-3)


def window_end(q: float, v: float, span: float) -> float:
    """q after ``span`` s of the push: the tip's x = l sin q moves at v."""
    return math.asin(math.sin(q) + v * span / L)


@pytest.mark.parametrize(("q", "span"), [(0.6, 0.007), (0.9, 0.007), (0.9, 0.02)])
def test_window_demand_spans_the_demand_along_the_push(q: float, span: float) -> None:
    # qdd = v^2 s / (l^2 c^3) grows with q: the largest demand is at the window's end, the least at its start
    m, qpos = model(q)
    v = 0.5
    hi, lo = window_demand(m, qpos, drive(q, v), span)
    q1 = window_end(q, v, span)
    assert hi[0] == pytest.approx(closed_form_h(q1, I_ROTOR) * v**2, rel=3e-3)
    assert lo[0] == pytest.approx(closed_form_h(q, I_ROTOR) * v**2, rel=2e-3)
    assert hi[0] > lo[0] * (1 + 0.9 * (closed_form_h(q1, 1.0) / closed_form_h(q, 1.0) - 1))
    same = window_demand(m, qpos, drive(q, v), 0.0)
    assert same[0, 0] == same[1, 0] == pytest.approx(joint_demand(m, qpos, drive(q, v)).total[0], rel=1e-12)


def test_dynamic_pair_over_a_window_matches_the_closed_form() -> None:
    """The LP at q0 (speed a / (l c0), pushing torque l c0 F0) with the demand at the window's end
    q1(a): (l c0 F0 + I a^2 s1 / (l^2 c1^3)) / T + a / (l c0 W) = 1, solved by brentq here."""
    from scipy.optimize import brentq

    q, span = 0.9, 0.007
    m, qpos = model(q)
    c = math.cos(q)

    def slack(a: float) -> float:
        return L * c * 2.0 + closed_form_h(window_end(q, a, span), I_ROTOR) * a * a + a / (L * c * 30.0) - 1.0

    expected = brentq(slack, 1e-6, L * c * 30 * (1 - 2 * L * c))
    dyn = dynamic_pair(m, qpos, state(q), 0, 0, object_body="object", rtol=1e-6, window=span)
    instant = dynamic_pair(m, qpos, state(q), 0, 0, object_body="object", rtol=1e-6)
    assert dyn.alpha == pytest.approx(expected, rel=3e-3)
    assert dyn.alpha < instant.alpha * (1 - 1e-2)  # the window costs speed here
    assert dyn.demand[0] == pytest.approx(
        closed_form_h(window_end(q, dyn.alpha, span), I_ROTOR) * dyn.alpha**2, rel=3e-3
    )


def test_zero_rotor_inertia_reduces_to_the_quasi_static_alpha() -> None:
    m, qpos = model(0.6, armature=0.0)
    dyn = dynamic_pair(m, qpos, state(0.6), 0, 0, object_body="object", rtol=1e-5)
    assert dyn.alpha == pytest.approx(dyn.alpha_static, rel=1e-4)


def test_gear_sweep_shows_the_dynamic_optimum() -> None:
    """Case 2, state 0 (L): at 30:1 inertia limits (dynamic 0.786 against quasi-static 1.594); at
    100:1 the speed does and both agree (0.509 and 0.500; the dynamic one is a little higher:
    decelerating joints give torque back); at 10:1 the grasp's torque no longer fits."""
    from mjtvm.jobs.gears import gear_sweep

    rows = {r["ratio"]: r for r in gear_sweep("case2", (10.0, 30.0, 100.0), states=(0,))}
    assert rows[10.0]["tvmmp"] is None
    assert rows[30.0]["tvmmp"] == pytest.approx(1.59419, rel=1e-4)
    assert rows[30.0]["tvmmp_dyn"] == pytest.approx(0.785568, rel=3e-3)
    assert (rows[30.0]["joint_dyn"], rows[30.0]["term_dyn"]) == ("f1_pitch0", "inertia")
    assert rows[100.0]["tvmmp"] == pytest.approx(0.499995, rel=1e-4)
    assert rows[100.0]["tvmmp_dyn"] == pytest.approx(0.508784, rel=3e-3)
    assert rows[100.0]["term_dyn"] == "speed"


def test_verify_options_parse() -> None:
    from mjtvm.cli.verify import verify_parser

    args = verify_parser().parse_args(["--dynamics", "--preload", "0.5", "--gears", "20,40"])
    assert (args.dynamics, args.preload, args.gears) == (True, 0.5, (20.0, 40.0))
    with pytest.raises(SystemExit):
        verify_parser().parse_args(["--gears", "0,40"])


def test_verify_takes_the_demand_along_the_rollouts_span(monkeypatch: pytest.MonkeyPatch) -> None:
    """verify's dynamic alpha uses the span its rollouts check (startup + window), whatever they are."""
    import mjtvm.physics.check as check
    from mjtvm.physics.simulate import SimSettings
    from mjtvm.problem2.dynamic import DynamicAlpha

    seen: list[float] = []

    def fake(*args: object, window: float = -1.0, **kw: object) -> DynamicAlpha:
        seen.append(window)
        return DynamicAlpha(0.0, 1.0, np.zeros(1), None, None, "", math.nan, 1, (0.0, 0.0))

    monkeypatch.setattr(check, "dynamic_pair", fake)
    settings = SimSettings(startup=0.001, window=0.004)
    row = check.dynamic_row(None, None, state(0.6), 0, None, 1.0, 1.0, "central", settings, "object", 0.9)
    assert seen == [pytest.approx(0.005, rel=1e-12)] and row["alpha_dyn"] == 0.0
    check.dynamic_row(None, None, state(0.6), 0, None, 1.0, 1.0, "central", None, "object", 0.9)
    assert seen[-1] == pytest.approx(0.007, rel=1e-12)  # SimSettings' defaults: 2 ms + 5 ms
