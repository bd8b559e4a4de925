"""Problem 1 when no force binds: the TVMS as the image of the joint-speed box (mjtvm.polytopes.speed_box).

The zonotope path (``tvms(method="auto")``) against the LP projection (``method="lp"``) on the
same states, to 1e-9 relative; against the hull of the 2^n images of the box's corners, an
enumeration independent of both; and every condition of the module docstring that sends a
state back to the LPs.
"""

from __future__ import annotations

import itertools
import json

import jsonschema
import numpy as np
import pytest
from scipy.spatial import ConvexHull

from benchmarks.peers import TRANSLATIONS, fingertip_jacobian, fingertip_state
from mjtvm.errors import ParamError
from mjtvm.model.contacts import Contact
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.transmission import Transmission
from mjtvm.polytopes.tvms import tvms
from mjtvm.polytopes.volume import hausdorff

from ..helpers import Q_MAX, max_speed

SCHEMA = json.loads(
    (__import__("importlib.resources").resources.files("mjtvm") / "data/schema/tvms.schema.json").read_text()
)


def assert_same_result(fast, slow, rel: float = 1e-9) -> None:
    """The zonotope result and the LP result: vertices, dimension, volumes, alphas."""
    assert fast.method == "zonotope" and slow.method == "lp"
    assert fast.status == slow.status == "bounded" and fast.dimension == slow.dimension
    assert len(fast.vertices) == len(slow.vertices)
    extent = float(np.max(np.abs(slow.vertices * slow.scale)))
    assert hausdorff(fast.vertices * fast.scale, slow.vertices * slow.scale) <= rel * extent
    assert fast.affine_volume == pytest.approx(slow.affine_volume, rel=rel)
    assert fast.volume == pytest.approx(slow.volume, rel=rel, abs=0.0)
    if slow.alpha_bracket is not None:
        assert np.allclose(fast.alpha_bracket, slow.alpha_bracket, rtol=rel, atol=0.0, equal_nan=True)
    assert fast.timings.num_lps == 0


def corner_images(jac: np.ndarray, half: np.ndarray) -> tuple[np.ndarray, float]:
    """The vertices and volume of the hull of J s for every corner s of the box |s_i| <= half_i."""
    pts = np.array(list(itertools.product((-1.0, 1.0), repeat=len(half)))) * half @ jac.T
    h = ConvexHull(pts)
    return pts[h.vertices], float(h.volume)


@pytest.mark.parametrize("joints", [3, 4, 7, 12])
def test_fingertip_translations_are_the_velocity_polytope(joints: int) -> None:
    state = fingertip_state(joints)
    fast, slow = tvms(state), tvms(state, method="lp")
    assert_same_result(fast, slow)
    verts, vol = corner_images(fingertip_jacobian(joints), np.full(joints, Q_MAX))
    assert fast.dimension == 3 and fast.volume == 0.0 and np.all(fast.vertices[:, 3:] == 0.0)
    assert len(fast.vertices) == len(verts)
    assert hausdorff(fast.vertices[:, :3], verts) <= 1e-12 * np.abs(verts).max()
    assert fast.affine_volume == pytest.approx(1e3 * vol, rel=1e-9)  # scaled by 10 per translation
    doc = fast.to_dict()
    jsonschema.validate(doc, SCHEMA)
    assert doc["method"] == "zonotope" and doc["timings"]["num_lps"] == 0


def test_gravity_torque_on_one_contact_narrows_the_box() -> None:
    """One contact: its force must be 0, each torque is its gravity torque and the box's
    half-widths are the speeds there (the RE25 line); the LP path agrees."""
    state = fingertip_state(4).with_(gravity_torque=np.array([0.3, -0.2, 0.0, 0.5]))
    fast, slow = tvms(state), tvms(state, method="lp")
    assert_same_result(fast, slow)
    half = np.array([max_speed(g) for g in state.gravity_torque])
    verts, vol = corner_images(fingertip_jacobian(4), half)
    assert hausdorff(fast.vertices[:, :3], verts) <= 1e-9 * np.abs(verts).max()
    assert fast.affine_volume == pytest.approx(1e3 * vol, rel=1e-9)


def test_full_twist_space_without_rvds_cone_and_a_planar_finger() -> None:
    """No cone: one point contact leaves the object free to spin: the LPs say unbounded. In
    the plane, one F contact and the RVDS of both translations: a zonogon."""
    state = fingertip_state(3)
    assert tvms(state, rvds_cone=False).status == "unbounded"
    with pytest.raises(ParamError, match=r"^method: .*free to move"):
        tvms(state, rvds_cone=False, method="zonotope")
    rng = np.random.default_rng(5)
    jac = 0.05 * rng.normal(size=(2, 5))
    planar = state.with_(
        space=2,
        object_position=np.zeros(2),
        joint_names=tuple(f"j{i}" for i in range(5)),
        operation_ranges=state.operation_ranges[:1] * 5,
        gravity_torque=np.zeros(5),
        contacts=(Contact("tip", "F", np.array([0.0, -0.02]), np.array([0.0, 1.0]), jac, mu=0.5),),
        refs=np.zeros((1, 3)),
        rvds=np.array([[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0]]),
    )
    fast, slow = tvms(planar), tvms(planar, method="lp")
    assert_same_result(fast, slow)
    assert fast.dimension == 2 and len(fast.vertices) == 10


def test_one_rolling_contact_along_its_normal_is_a_segment() -> None:
    """An L contact fixes only the normal speed: with the RVDS +-n the TVMS is the segment
    |v| <= sum_i |n^T J_i| qd_max_i."""
    state = fingertip_state(4)
    c = state.contacts[0]
    n = c.normal
    rolling = state.with_(
        contacts=(Contact("tip", "L", c.position, n, c.jacobian),),
        rvds=np.array([[*n, 0, 0, 0], [*(-n), 0, 0, 0]]),
    )
    fast, slow = tvms(rolling), tvms(rolling, method="lp")
    assert_same_result(fast, slow)
    half = float(np.abs(n @ c.jacobian).sum() * Q_MAX)
    assert fast.dimension == 1
    assert np.sort(fast.vertices @ np.r_[n, 0, 0, 0]) == pytest.approx([-half, half], rel=1e-12)


def test_every_condition_sends_the_state_back_to_the_lps() -> None:
    state = fingertip_state(4)
    c = state.contacts[0]
    other = fingertip_jacobian(4, seed=1)
    two = Contact("other", "F", np.array([0.0, 0.02, 0.0]), np.array([0.0, -1.0, 0.0]), other, mu=0.5)
    half_box = OperationRange.box(1.0, 10.0)
    cases = {
        "a REFS wrench needs contact forces": state.with_(refs=np.array([[0, 0, -1.0, 0, 0, 0]])),
        "has a preload": state.with_(
            contacts=(Contact("tip", "F", c.position, c.normal, c.jacobian, mu=0.5, preload=1.0),)
        ),
        "is a S contact": state.with_(
            contacts=(
                Contact(
                    "tip",
                    "S",
                    c.position,
                    c.normal,
                    c.jacobian,
                    mu=0.5,
                    slide_direction=np.array([1.0, 0, 0]),
                ),
            )
        ),
        "transmission": state.with_(
            transmission=Transmission(tuple(f"a{i}" for i in range(4)), np.eye(4), (), None)
        ),
        "exceeds its joint's torque": state.with_(gravity_torque=np.array([2.0, 0, 0, 0])),
        "lowers its speed": state.with_(
            contacts=(c, two),
            operation_ranges=(half_box,) * 3 + (OperationRange(np.array([[0, 0], [1.0, 0], [0, 10.0]])),),
            gravity_torque=np.array([0, 0, 0, 0.1]),
        ),
        "not a linear subspace": state.with_(rvds=TRANSLATIONS[:4]),
        "restrict the joint speeds": state.with_(contacts=(c, two)),
    }
    for why, bad in cases.items():
        with pytest.raises(ParamError, match=rf"^method: .*{why}"):
            tvms(bad, method="zonotope")
        assert tvms(bad).method == "lp"


def test_two_contacts_that_move_together_with_squeezing_forces() -> None:
    """Two F contacts on one link at the object's translations: the kinematics leave the joints
    free, the squeezing forces could load the joints but need not (full speed at g = 0): the
    LPs give the same zonotope."""
    state = fingertip_state(5)
    c = state.contacts[0]
    twin = Contact("twin", "F", np.array([0.0, 0.0, 0.02]), np.array([0.0, 0.0, -1.0]), c.jacobian, mu=0.5)
    both = state.with_(contacts=(c, twin))
    assert_same_result(tvms(both), tvms(both, method="lp"))


def test_command_line_takes_the_zonotope_by_default(tmp_path, capsys) -> None:
    """`mjtvm tvms STATE`: method auto gives the zonotope; --method zonotope on a loaded grasp
    is one line naming the option's field, exit 2."""
    from mjtvm.cli import main
    from mjtvm.formats.state_file import state_to_dict

    path = tmp_path / "tip.json"
    path.write_text(json.dumps(state_to_dict(fingertip_state(4))))
    assert main(["tvms", str(path), "--quiet"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["method"] == "zonotope" and len(doc["vertices"]) == 14
    assert main(["tvms", "case1", "--method", "zonotope", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "method" in err[0] and "REFS wrench" in err[0]


def test_speeds_at_gravity_torques_match_the_operation_range() -> None:
    """The box's half-widths (one vectorised pass per distinct range) equal
    OperationRange.max_speed_at to the bit, and -inf beyond the largest torque."""
    from mjtvm.model.operation_range import default_operation_range
    from mjtvm.polytopes.speed_box import _speeds_at

    motor, box = default_operation_range(), OperationRange.box(2.0, 10.0)
    ranges = (motor, box, motor, box, motor)
    torques = np.array([0.0, -1.5, 0.7, 2.5, -1.052])
    expected = [r.max_speed_at(t) for r, t in zip(ranges, torques, strict=True)]
    assert _speeds_at(ranges, torques).tolist() == expected
    assert expected[3] == -np.inf and expected[1] == 10.0
