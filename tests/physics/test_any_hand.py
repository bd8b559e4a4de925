"""The physics check on a hand that is not the generated one: a three-finger pinch of a box with
ellipsoid and capsule fingertips and position servos, motors attached with MjSpec."""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.grasp.resolve.state import grasp_state
from mjtvm.model.state import GraspState
from mjtvm.physics.motors import attach_dcmotors
from mjtvm.physics.rig import Rig
from mjtvm.physics.simulate import rollout, sim_model
from mjtvm.physics.witness import Drive, witness_drive
from mjtvm.problem2.tvmmp import tvmmp

HALF = 0.03  # m: the box's half size
# Finger a (x < 0): a vertical link from z = 0.02 to 0.1, then a horizontal one towards the box
# ending in an ellipsoid; finger b mirrored, ending in a capsule along x whose cap touches; finger c
# from -y with an ellipsoid (two point contacts alone leave the rotation about their line free: the
# LP is infeasible under the smallest asymmetry of the contact points); the box's centre of mass is
# 1 cm towards c, so that c carries load. Every tip presses 0.01 mm into the box (MuJoCo reports
# contacts from penetration on, without margin).
PINCH = f"""<mujoco>
  <option gravity="0 0 -9.81" integrator="implicitfast"/>
  <default><geom contype="2" conaffinity="0" friction="0.8 0.005 0.0001"/><position kp="2"/></default>
  <worldbody>
    <body name="a1" pos="-0.12 0 0.02"><joint name="a1" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.08" size="0.004" mass="0.03"/>
      <body name="a2" pos="0 0 0.08"><joint name="a2" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.07 0 0" size="0.004" mass="0.03"/>
        <geom name="a_tip" type="ellipsoid" pos="0.08201 0 0" size="0.012 0.008 0.01" euler="0 0 90" mass="0.005"/>
      </body></body>
    <body name="b1" pos="0.12 0 0.02"><joint name="b1" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.08" size="0.004" mass="0.03"/>
      <body name="b2" pos="0 0 0.08"><joint name="b2" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 -0.066 0 0" size="0.004" mass="0.03"/>
        <geom type="capsule" fromto="-0.066 0 0 -0.08201 0 0" size="0.008" mass="0.005"/>
      </body></body>
    <body name="c1" pos="0 -0.12 0.02"><joint name="c1" axis="1 0 0"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.08" size="0.004" mass="0.03"/>
      <body name="c2" pos="0 0 0.08"><joint name="c2" axis="1 0 0"/>
        <geom type="capsule" fromto="0 0 0 0 0.07 0" size="0.004" mass="0.03"/>
        <geom name="c_tip" type="ellipsoid" pos="0 0.08001 0" size="0.012 0.01 0.008" mass="0.005"/>
      </body></body>
    <body name="box" pos="0 0 0.1"><freejoint/><inertial pos="0 -0.01 0" mass="0.05" diaginertia="3e-5 3e-5 3e-5"/>
      <geom name="box" type="box" size="{HALF} {HALF} {HALF}" contype="1" conaffinity="2"/></body>
  </worldbody>
  <actuator><position joint="a1"/><position joint="a2"/><position joint="b1"/><position joint="b2"/>
    <position joint="c1"/><position joint="c2"/></actuator>
</mujoco>"""
TYPES = {"a_tip": "F", "b2/geom1": "F", "c_tip": "F"}  # finger b's tip is unnamed: keyed by its label


@pytest.fixture(scope="module")
def pinch() -> tuple[mujoco.MjModel, mujoco.MjData, GraspState]:
    model = attach_dcmotors(
        PINCH, dict.fromkeys(("a1", "a2", "b1", "b2", "c1", "c2"), DCMotor.from_datasheet())
    )
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rvds = [[0, 0, 1, 0, 0, 0], [0, 0, -1, 0, 0, 0]]  # fingers a, b move in x-z, c in y-z: only z
    # grasp_state checks contact-type keys by name only (sim.grasp._check_geoms), so the state
    # is built from a copy with the tip named, then its contact renamed to the label
    xml = PINCH.replace(
        '<geom type="capsule" fromto="-0.066', '<geom name="b_tip" type="capsule" fromto="-0.066'
    )
    named = attach_dcmotors(
        xml, dict.fromkeys(("a1", "a2", "b1", "b2", "c1", "c2"), DCMotor.from_datasheet())
    )
    nd = mujoco.MjData(named)
    mujoco.mj_forward(named, nd)
    types = {"a_tip": "F", "b_tip": "F", "c_tip": "F"}
    state = grasp_state(named, nd, contact_types=types, mu=0.8, rvds=rvds, object_body="box")
    contacts = tuple(replace(c, name="b2/geom1") if c.name == "b_tip" else c for c in state.contacts)
    return model, data, state.with_(contacts=contacts)


def _on_surface(model: mujoco.MjModel, data: mujoco.MjData, g: int, p: np.ndarray) -> float:
    """Residual of ``p`` (world) on geom ``g``'s surface (m; ellipsoid: of its normalised equation)."""
    local = data.geom_xmat[g].reshape(3, 3).T @ (p - data.geom_xpos[g])
    size = model.geom_size[g]
    if int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_ELLIPSOID):
        return float(np.sum((local / size) ** 2) - 1.0)
    axial = np.clip(local[2], -size[1], size[1])  # capsule: distance from its axis segment
    return float(np.linalg.norm(local - [0.0, 0.0, axial]) - size[0])


def test_contact_points_lie_on_the_finger_surfaces(pinch) -> None:  # type: ignore[no-untyped-def]
    model, data, state = pinch
    assert {c.name for c in state.contacts} == set(TYPES)
    sim = sim_model(model, TYPES, mu=0.8, object_body="box")
    drive = witness_drive(state, 0, 0, float(tvmmp(state, witnesses=False).alpha[0, 0]), 0.5)
    rig = Rig(sim, drive, "box")
    assert rig.radius == pytest.approx(np.sqrt(3) * HALF)  # bounding radius of the box
    d = mujoco.MjData(sim)
    d.qpos[:] = data.qpos
    mujoco.mj_forward(sim, d)
    for label, g, *_ in rig.fingers:
        dist, og, on_f, _on_o, n = rig.nearest(d, g)
        assert abs(dist + 1e-5) < 1e-7 and og == sim.geom("box").id
        assert abs(_on_surface(sim, d, g, on_f)) < 1e-6, label
        assert abs(np.max(np.abs(n)) - 1.0) < 1e-6  # normal to a face of the box
        # the sphere rule (geom centre + size[0] x normal) would be off the surface here
        assert np.linalg.norm(d.geom_xpos[g] + sim.geom_size[g, 0] * n - on_f) > 1e-3


@pytest.mark.parametrize("l", [0, 1])
def test_rollout_at_half_speed_passes_or_states_why(pinch, l: int) -> None:  # type: ignore[no-untyped-def]
    model, data, state = pinch
    res = tvmmp(state)
    assert res.status[0][l] == "optimal"
    drive = witness_drive(state, 0, l, float(res.alpha[0, l]), 0.5)
    out = rollout(
        sim_model(model, TYPES, mu=0.8, object_body="box"), data.qpos.copy(), drive, object_body="box"
    )
    assert out.passed or out.reason  # either way, no exception
    assert res.alpha[0, l] > 0 and out.settle_drift < 1e-4 and np.isfinite(out.speed_error)


def test_servo_hand_is_refused_without_motors() -> None:
    model = mujoco.MjModel.from_xml_string(PINCH)
    fake = Drive(("a1",), np.zeros(1), np.zeros(1), np.zeros(6), (("a_tip", "F"),))
    with pytest.raises(ModelError, match=r"joint 'a1'.*<dcmotor>"):
        Rig(model, fake, "box")


def test_physics_check_on_the_allegro_grasp_of_the_readme() -> None:
    """The README's hand-only Allegro grasp (position servos replaced by <dcmotor> built from the
    grasp's datasheet entry with MjSpec, joint damping 1 N m s/rad folded into the ranges and fed
    forward in the rollouts): at the LP's speeds the simulated hand reaches 0.85-1.0 of every
    alpha_kl of the first lift state (measured 0.875-1.0; damping-limited, slow enough that the
    reflected rotor inertia does not matter)."""
    from mjtvm.jobs import verify as V

    lift = V.cached_lift("allegro-ik", 5)
    rows = V.verify_state(lift, 0, "L", mu=0.6, mg=0.981)
    assert len(rows) == 6 and all(r["status"] == "optimal" for r in rows)
    ratios = [r["ratio"] for r in rows]
    assert all(0.85 <= x <= 1.05 for x in ratios), ratios
    assert all(r["verdict"] for r in rows)
