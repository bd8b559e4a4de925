"""Problem 1's projection (eq. 26-29): hand-derived planar TVMSs, degenerate cases, LP vs cdd."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.synthetic import random_state
from mjtvm import Contact, GraspState, default_operation_range
from mjtvm.polytopes.enumeration import force_form, project_cdd
from mjtvm.polytopes.lifted import lifted_polytope
from mjtvm.polytopes.projection import project_lp
from mjtvm.polytopes.tvms import tvms
from mjtvm.polytopes.volume import hausdorff
from mjtvm.problem2 import assemble

from ..helpers import T_MAX, distance_to_hull, max_speed

OP = default_operation_range()
R = 0.05  # m: the contacts sit at (-R, 0) and (R, 0), the object's reference point at the origin
J = np.array([[0.1, 0.0], [0.05, 0.1]])  # m/rad: both contact points move with J qd
MG = 2.0  # N
G_F = np.array([0.1, -0.05])  # N m


def gripper(jac, refs, *, g_f=G_F, types=("F", "F"), mu=0.5, base=False) -> GraspState:
    """A planar object squeezed between two jaws at (-R, 0) and (R, 0) that both move with
    the same joints (contact-point velocity ``jac @ qd``); optionally resting on a fixed base
    at (0, -R) through an L-point."""
    jac = np.asarray(jac, float)
    m = jac.shape[1]
    contacts = [
        Contact("left", types[0], [-R, 0.0], [1.0, 0.0], jac, mu=mu),
        Contact("right", types[1], [R, 0.0], [-1.0, 0.0], jac, mu=mu),
    ]
    if base:
        contacts.append(Contact("base", "L", [0.0, -R], [0.0, 1.0], np.zeros((2, m))))
    return GraspState(
        2,
        [0.0, 0.0],
        tuple(f"q{j}" for j in range(m)),
        (OP,) * m,
        np.asarray(g_f, float)[:m],
        tuple(contacts),
        np.array(refs, float),
    )


def assert_same_vertices(actual: np.ndarray, expected: np.ndarray, rel: float = 1e-7) -> None:
    assert len(actual) == len(expected)
    scale = max(float(np.max(np.abs(expected))), 1e-300)
    assert hausdorff(actual, expected) <= rel * scale


def assert_same_polytope(lp: np.ndarray, cdd: np.ndarray, rel: float = 1e-7) -> None:
    """The LP projection and float cddlib give the same polytope: every cdd vertex is an LP
    vertex (within ``rel``), and an LP vertex that cdd lacks lies within ``rel`` of cdd's hull.

    Float cddlib can drop a vertex that stands out of the hull of its neighbours by less than
    its own tolerance: on random_state(2, space=3, joints_per_finger=3, num_refs=2) with numpy
    2.5 / scipy 1.18 (Python >= 3.12) one LP vertex lies 1.0e-8 relative outside the hull of
    the others and 3.4e-5 from its nearest neighbour, and cdd returns 56 of the 57. A vertex
    count cannot be decided below the tolerances; the polytope can.
    """
    scale = max(float(np.max(np.abs(cdd))), 1e-300)
    from scipy.spatial.distance import cdist

    nearest = cdist(lp, cdd).min(axis=0)
    assert np.all(nearest <= rel * scale), "cdd has a vertex that the LP projection lacks"
    unmatched = lp[cdist(lp, cdd).min(axis=1) > rel * scale]
    assert len(unmatched) <= 1, f"{len(unmatched)} LP vertices not in cdd's answer"
    if len(unmatched):
        assert np.all(distance_to_hull(unmatched, cdd) <= rel * scale)


def both(state: GraspState, **kw):
    poly = lifted_polytope(state, **kw)
    return project_lp(poly), project_cdd(poly, time_limit=60.0)


def test_parallelogram_derived_by_hand():
    r"""Two F-jaws on one 2-joint stage, REFS = {(0, -mg, 0)}.

    Kinematics (eq. 7): J qd = G_i^T rdot at both contacts, G_1^T rdot = (v_x, v_y - R w)
    and G_2^T rdot = (v_x, v_y + R w); subtracting, w = 0, then (v_x, v_y) = J qd.
    Statics (eq. 20): f_1 + f_2 = (0, mg); moments about the origin -R f_1y + R f_2y = 0, so
    f_1y = f_2y = mg / 2 and f_1x = -f_2x = N >= mg / (2 mu): any large squeeze N works.
    Torques (eq. 19): tau = J^T (f_1 + f_2) + g_f = J^T (0, mg) + g_f = (0.2, 0.15) N m,
    whatever N. Operation range (RE25 through 1/40, eq. 2): |qd_j| <= s(|tau_j|), the
    speed-torque line s(t) = Q0 - (Q0 - Qn) t / T for t <= T. Hence S_ov is the
    parallelogram {(J qd, 0) : |qd_j| <= s_j} with vertices J (+-s_1, +-s_2): 2-D in the
    3-D twist space, area |det J| 4 s_1 s_2, scaled by diag(10, 10, 1): 100 times that.
    The lifted polytope is unbounded (the squeeze), its projection is not.
    """
    state = gripper(J, [[0.0, -MG, 0.0]])
    tau = J.T @ [0.0, MG] + G_F
    assert np.allclose(tau, [0.2, 0.15]) and np.all(np.abs(tau) < T_MAX)
    s1, s2 = max_speed(tau[0]), max_speed(tau[1])
    expected = np.array([[*(J @ [a * s1, b * s2]), 0.0] for a in (1, -1) for b in (1, -1)])
    lp, cdd = both(state)
    for proj in (lp, cdd):
        assert proj.status == "bounded" and proj.dimension == 2
        assert_same_vertices(proj.vertices, expected)
    # The facets (LP method): the parallelogram's four edges |qd_j| <= s_j, i.e. the rows of
    # +-J^{-T} e_j over (v_x, v_y), with offsets s_j after normalising.
    normals, offsets = lp.facets
    jinv = np.linalg.inv(J)
    rows = np.array([sign * np.append(jinv[j], 0.0) for j in (0, 1) for sign in (1.0, -1.0)])
    limits = np.array([s1, s1, s2, s2]) / np.linalg.norm(rows, axis=1)
    rows /= np.linalg.norm(rows, axis=1)[:, None]
    assert len(normals) == 4
    for row, limit in zip(rows, limits):
        j = np.argmax(normals @ row)
        np.testing.assert_allclose(normals[j], row, atol=1e-9)
        assert offsets[j] == pytest.approx(limit, rel=1e-9)
    assert np.all(expected @ normals.T <= offsets + 1e-9)
    result = tvms(state)
    area = abs(np.linalg.det(J)) * 4 * s1 * s2
    assert result.volume == 0.0
    assert result.affine_volume == pytest.approx(100 * area, rel=1e-9)


def test_two_refs_vertices_share_one_box():
    r"""REFS = {(0, -mg, 0), (0, mg, 0)}: one qd and box for both (eq. 26).

    Vertex 1 needs tau = (0.2, 0.15) (previous test); vertex 2, pulled up, f_1 + f_2 =
    (0, -mg) and tau = J^T (0, -mg) + g_f = (0.0, -0.25). The common box allows
    |qd_j| <= min_i s(|tau_ij|): s_1 = s(0.2), s_2 = s(0.25); S_ov is the parallelogram
    J (+-s_1, +-s_2).
    """
    state = gripper(J, [[0.0, -MG, 0.0], [0.0, MG, 0.0]])
    assert np.allclose(J.T @ [0.0, -MG] + G_F, [0.0, -0.25])
    s1, s2 = max_speed(0.2), max_speed(0.25)
    expected = np.array([[*(J @ [a * s1, b * s2]), 0.0] for a in (1, -1) for b in (1, -1)])
    for proj in both(state):
        assert_same_vertices(proj.vertices, expected)


def test_segment_and_point():
    r"""One joint moving both jaws along x: (0.1 qd, 0) = (v_x, v_y -+ R w), so v_y = w = 0 and
    v_x = 0.1 qd; tau = J^T (0, mg) + g_f = g_f1 = 0.1 N m (the weight acts along y): the
    segment 0.1 (+-s(0.1), 0, 0), dimension 1, scaled length 2 s(0.1). Fixed jaws (J = 0):
    only the origin, dimension 0."""
    seg = gripper([[0.1], [0.0]], [[0.0, -MG, 0.0]])
    end = 0.1 * max_speed(0.1)
    for proj in both(seg):
        assert proj.dimension == 1
        assert_same_vertices(proj.vertices, np.array([[end, 0, 0], [-end, 0, 0]]))
    assert tvms(seg).affine_volume == pytest.approx(2 * max_speed(0.1), rel=1e-9)
    point = gripper(np.zeros((2, 1)), [[0.0, -MG, 0.0]])
    for proj in both(point):
        assert proj.status == "bounded" and proj.dimension == 0
        assert np.allclose(proj.vertices, 0.0) and len(proj.vertices) == 1


def test_empty_when_statics_infeasible():
    """mg = 20 N needs tau_2 = 0.1 * 20 - 0.05 = 1.95 N m > T_MAX = 1.052 N m: no balance."""
    state = gripper(J, [[0.0, -20.0, 0.0]])
    for proj in both(state):
        assert proj.status == "empty" and proj.dimension == -1 and len(proj.vertices) == 0


def test_unbounded_free_spin():
    r"""Frictionless jaws (normals through the centre) and an L-point on a fixed base: the
    jaws give v_x = 0.1 qd_1, the base v_y = 0 (its point moves as (v_x + R w, v_y)), and
    nothing resists the spin w: unbounded along +-(0, 0, 1)."""
    state = gripper(J, [[0.0, -MG, 0.0]], types=("L", "L"), base=True)
    lp, cdd = both(state)
    for proj in (lp, cdd):
        assert proj.status == "unbounded" and len(proj.vertices) == 0
        assert abs(proj.unbounded_direction[2]) == pytest.approx(1.0, abs=1e-9)
    assert lp.dimension == 2


def test_unbounded_rolling_about_one_contact():
    r"""One F-jaw at (-R, 0), no load: J qd = (v_x, v_y - R w) bounds v_x and v_y - R w only,
    so the object rolls about the contact without limit: direction +-(0, R, 1)."""
    state = GraspState(
        2,
        [0.0, 0.0],
        ("q0", "q1"),
        (OP, OP),
        [0.0, 0.0],
        (Contact("left", "F", [-R, 0.0], [1.0, 0.0], J, mu=0.5),),
        np.zeros((1, 3)),
    )
    roll = np.array([0.0, R, 1.0]) / np.hypot(R, 1.0)
    for proj in both(state):
        assert proj.status == "unbounded"
        assert abs(proj.unbounded_direction @ roll) == pytest.approx(1.0, abs=1e-9)


def test_lifted_polytope_reuses_the_assembly():
    """The lifted rows are the assembly's (K copies, -w_k on the balance rows), plus the twist
    columns: A_twist itself, or A_twist R^T for the RVDS cone (origin dropped)."""
    state = random_state(3, space=3, fingers=2, joints_per_finger=3, num_refs=2, friction_edges=6)
    asm = assemble(state, copies=2)
    lower, upper = asm.statics_bounds(state.refs)
    for cone in (False, True):
        poly = lifted_polytope(state, rvds_cone=cone)
        n = asm.num_variables
        assert abs(poly.A[:, :n] - asm.A).max() == 0.0
        gens = state.rvds.T if cone else np.eye(6)
        assert np.allclose(poly.A[:, n:].toarray(), asm.A_twist @ gens)
        assert np.array_equal(poly.row_lower, lower) and np.array_equal(poly.row_upper, upper)
        assert poly.cone is cone


def test_force_form_has_the_papers_variables():
    """F-points in space: 16 edge weights become 3 force components and 16 facet rows."""
    state = random_state(0, space=3, fingers=2, joints_per_finger=2, contact_types=("F", "L"))
    poly = lifted_polytope(state, rvds_cone=False)
    ff = force_form(poly)
    assert poly.A.shape[1] - ff.A.shape[1] == 16 - 3
    assert ff.A.shape[0] - poly.A.shape[0] == 16


CASES = [
    (2, 2, 0, 1),
    (2, 2, 1, 2),
    (2, 3, 1, 1),
    (2, 3, 3, 2),
    (3, 2, 2, 1),
    (3, 2, 3, 2),
    (3, 3, 0, 1),
    (3, 3, 1, 2),
    (3, 3, 2, 2),
    (3, 3, 3, 2),
]


@pytest.mark.parametrize(("space", "joints", "seed", "refs"), CASES)
def test_lp_and_cdd_agree_on_random_states(space, joints, seed, refs):
    state = random_state(
        seed, space=space, fingers=2, joints_per_finger=joints, num_refs=refs, friction_edges=6
    )
    lp, cdd = both(state, rvds_cone=False)
    assert lp.status == cdd.status == "bounded"
    assert lp.dimension == cdd.dimension
    assert_same_polytope(lp.vertices, cdd.vertices)


@pytest.mark.parametrize("types", [("F", "L"), ("F", "L", "D")])
def test_full_dimensional_planar_volumes_agree(types):
    state = random_state(0, space=2, fingers=2, joints_per_finger=3, contact_types=types)
    lp, cdd = tvms(state, rvds_cone=False), tvms(state, method="cdd", rvds_cone=False)
    assert lp.dimension == cdd.dimension == 3
    assert lp.volume > 0 and lp.volume == pytest.approx(cdd.volume, rel=1e-9)
    assert_same_vertices(lp.vertices, cdd.vertices)
