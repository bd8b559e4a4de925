"""Contact detection within a tolerance (mjtvm.grasp.contacts.touch, .pairs) against ``mj_geomDistance``."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from mjtvm.grasp.contacts.pairs import candidate_pairs
from mjtvm.grasp.contacts.touch import detected_contacts, geom_label, precise_collision, subtree

TOL = 2e-3
OCTA = "0.012 0 0  -0.012 0 0  0 0.012 0  0 -0.012 0  0 0 0.012  0 0 -0.012"
WEDGE = "0 0 0  0.02 0 0  0 0.015 0  0 0 0.01  0.02 0 0.01  0 0.015 0.01"
#: Every primitive a finger may have and two convex meshes (inline vertices: MuJoCo takes their
#: hull), on two hand bodies with several geoms each (MuJoCo's mid-phase applies); the object is
#: a sphere, a box and two meshes.
RANDOM_XML = f"""<mujoco>
<asset><mesh name="octa" vertex="{OCTA}"/><mesh name="wedge" vertex="{WEDGE}"/></asset>
<worldbody>
 <body name="hand"><joint name="j" type="hinge" axis="0 0 1"/>
  <geom name="cap" type="capsule" size="0.008 0.02"/>
  <geom name="ball" type="sphere" size="0.01" pos="0.05 0 0"/>
  <geom name="brick" type="box" size="0.01 0.015 0.008" pos="0 0.05 0"/>
  <geom name="can" type="cylinder" size="0.01 0.012" pos="0.05 0.05 0"/>
  <geom name="egg" type="ellipsoid" size="0.012 0.008 0.01" pos="0 -0.05 0"/>
  <geom name="gem" type="mesh" mesh="octa" pos="0.05 -0.05 0"/>
  <geom name="ramp" type="mesh" mesh="wedge" pos="-0.05 0 0"/>
  <body name="tip" pos="-0.05 0.05 0"><joint name="k" type="hinge" axis="0 1 0"/>
   <geom name="tipball" type="sphere" size="0.009"/>
   <geom name="tipgem" type="mesh" mesh="octa" pos="0 0 0.02"/>
  </body>
 </body>
 <body name="object" pos="0 0 0.1"><freejoint/>
  <geom name="o_ball" type="sphere" size="0.015"/>
  <geom name="o_box" type="box" size="0.02 0.01 0.006" pos="0.03 0 0"/>
  <geom name="o_gem" type="mesh" mesh="octa" pos="-0.025 0 0"/>
  <geom name="o_wedge" type="mesh" mesh="wedge" pos="0 0.025 0"/>
 </body>
</worldbody></mujoco>"""


def _exact(model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, float]:
    """Hand geom label -> its smallest ``mj_geomDistance`` to the object, where at most TOL."""
    inside = subtree(model, model.body("object").id)
    obj = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) in inside]
    out: dict[str, float] = {}
    with precise_collision(model):
        for g in range(model.ngeom):
            if g in obj:
                continue
            for o in obj:
                d = mujoco.mj_geomDistance(model, data, g, o, 1.0, None)
                if d <= TOL:
                    out[geom_label(model, g)] = min(out.get(geom_label(model, g), 1.0), d)
    return out


def test_detection_is_mj_geom_distance_over_random_poses() -> None:
    """Over 400 random object poses among primitive and mesh geoms, the geoms found within TOL are
    exactly those ``mj_geomDistance`` puts within it; apart, their distances agree."""
    model = mujoco.MjModel.from_xml_string(RANDOM_XML)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    near = 0
    for _ in range(400):
        data.qpos[:2] = rng.uniform(-0.5, 0.5, 2)
        data.qpos[2:5] = rng.uniform([-0.07, -0.07, -0.03], [0.07, 0.07, 0.03])
        q = rng.normal(size=4)
        data.qpos[5:9] = q / np.linalg.norm(q)
        mujoco.mj_kinematics(model, data)
        want = _exact(model, data)
        got: dict[str, float] = {}
        for c in detected_contacts(model, data, object_body="object", one_per_body=False, tolerance=TOL):
            got[c.geom] = min(got.get(c.geom, 1.0), c.distance)
            assert c.distance <= TOL
        assert set(got) == set(want)
        for g, d in want.items():
            if d > 0:  # MuJoCo's multi-point mesh contacts sit up to a few um off the exact distance
                assert got[g] == pytest.approx(d, abs=5e-6)
        near += len(want)
    assert near > 300  # the poses put many pairs within the tolerance


def _gap_xml(hand: str, *, pair: str = "", exclude: str = "") -> str:
    """A box object (half 20 mm, plus a sphere: two geoms) and a hand body at x = 31.5 mm whose
    geoms are given: a 10 mm half-box there is 1.5 mm from the object's face."""
    return f"""<mujoco><worldbody>
      <body name="hand" pos="0.0315 0 0"><joint type="slide"/>{hand}</body>
      <body name="object"><freejoint/>
        <geom name="o" type="box" size="0.02 0.02 0.02"/>
        <geom name="o2" type="sphere" size="0.01" pos="-0.03 0 0"/>
      </body></worldbody>
      <contact>{pair}{exclude}</contact></mujoco>"""


TWO_GEOMS = '<geom name="h" type="box" size="0.01 0.01 0.01"/><geom name="h2" type="sphere" size="0.005" pos="0.03 0 0"/>'


def test_pair_culled_by_the_mid_phase_is_found() -> None:
    """Two bodies of several geoms: MuJoCo's mid-phase, built without the widened margin, culled
    this pair 1.5 mm apart (the issue's "nearest distance 1.94 mm > contact_tolerance 2 mm")."""
    model = mujoco.MjModel.from_xml_string(_gap_xml(TWO_GEOMS))
    data = mujoco.MjData(model)
    (c,) = detected_contacts(model, data, object_body="object", tolerance=TOL)
    assert c.geom == "h"
    assert c.distance == pytest.approx(1.5e-3, abs=1e-12)
    np.testing.assert_allclose(c.normal, [-1.0, 0.0, 0.0], atol=1e-12)  # into the object
    assert detected_contacts(model, data, object_body="object", tolerance=1.4e-3) == []
    assert int(model.opt.disableflags) == 0  # the mid-phase flag is restored


def test_explicit_pair_found_from_mj_geom_distance() -> None:
    """A ``<pair>`` keeps its own margin (0), so MuJoCo's pipeline does not report it at 1.5 mm;
    the contact comes from ``mj_geomDistance``: the witness points' midpoint, the normal into the
    object, the exact distance."""
    hand = '<geom name="h" type="box" size="0.01 0.01 0.01" contype="0" conaffinity="0"/>'
    model = mujoco.MjModel.from_xml_string(_gap_xml(hand, pair='<pair geom1="h" geom2="o"/>'))
    data = mujoco.MjData(model)
    (c,) = detected_contacts(model, data, object_body="object", tolerance=TOL)
    assert (c.geom, c.distance) == ("h", pytest.approx(1.5e-3, abs=1e-12))
    np.testing.assert_allclose(c.normal, [-1.0, 0.0, 0.0], atol=1e-12)
    assert c.position[0] == pytest.approx(0.02075, abs=1e-12)  # midway between x = 20 and 21.5 mm


def test_geoms_that_cannot_collide_are_not_contacts() -> None:
    """A visual geom (contype = conaffinity = 0) and an excluded body pair are not candidates,
    however near: MuJoCo's own filter."""
    visual = '<geom name="h" type="box" size="0.01 0.01 0.01" contype="0" conaffinity="0"/>'
    for xml in (_gap_xml(visual), _gap_xml(TWO_GEOMS, exclude='<exclude body1="hand" body2="object"/>')):
        model = mujoco.MjModel.from_xml_string(xml)
        assert candidate_pairs(model, {model.body("object").id}) == []
        assert detected_contacts(model, mujoco.MjData(model), object_body="object", tolerance=TOL) == []


def test_candidate_pairs_are_read_anew_when_the_model_changes() -> None:
    """The pairs are kept per model structure: a model compiled again from the same file gets
    the same ones, and a collision flag edited in place or other object bodies are read anew."""
    model = mujoco.MjModel.from_xml_string(_gap_xml(TWO_GEOMS))
    ob = {model.body("object").id}
    every = [(0, 2), (0, 3), (1, 2), (1, 3)]  # the hand's h, h2 (geoms 0, 1) x the object's o, o2
    candidate_pairs(model, ob).clear()  # the caller's copy: the memo keeps its own
    assert candidate_pairs(model, ob) == every
    assert candidate_pairs(mujoco.MjModel.from_xml_string(_gap_xml(TWO_GEOMS)), ob) == every
    model.geom_contype[1] = model.geom_conaffinity[1] = 0  # h2 made visual, in place
    assert candidate_pairs(model, ob) == [(0, 2), (0, 3)]
    assert candidate_pairs(model, {model.body("hand").id}) == [(2, 0), (3, 0)]  # the hand as object
