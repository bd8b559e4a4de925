"""Problem 2 (eq. 31-35) on cases whose alphas are derived by hand in each docstring."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.synthetic import random_state
from mjtvm import Contact, GraspState, StateError, default_operation_range, tvmmp
from mjtvm.problem2.assembly import grasp_map_transpose

from ..helpers import Q_MAX, T_MAX, G, max_speed

OP = default_operation_range()

# A planar one-joint finger: joint at the origin, link along +x (q = 0), length 0.1 m,
# mass 0.051 kg at mid-link. The object rests on the link at distance A from the joint.
A, LINK_L, LINK_M = 0.05, 0.1, 0.051
G_F = LINK_M * G * LINK_L / 2  # torque holding the horizontal link against gravity


def one_joint_state(contacts, refs, rvds, *, object_position=(A, 0.03), g_f=G_F) -> GraspState:
    return GraspState(
        2,
        object_position,
        ("q",),
        (OP,),
        [g_f],
        tuple(contacts),
        np.array(refs, float),
        np.array(rvds, float),
    )


def link_contact(ctype="F", mu=0.3, **kw) -> Contact:
    # Contact point (A, 0) on the link: its velocity is qd * (0, A) (J = [[0], [A]]).
    return Contact("tip", ctype, [A, 0.0], [0.0, 1.0], [[0.0], [A]], mu=mu, **kw)


def test_planar_one_joint_finger_lifts_object_on_its_link():
    r"""Object resting on the link, lifted straight up with r = (0, 1, 0).

    Statics: the only contact force balances w = (0, -mg, 0): f = (0, mg), and its
    moment about p_O = (A, R) is zero since it acts along the line through p_O.
    Torque (eq. 19): tau = J^T f + g_f = A mg + m_l g l / 2.
    Kinematics (eq. 7, F): J qd = G^T rdot, i.e. (0, A qd) = (v_x + w R, v_y), so
    v_y = alpha = A qd. The speed-torque line bounds qd <= Q0 - (Q0 - Qn) tau / T.
    Hence alpha = A (Q0 - (Q0 - Qn) (A mg + m_l g l/2) / T).
    """
    mg = 1.0
    expected = A * max_speed(A * mg + G_F)
    for box in ("eliminated", "literal"):
        res = tvmmp(one_joint_state([link_contact()], [[0, -mg, 0]], [[0, 1, 0]]), box=box)
        assert res.status == (("optimal",),)
        assert res.tvmmp == pytest.approx(expected, rel=1e-9)
        w = res.witnesses[0][0]
        assert w.torques[0] == pytest.approx(A * mg + G_F, rel=1e-9)
        assert w.forces[0] == pytest.approx([0.0, mg], abs=1e-9)
        assert w.speeds[0] == pytest.approx(expected / A, rel=1e-9)
        # the box of eq. 2 contains the witness and its corners lie in the operation range
        tmin, tmax, qmin, qmax = w.box[0]
        assert tmin <= w.torques[0] <= tmax and qmin <= w.speeds[0] <= qmax
        for t in (tmin, tmax):
            for q in (qmin, qmax):
                assert OP.contains(t, q, tol=1e-8)


def test_several_refs_vertices_take_the_minimum():
    r"""REFS {(0, -1, 0), (0, -2, 0)}: alpha_k = A qd_max(A mg_k + g_f) as above, and the
    heavier vertex (k = 1) limits: TVMMP = alpha_1 < alpha_0 (eq. 32)."""
    res = tvmmp(one_joint_state([link_contact()], [[0, -1, 0], [0, -2, 0]], [[0, 1, 0]]))
    a0, a1 = A * max_speed(A * 1 + G_F), A * max_speed(A * 2 + G_F)
    assert res.alpha[:, 0] == pytest.approx([a0, a1], rel=1e-9)
    assert res.tvmmp == pytest.approx(a1, rel=1e-9)
    assert res.limiting == (1, 0)
    assert res.distribution[0] == pytest.approx([0, a1, 0], rel=1e-9)


def test_base_d_point_with_downward_direction_gives_exactly_zero():
    r"""A box resting on the link (F) at (A, 0) and on the base (D) at (A + 0.03, 0).

    D-point (eq. 10, zero Jacobian, n = (0, 1)): n^T (0 - G^T rdot) <= 0, i.e. the base
    point of the object moves up: v_y + w (0.03) >= 0. For r = (0, -1, 0), -alpha >= 0, so
    alpha = 0: feasible (statics as before, qd = 0) and exactly 0. Upward the D-point
    allows everything and alpha is the one-joint value. TVMMP = 0, feasible.
    """
    base = Contact("base", "D", [A + 0.03, 0.0], [0.0, 1.0], [[0.0], [0.0]])
    state = one_joint_state(
        [link_contact(), base], [[0, -1, 0]], [[0, -1, 0], [0, 1, 0]], object_position=(A, 0.02)
    )
    res = tvmmp(state)
    assert res.status == (("optimal", "optimal"),)
    assert res.alpha[0, 0] == 0.0
    assert res.tvmmp == 0.0 and res.feasible
    assert res.alpha[0, 1] == pytest.approx(A * max_speed(A + G_F), rel=1e-9)
    assert res.to_dict()["tvmmp"] == 0.0


def test_statics_that_cannot_be_balanced_are_infeasible():
    r"""Two ways to be infeasible (eq. 25 has no solution):

    * too heavy: tau = A mg + g_f > T_max when mg > (T_max - g_f) / A (= 20.5 N);
    * an L-point (eq. 22) pushes along its normal only, so a lateral load
      w = (1, -1, 0) cannot be balanced whatever the torques.
    """
    heavy = (T_MAX - G_F) / A * 1.01
    res = tvmmp(one_joint_state([link_contact()], [[0, -heavy, 0]], [[0, 1, 0], [1, 0, 0]]))
    assert res.status == (("infeasible", "infeasible"),)
    assert res.tvmmp is None and not res.feasible
    assert res.distribution == (None, None)
    assert res.to_dict()["alpha"] == [[None, None]]
    ok = tvmmp(one_joint_state([link_contact()], [[0, -heavy / 1.02, 0]], [[0, 1, 0]]))
    assert ok.status == (("optimal",),)
    lateral = tvmmp(one_joint_state([link_contact("L")], [[1, -1, 0]], [[0, 1, 0]]))
    assert lateral.status == (("infeasible",),) and not lateral.feasible


def test_friction_threshold_flips_feasibility_in_the_plane():
    r"""Load w = (wx, -mg, R wx) on the link contact (R = 0.03 above it).

    Force balance gives f = (-wx, mg); the moment of f about p_O = (A, R) is
    r_x f_y - r_y f_x = -R wx, cancelled by w's R wx. The planar cone (exact, eq. 21)
    admits f iff |wx| <= mu mg: the threshold is mu* = wx / mg = 0.25.
    """
    wx, mg, r = 0.25, 1.0, 0.03
    for mu, expected in ((0.24, "infeasible"), (0.2501, "optimal"), (0.26, "optimal")):
        res = tvmmp(one_joint_state([link_contact(mu=mu)], [[wx, -mg, r * wx]], [[0, 1, 0]]))
        assert res.status[0][0] == expected, mu
    res = tvmmp(one_joint_state([link_contact(mu=0.26)], [[wx, -mg, r * wx]], [[0, 1, 0]]))
    assert res.tvmmp == pytest.approx(A * max_speed(A * mg + G_F), rel=1e-9)


@pytest.mark.parametrize("angle", [0.0, np.pi / 16])
def test_friction_threshold_in_space_follows_the_pyramid(angle):
    r"""Spatial: one F contact at the origin, n = e_z, object centre 0.05 above it.

    Load w = (wx c, wx s, -mg, moment) with the tangential load at angle th from e_x.
    Default tangent rule: t1 = e_x (least aligned axis, lowest index on the tie), so the
    16 edges sit at th_k = 2 pi k / 16. Along an edge (th = 0) the pyramid reaches the
    cone: threshold mu* = wx / mg. Midway between two edges (th = pi/16) it reaches only
    the inscribed circle, mu cos(pi/16): threshold (wx / mg) / cos(pi/16).
    """
    wx, mg, h = 0.25, 1.0, 0.05
    tang = wx * np.array([np.cos(angle), np.sin(angle), 0.0])
    f = np.array([-tang[0], -tang[1], mg])  # the force that must balance w's force part
    moment = -np.cross([0, 0, -h], f)  # w's moment cancels the contact force's
    w = np.concatenate([-f, moment])
    jac = np.array([[1.0], [1.0], [1.0]])  # one joint moving the contact point diagonally
    threshold = wx / mg / np.cos(angle)
    for mu, expected in ((threshold * 0.999, "infeasible"), (threshold * 1.001, "optimal")):
        c = Contact("c", "F", [0, 0, 0], [0, 0, 1], jac, mu=mu)
        st = GraspState(3, [0, 0, h], ("q",), (OP,), [0.0], (c,), [w], [[1, 1, 1, 0, 0, 0]])
        assert tvmmp(st).status[0][0] == expected, mu


def test_s_point_kinetic_friction():
    r"""S-point on a thick link: contact at (A, H) (H above the joint axis), n = (0, 1),
    slide direction s = (1, 0), object centre (A, H + R).

    J = qd (-H, A). Kinetic friction (eq. 16-17): f = n_f (n - mu s) = n_f (-mu, 1).
    Balancing w = (mu mg, -mg, R mu mg) gives n_f = mg (moment of f about p_O:
    r_x f_y - r_y f_x = -R mu mg). Torque: tau = J^T f + g_f = (A + mu H) mg + g_f.
    Kinematics (eq. 8, 13) for r = (0, 1, 0): normal row A qd = alpha; tangential row
    (t = (-1, 0)): -(-H qd - (v_x + w R)) = rho, so rho = H qd >= 0. Hence
    alpha = A qd_max((A + mu H) mg + g_f). Downward r = (0, -1, 0): qd = -alpha / A and
    rho = -H alpha / A >= 0 force alpha = 0: the finger cannot slide against s.
    A normal component of the slide direction is ignored.
    """
    mu, mg, h, r = 0.3, 1.0, 0.01, 0.03
    jac = [[-h], [A]]
    w = [mu * mg, -mg, r * mu * mg]
    expected = A * max_speed((A + mu * h) * mg + G_F)
    for slide in ([1.0, 0.0], [2.0, 0.7]):
        c = Contact("s", "S", [A, h], [0.0, 1.0], jac, mu=mu, slide_direction=slide)
        st = one_joint_state([c], [w], [[0, 1, 0], [0, -1, 0]], object_position=(A, h + r))
        res = tvmmp(st)
        assert res.status == (("optimal", "optimal"),)
        assert res.alpha[0, 0] == pytest.approx(expected, rel=1e-9)
        assert res.alpha[0, 1] == 0.0
        assert res.witnesses[0][0].slip_speeds == pytest.approx([h * expected / A], rel=1e-9)
        assert res.witnesses[0][0].forces[0] == pytest.approx([-mu * mg, mg], rel=1e-9)


def turntable(g_f: float, rvds) -> GraspState:
    # A joint about e_z at the origin turns a plate; the object (centre (0, 0, H)) stands on
    # it on two F-points at (+-B, 0, 0). Contact velocities: qd e_z x p = qd (0, +-B, 0).
    b, h = 0.04, 0.05
    contacts = [
        Contact(f"c{i}", "F", [s * b, 0, 0], [0, 0, 1], [[0.0], [s * b], [0.0]], mu=0.5)
        for i, s in enumerate((1, -1))
    ]
    return GraspState(3, [0, 0, h], ("turn",), (OP,), [g_f], tuple(contacts), [[0, 0, -1.0, 0, 0, 0]], rvds)


def test_rotational_rvds_direction_in_space():
    r"""Turntable: r = (0, 0, 0, 0, 0, +-1), a pure rotation about the vertical axis.

    F-points (eq. 7): qd (0, +-B, 0) = alpha e_z x (+-B, 0, -H) = alpha (0, +-B, 0), so
    qd = alpha. Statics: the z-moment balance B f1y - B f2y = 0 kills the only torque the
    contacts could add (tau = B f1y - B f2y + g_f), so tau = g_f and
    alpha = qd_max(g_f) = Q0 - (Q0 - Qn) g_f / T. With g_f = 0: the no-load speed.
    A rotation about e_x needs qd = H alpha / B and qd = -H alpha / B: alpha = 0.
    """
    rvds = [[0, 0, 0, 0, 0, 1], [0, 0, 0, 0, 0, -1], [0, 0, 0, 1, 0, 0]]
    res = tvmmp(turntable(0.5, rvds))
    assert res.alpha[0] == pytest.approx([max_speed(0.5), max_speed(0.5), 0.0], rel=1e-9, abs=1e-12)
    assert tvmmp(turntable(0.0, rvds[:1])).tvmmp == pytest.approx(Q_MAX, rel=1e-9)


def test_sphere_spinning_under_frictionless_contacts_is_unbounded():
    r"""A sphere on one L-point at its bottom (base, zero Jacobian): any rotation about
    its centre moves the contact point tangentially, which eq. (8) does not constrain,
    so alpha is unbounded for r = omega; lifting needs v_z = 0 there: alpha = 0.
    TVMMP is the minimum over the optimal pairs (0); with only the rotation, none is
    optimal and TVMMP is null while the state stays feasible."""
    c = Contact("base", "L", [0, 0, 0], [0, 0, 1], np.zeros((3, 1)))
    rvds = [[0, 0, 0, 0, 0, 1], [0, 0, 1, 0, 0, 0]]
    st = GraspState(3, [0, 0, 0.1], ("q",), (OP,), [0.0], (c,), [[0, 0, -1, 0, 0, 0]], rvds)
    res = tvmmp(st)
    assert res.status == (("unbounded", "optimal"),)
    assert res.tvmmp == 0.0 and res.feasible
    only_spin = tvmmp(st.with_(rvds=np.array(rvds[:1], float)))
    assert only_spin.tvmmp is None and only_spin.feasible
    assert only_spin.distribution == (None,)


def test_origin_rvds_vertex_is_skipped():
    """Supplement 3: the origin is skipped; if it is the only vertex, feasibility is still checked."""
    st = one_joint_state([link_contact()], [[0, -1, 0]], [[0, 0, 0], [0, 1, 0]])
    res = tvmmp(st)
    assert res.status == (("skipped", "optimal"),)
    assert res.distribution[0] == pytest.approx([0, 0, 0])
    only = tvmmp(st.with_(rvds=np.zeros((1, 3))))
    assert only.status == (("skipped",),) and only.feasible and only.tvmmp is None
    heavy = tvmmp(st.with_(rvds=np.zeros((1, 3)), refs=np.array([[0, -100.0, 0]])))
    assert not heavy.feasible


def test_problem_2_needs_rvds():
    """A state without RVDS is incomplete data for Problem 2: the error names its field."""
    st = one_joint_state([link_contact()], [[0, -1, 0]], [[0, 1, 0]]).with_(rvds=None)
    with pytest.raises(StateError, match=r"^rvds: Problem 2 needs RVDS vertices"):
        tvmmp(st)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("box", ["eliminated", "literal"])
def test_witness_satisfies_the_paper_equations(seed, box):
    r"""Every optimal witness satisfies eq. (7)-(13), (19), (20), (24) and (2), checked
    here directly from the contacts, independently of the assembly."""
    types = ("F", "S", "L", "F", "D")
    state = random_state(seed, contact_types=types, num_rvds=4)
    res = tvmmp(state, box=box)
    assert res.feasible
    for l, w in enumerate(res.witnesses[0]):
        assert w is not None
        wrench = sum(
            grasp_map_transpose(c.position, state.object_position).T @ f
            for c, f in zip(state.contacts, w.forces)
        )
        assert wrench + state.refs[0] == pytest.approx(np.zeros(6), abs=1e-7)  # eq. 20
        tau = sum(c.jacobian.T @ f for c, f in zip(state.contacts, w.forces)) + state.gravity_torque
        assert w.torques == pytest.approx(tau, abs=1e-7)  # eq. 19
        s_index = 0
        for c, f in zip(state.contacts, w.forces):
            rel = c.jacobian @ w.speeds - grasp_map_transpose(c.position, state.object_position) @ w.twist
            nf = f @ c.normal
            if c.type == "F":
                assert rel == pytest.approx(np.zeros(3), abs=1e-7)  # eq. 7
                tangential = np.linalg.norm(f - nf * c.normal)
                assert tangential <= c.mu * nf + 1e-7  # inside the cone (the pyramid is inscribed)
            elif c.type == "D":
                assert c.normal @ rel <= 1e-7 and np.allclose(f, 0)  # eq. 10
            else:
                assert c.normal @ rel == pytest.approx(0, abs=1e-7)  # eq. 8
                assert nf >= -1e-9
            if c.type == "S":
                s = c.slide_direction - (c.slide_direction @ c.normal) * c.normal
                s /= np.linalg.norm(s)
                rho = w.slip_speeds[s_index]
                s_index += 1
                assert rel - (c.normal @ rel) * c.normal == pytest.approx(-rho * s, abs=1e-7)  # eq. 13
                assert f == pytest.approx(nf * (c.normal - c.mu * s), abs=1e-7)  # eq. 16
        for j, op in enumerate(state.operation_ranges):
            tmin, tmax, qmin, qmax = w.box[j]
            assert tmin - 1e-9 <= w.torques[j] <= tmax + 1e-9
            assert qmin - 1e-9 <= w.speeds[j] <= qmax + 1e-9
            assert all(op.contains(t, q, tol=1e-7) for t in (tmin, tmax) for q in (qmin, qmax))  # eq. 2
        assert w.twist == pytest.approx(res.alpha[0, l] * state.rvds[l])


def test_shared_slip_fixes_the_ratio_of_slip_speeds():
    r"""Two S-points at (-+1, 0) under the object (n = (0, 1), slide direction +x with
    lengths 1 and 2); joint i moves contact i along +x (J_1 = [[1, 0], [0, 0]],
    J_2 = [[0, 1], [0, 0]]); no load (w = 0, g_f = 0, so n_f = 0 and tau = 0). Translating
    the object along r = (1, 0, 0): slip of contact i (object relative to finger) is
    alpha - qd_i (eq. 13).

    * per_contact: alpha - qd_i = rho_i >= 0 holds for any alpha with qd = 0: unbounded.
    * shared (eq. 34 literally): alpha - qd_1 = rho, alpha - qd_2 = 2 rho, so
      alpha = 2 qd_1 - qd_2 <= 3 Q0 with |qd_i| <= Q0 (zero torque): alpha = 3 Q0.
    """
    contacts = tuple(
        Contact(f"s{i}", "S", [x, 0.0], [0.0, 1.0], jac, mu=0.3, slide_direction=[length, 0.0])
        for i, (x, jac, length) in enumerate(
            [(-1.0, [[1.0, 0.0], [0.0, 0.0]], 1.0), (1.0, [[0.0, 1.0], [0.0, 0.0]], 2.0)]
        )
    )
    state = GraspState(2, [0, 0.5], ("a", "b"), (OP, OP), [0.0, 0.0], contacts, [[0, 0, 0]], [[1, 0, 0]])
    assert tvmmp(state).status == (("unbounded",),)
    shared = tvmmp(state.with_(slip="shared"))
    assert shared.alpha[0, 0] == pytest.approx(3 * Q_MAX, rel=1e-9)
    w = shared.witnesses[0][0]
    assert w.speeds == pytest.approx([Q_MAX, -Q_MAX], rel=1e-9)
    assert w.slip_speeds == pytest.approx([2 * Q_MAX], rel=1e-9)


def test_tied_alphas_give_the_first_pair():
    """Alphas tied up to round-off (LIMITING_TIE_REL) name the first pair in (k, l) order,
    whichever of them the solver's round-off made smaller; the TVMMP is the minimum."""
    from mjtvm.problem2.tvmmp import _limiting, _Pairs

    pairs = _Pairs.empty(2, 2)
    pairs.alpha[:] = [[2.0, 1.0 + 4e-16], [1.0, 1.0 + 1e-6]]
    pairs.status = [["optimal"] * 2 for _ in range(2)]
    assert _limiting(pairs) == ((0, 1), 1.0)
    pairs.alpha[0, 1] = 1.0 + 1e-7  # a genuine difference: not a tie
    assert _limiting(pairs) == ((1, 0), 1.0)


def test_an_answer_whose_deferred_certificate_fails_is_solved_again_with_a_note(monkeypatch):
    """The optimal answers are certified together after every LP (StateLPs.certify_many): one
    that fails there goes through the other ways (a cold HiGHS solve certifies it) with a
    note, and its alpha is the LP's."""
    from mjtvm.lp.certificate import Certificate
    from mjtvm.problem2.lps import StateLPs

    state = random_state(3, fingers=3, joints_per_finger=3, num_refs=2, num_rvds=3)
    want = tvmmp(state)
    real = StateLPs.certify_many

    def first_fails(self, answers):  # type: ignore[no-untyped-def]
        certs = real(self, answers)
        return [Certificate(1.0, c.dual, c.gap, c.bound) if i == 0 else c for i, c in enumerate(certs)]

    monkeypatch.setattr(StateLPs, "certify_many", first_fails)
    got = tvmmp(state)
    assert want.status == got.status and all(s == "optimal" for row in got.status for s in row)
    np.testing.assert_allclose(got.alpha, want.alpha, rtol=1e-9)
    assert len(got.notes) == 1 and got.notes[0][0] == (0, 0)  # the first pair solved: (k=0, l=0)
    assert (
        "not certified (primal violation 1.0e+00" in got.notes[0][1]
        and "certified by highs (cold)" in got.notes[0][1]
    )
    assert all(c is True for row in got.certified for c in row)


def test_a_pair_found_infeasible_after_the_lps_drops_its_k(monkeypatch):
    """Should the other ways find a deferred pair infeasible, its k is infeasible for every l
    (as when HiGHS says so at once), and its later LPs, solved already, are not reported."""
    from mjtvm.lp.lp import LPSolution
    from mjtvm.lp.solvers import Settled
    from mjtvm.problem2.lps import StateLPs
    from mjtvm.problem2.verdict import Verdict

    state = random_state(3, fingers=3, joints_per_finger=3, num_refs=2, num_rvds=3)
    real = StateLPs.conclude

    def k1_l0_infeasible(self, w, r, alpha_max, settled, cert):  # type: ignore[no-untyped-def]
        if np.array_equal(w, state.refs[1]) and np.array_equal(r, state.rvds[0]):
            return Verdict(
                Settled(LPSolution("infeasible", None, None), "highs", "made infeasible"), None, True
            )
        return real(self, w, r, alpha_max, settled, cert)

    want = tvmmp(state)
    monkeypatch.setattr(StateLPs, "conclude", k1_l0_infeasible)
    got = tvmmp(state)
    assert not got.feasible and got.tvmmp is None
    assert got.status[1] == ("infeasible",) * 3 and got.status[0] == want.status[0] == ("optimal",) * 3
    assert np.all(np.isnan(got.alpha[1])) and np.array_equal(got.alpha[0], want.alpha[0])
    assert [pair for pair, _ in got.notes] == [(1, 0)]
