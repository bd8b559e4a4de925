"""The contact report of a grasp (mjtvm.grasp.contacts.report): penetration refused or reported, IK
targets that are not the geoms that touch, and the rows of ``mjtvm show``."""

from __future__ import annotations

from dataclasses import replace
from types import MappingProxyType
from typing import Any

import numpy as np
import pytest

from mjtvm.grasp.contacts.report import contact_rows, contact_warnings
from mjtvm.grasp.document.document import GraspError
from mjtvm.grasp.resolve.file import load_grasp
from tests.grasp.resolve.test_file import _doc

R_BALL = 0.1  # m: case 2's ball, centre at z = 0.1 on the palm plane z = 0


def _sunk(**changes: Any) -> dict[str, Any]:
    """Case 2 with the ball 1.5 mm lower: 1.5 mm into the palm (a plane: exact), the fingertips
    f1 and f3 a fraction of a millimetre into it, f2 and f4 0.62 mm off (within 1 mm)."""
    return _doc(
        object={"body": "object", "position": [0.0, 0.0, 0.0985]},
        contact_tolerance=1e-3,
        ignore=[{"geom": "f1_link2"}, {"geom": "f3_link2"}],
        **changes,
    )


def test_penetration_beyond_max_penetration_is_an_error() -> None:
    grasp = load_grasp(_sunk())
    with pytest.raises(
        GraspError,
        match=r"^grasp: contacts\[0\]: geom 'palm' is 1\.5 mm inside the object's geom 'object' > "
        r"max_penetration 1 mm: move the finger out \(or raise max_penetration\)$",
    ):
        grasp.state()
    doc = _sunk(max_penetration=2e-4)
    doc["contacts"], doc["ignore"] = (
        doc["contacts"][1:],
        [*doc["ignore"], {"geom": "palm"}],
    )  # an ignored palm may sink
    with pytest.raises(
        GraspError, match=r"contacts\[0\]: geom 'f1_tip' is 0\.231 mm inside .* > max_penetration 0\.2 mm"
    ):
        load_grasp(doc).state()


def test_smaller_penetration_is_reported() -> None:
    grasp = load_grasp(_sunk(max_penetration=2e-3))
    grasp.state()  # accepted
    warnings = contact_warnings(grasp)
    assert warnings == [  # one cause, one line, counting its contacts
        "3 contacts are inside the object's geom 'object', by up to 1.5 mm (max_penetration 2 mm): "
        "contacts[0] 'palm' 1.5 mm, contacts[1] 'f1_tip' 0.231 mm, contacts[3] 'f3_tip' 0.378 mm"
    ]
    doc = _sunk(max_penetration=2e-3)
    doc["contacts"], doc["ignore"] = doc["contacts"][1:], [*doc["ignore"], {"geom": "palm"}]
    assert contact_warnings(load_grasp(doc)) == [
        "2 contacts are inside the object's geom 'object', by up to 0.378 mm (max_penetration 2 mm): "
        "contacts[0] 'f1_tip' 0.231 mm, contacts[2] 'f3_tip' 0.378 mm"
    ]
    doc["contacts"] = doc["contacts"][:1]
    doc["ignore"] = [*doc["ignore"], {"geom": "f3_tip"}]
    assert contact_warnings(load_grasp(doc)) == [
        "contacts[0]: geom 'f1_tip' is 0.231 mm inside the object's geom 'object' (max_penetration 2 mm)"
    ]


def test_touching_grasps_report_nothing() -> None:
    """Contacts placed touching (case 2, exactly; the Allegro's IK, within 2e-8 m) are not reported."""
    for name in ("case2", "allegro-ik"):
        assert contact_warnings(load_grasp(name)) == []


def test_ik_target_that_is_not_the_touching_geom_is_reported() -> None:
    """An IK target on the link capsule of case 2's finger 1 (1 mm from the ball) while the
    fingertip sphere of the same body touches: the warning names both."""
    grasp = load_grasp("case2")
    config = {
        "ik": {"targets": [{"geom": "f1_link2"}, {"geom": "f1_tip"}, {"site": "f2_site", "point": [0, 0, 0]}]}
    }
    grasp = replace(grasp, document=MappingProxyType({**grasp.document, "configuration": config}))
    assert contact_warnings(grasp) == [
        "configuration.ik.targets[0]: the IK target geom 'f1_link2' is 1 mm from the object; geom "
        "'f1_tip' (0 mm) of its body touches it instead: the contact is not the IK target's"
    ]


def test_contact_rows_of_case2() -> None:
    """Case 2: the palm and four fingertips touch (selected), the link capsules of fingers 2-4
    are 1 mm off (the default reach is 10 tolerances, at least 1 mm), with their exact normals."""
    grasp = load_grasp("case2")
    rows = contact_rows(grasp)
    selected = [(r.geom, r.type) for r in rows if r.selected]
    assert selected == [("palm", "D"), ("f1_tip", "F"), ("f2_tip", "L"), ("f3_tip", "F"), ("f4_tip", "L")]
    assert all(abs(r.distance) < 1e-12 for r in rows if r.selected)
    near = [r for r in rows if not r.selected]
    assert {r.geom for r in near} == {"f2_link2", "f3_link2", "f4_link2"}
    for r in near:
        assert r.why == "beyond contact_tolerance" and r.type is None
        assert r.distance == pytest.approx(1e-3, abs=1e-9)
        # a link capsule beside the ball: the normal into the ball points at its centre
        centre = np.array([0.0, 0.0, 0.1])
        expected = (centre - r.position) / np.linalg.norm(centre - r.position)
        assert r.normal is not None
        np.testing.assert_allclose(r.normal, expected, atol=1e-6)
    palm = rows[0]
    np.testing.assert_allclose(palm.normal, [0, 0, 1], atol=1e-12)  # from the palm up into the ball
    assert R_BALL == pytest.approx(0.1 - float(palm.position[2]), abs=1e-12)
    assert [r.geom for r in contact_rows(grasp, within=1e-4)] == [g for g, _ in selected]


def test_ignored_and_shadowed_rows_say_why() -> None:
    rows = {r.geom: r for r in contact_rows(load_grasp("case1"))}
    assert (rows["palm"].type, rows["palm"].selected, rows["palm"].why) == ("ignore", False, "ignored")
    assert rows["f1_link2"].why == "a deeper contact of its body is kept"


def test_hand_geoms_that_overlap_each_other_are_reported() -> None:
    """The shipped Shadow grasp's first and middle fingers overlap at the configuration (a
    contact no LP sees, which the physics check feels); the paper's Case 2 hand does not."""
    from mjtvm.grasp.contacts.report import contact_warnings
    from mjtvm.grasp.resolve.file import load_grasp

    lines = [w for w in contact_warnings(load_grasp("shadow_hand-sphere")) if w.startswith("hand geoms")]
    assert lines == [
        "hand geoms 'ff_middle' and 'mf_middle' overlap by 0.172 mm: a contact of the hand with itself, which no LP sees",
        "hand geoms 'ff_distal' and 'mf_middle' overlap by 0.267 mm: a contact of the hand with itself, which no LP sees",
    ]
    assert not [w for w in contact_warnings(load_grasp("case2")) if w.startswith("hand geoms")]


def test_a_contact_typed_by_a_rule_is_checked_for_penetration_too() -> None:
    """The palm typed D by a rule instead of a contacts entry: the same 1.5 mm refused, named
    by the rule's field; within the limit, the penetration is reported under that field."""
    doc = _sunk()
    doc["contacts"] = doc["contacts"][1:]  # the palm's entry goes; a rule types it
    doc["contact_rules"] = [{"geom": "palm", "type": "D"}]
    with pytest.raises(
        GraspError, match=r"^grasp: contact_rules\[0\]: geom 'palm' is 1\.5 mm inside the object's geom"
    ):
        load_grasp(doc).state()
    doc["max_penetration"] = 2e-3
    warnings = contact_warnings(load_grasp(doc))
    assert any("contact_rules[0] 'palm' 1.5 mm" in w for w in warnings), warnings


def test_a_self_overlap_of_several_contact_points_is_one_line() -> None:
    """MuJoCo gives a capsule beside a box two contact points: one warning for the pair, counting
    them, at the deeper one's depth."""
    import mujoco

    from mjtvm.grasp.contacts.report import REPORTED_PENETRATION

    grasp = load_grasp("shadow_hand-sphere")
    model = grasp.model
    for name in ("ff_middle", "mf_middle"):  # capsules made boxes of the same extent
        i = model.geom(name).id
        r, h, _ = model.geom_size[i]
        model.geom_type[i], model.geom_size[i] = mujoco.mjtGeom.mjGEOM_BOX, [r, r, h]
    data = mujoco.MjData(model)
    data.qpos[:] = grasp.data.qpos
    mujoco.mj_forward(model, data)
    pair = {model.geom("ff_distal").id, model.geom("mf_middle").id}
    depths = [-c.dist for c in data.contact[: data.ncon] if {int(c.geom1), int(c.geom2)} == pair]
    assert len(depths) == 2 and min(depths) > REPORTED_PENETRATION
    lines = [w for w in contact_warnings(grasp) if w.startswith("hand geoms")]
    assert len(lines) == 2 and len([w for w in lines if "'ff_distal'" in w]) == 1
    assert f"overlap by {round(1e3 * max(depths), 6):.3g} mm (2 contact points): a contact" in lines[1]
