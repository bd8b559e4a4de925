"""Problem 2 never reports a wrong alpha as optimal without a note: the reproducers of the
silent wrong numbers found by fuzzing, each against the independent cvxpy transcription
(oracles.reference) on the clean state, and every answer certified."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mjtvm import tvmmp
from mjtvm.formats.state_file import load_state
from mjtvm.grasp.resolve.file import load_grasp
from mjtvm.model.state import GraspState
from mjtvm.paper_hand.scenario import load_scenario
from mjtvm.polytopes.tvms import tvms
from oracles.reference import reference_tvmmp
from tests.support.perturb import add_jacobian_roundoff, rescale, slide_contact

EXAMPLES = Path(__file__).resolve().parents[2] / "mjtvm" / "data" / "examples"
FORMS = [("highs", "eliminated"), ("highs", "literal"), ("clarabel", "eliminated")]


def all_certified(result) -> bool:  # type: ignore[no-untyped-def]
    return all(c in (True, None) for row in result.certified for c in row)


def assert_matches(state: GraspState, ref: np.ndarray, *, rtol: float = 1e-6) -> None:
    """Every form's alphas within ``rtol`` of the reference, certified, none negative."""
    for solver, box in FORMS:
        got = tvmmp(state, solver=solver, box=box)
        assert all_certified(got), (solver, box, got.notes)
        assert np.all(np.nan_to_num(got.alpha) >= 0.0)
        np.testing.assert_allclose(got.alpha, ref, rtol=rtol, atol=1e-12, err_msg=f"{solver} {box}")


def noisy(state: GraspState, seed: int) -> GraspState:
    """``state`` with +-1e-18..1e-14 in every zero entry of its Jacobians."""
    return add_jacobian_roundoff(state, np.random.default_rng(seed))


@pytest.fixture(scope="module")
def allegro() -> GraspState:
    return load_grasp("allegro-ik").state()


def test_allegro_fingertip_sliding_across_its_tangent_is_right():
    """allegro-ik, the first fingertip an S-point sliding along t2: TVMMP -0.0337 'optimal'
    before (its tangent's round-off z component, 1.7e-18, made the alpha column's factor
    1e9 too large and the LP lost that S-point's joint speeds); the reference says 0.02771."""
    state = slide_contact(load_grasp("allegro-ik").state(), 0, np.pi / 2)
    ref, _status = reference_tvmmp(state, solver="HIGHS")
    assert np.nanmin(ref) == pytest.approx(0.027710445719941, rel=1e-9)
    assert_matches(state, ref)
    assert tvmmp(state).tvmmp == pytest.approx(0.027710445719941, rel=1e-9)


@pytest.mark.parametrize("angle", [0.25 * np.pi, 0.75 * np.pi, 1.5 * np.pi])
@pytest.mark.parametrize("finger", [1, 2])
def test_allegro_other_fingertips_slide_contact(allegro, finger, angle):
    state = slide_contact(allegro, finger, angle)
    assert_matches(state, reference_tvmmp(state, solver="HIGHS")[0])


@pytest.mark.parametrize("entry", [(0, 1, 0), (0, 1, 2), (1, 1, 3), (1, 1, 1)])
def test_pinch_with_round_off_in_an_empty_row(entry):
    """pinch.json with one zero Jacobian entry of its empty y rows set to 1e-18: TVMMP 0 before
    (the exact LP of the perturbed data pins that joint), 1.1098 as written."""
    state = load_state(EXAMPLES / "pinch.json")
    ref = reference_tvmmp(state, solver="HIGHS")[0]
    ci, i, j = entry
    jac = state.contacts[ci].jacobian.copy()
    jac[i, j] = 1e-18
    contacts = list(state.contacts)
    contacts[ci] = replace(contacts[ci], jacobian=jac)
    perturbed = state.with_(contacts=tuple(contacts))
    assert tvmmp(perturbed).tvmmp == pytest.approx(1.1097650791099665, rel=1e-9)
    assert_matches(perturbed, ref, rtol=1e-9)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_gripper3_with_noise_in_every_zero_entry(seed):
    """gripper3-box with 1e-18..1e-14 in every zero Jacobian entry (the table's Jacobian is all
    noise then): 0.354 -> 0.176 before, the clean state's alphas within 1e-9 now."""
    state = load_grasp("gripper3-box").state()
    ref = reference_tvmmp(state, solver="HIGHS")[0]
    assert tvmmp(noisy(state, seed)).tvmmp == pytest.approx(0.3538440761075915, rel=1e-9)
    assert_matches(noisy(state, seed), ref, rtol=1e-9)


@pytest.mark.parametrize("scale", [1e-20, 1e-100, 1e-200])
@pytest.mark.parametrize("solver", ["highs", "clarabel"])
def test_an_unholdable_grasp_is_infeasible_whatever_the_jacobians_size(scale, solver):
    """One F-point with a horizontal normal cannot hold a 1 N weight (its cone has no vertical
    force without a normal one). With its Jacobian times 1e-100 it was 'feasible' with zero
    contact forces, the weight left unbalanced; its witness now fails the primal check and
    HiGHS on its own scaling proves the LP infeasible (Farkas multipliers)."""
    pinch = load_state(EXAMPLES / "pinch.json")
    c = pinch.contacts[0]
    state = pinch.with_(contacts=(replace(c, jacobian=c.jacobian * scale),))
    assert reference_tvmmp(state, solver="HIGHS")[1][0][0] == "infeasible"
    got = tvmmp(state, solver=solver)
    assert not got.feasible and got.tvmmp is None
    assert all(s == "infeasible" for s in got.status[0])
    assert all_certified(got)


def test_case1_along_plus_and_minus_beta():
    """Case 1 with the paper's timing RVDS, beta projected onto the TVMS's span with its
    round-off (1e-16 in y, omega_x, omega_z): HiGHS said 21.46474 along one sign of beta
    (5.1e-5 low) while the reference and the TVMS agree on 21.46583 for both."""
    case1 = load_scenario("case1").state()
    v = tvms(case1).vertices
    basis = np.linalg.svd(v - v.mean(axis=0))[2][:4]
    beta = basis.T @ (basis @ np.array([0.1, 0.0, -0.025, 0.0, 1.0, 0.0]))
    assert 0.0 < np.max(np.abs(beta[[1, 3, 5]])) < 1e-15  # the round-off is there
    dirs = [np.eye(6)[1], np.eye(6)[3], np.eye(6)[5], beta]
    state = case1.with_(rvds=np.array([s * d for d in dirs for s in (1.0, -1.0)]))
    clean = state.with_(rvds=np.where(np.abs(state.rvds) < 1e-15, 0.0, state.rvds))
    ref = reference_tvmmp(clean, solver="CLARABEL")[0]
    assert ref[0, 6] == pytest.approx(21.46583, rel=1e-6)
    assert_matches(state, ref, rtol=1e-7)


@pytest.mark.parametrize("name", ["case1", "case2"])
@pytest.mark.parametrize("units", [(1e-6, 1e6, 1.0), (1e6, 1e-6, 1e-3), (1e-6, 1e-6, 1e-6)])
def test_other_unit_systems_are_certified(name, units):
    """Lengths in Mm and forces in uN (an alpha was 6.6e-4 off there), and the reverse: the
    SI alphas within 1e-7, every answer certified."""
    state = load_scenario(name).state()
    if state.rvds is None:
        state = state.with_(rvds=np.eye(6)[[1, 1, 3, 3, 5, 5]] * np.array([1.0, -1.0] * 3)[:, None])
    ref = tvmmp(state).alpha
    length, force, time = units
    assert_matches(rescale(state, length=length, force=force, time=time), ref, rtol=1e-7)


def test_after_another_highs_user_of_the_process():
    """A HiGHS solve by someone else first (cvxpy's, with HiGHS' default threads) starts the
    process's task scheduler; every later mjtvm run with threads = 1 was refused by HiGHS
    and fell back to Clarabel. Now the same alphas as alone, without a note."""
    state = load_state(EXAMPLES / "pinch.json")
    reference_tvmmp(state, solver="HIGHS")
    got = tvmmp(state)
    assert got.notes == () and set(got.settled_by[0]) <= {"highs", None}
    assert got.tvmmp == pytest.approx(1.1097650791099665, rel=1e-12)


@pytest.mark.parametrize(
    "name", ["pinch", "allegro-ik", "allegro-sphere", "gripper3-box", "case1", "case1-s", "case2"]
)
def test_noise_in_every_zero_entry_of_a_shipped_state_changes_no_alpha(name):
    """1e-18..1e-14 in every zero Jacobian entry of every shipped state (what other tools
    write where MuJoCo writes 0): every alpha within 1e-9 of the clean state's, the same
    statuses, every answer certified."""
    if name == "pinch":
        state = load_state(EXAMPLES / "pinch.json")
    else:
        state = load_scenario(name).state()
    if state.rvds is None:
        state = state.with_(rvds=np.vstack([np.eye(6), -np.eye(6)]))
    clean = tvmmp(state, witnesses=False)
    for seed in (0, 1):
        got = tvmmp(noisy(state, seed), witnesses=False)
        assert got.status == clean.status and all_certified(got)
        np.testing.assert_allclose(got.alpha, clean.alpha, rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("name", ["case1", "case2"])
def test_a_states_answers_certified_together_get_their_own_certificates(name):
    """StateLPs.certify_many (tvmmp's path) and StateLPs.certify answer by answer agree on
    every measure of every pair of the paper's states, and certify them all."""
    from benchmarks.cases import case1_rvds
    from mjtvm.problem2.lps import StateLPs

    state = load_scenario(name).state()
    if state.rvds is None:  # Case 1 reports the TVMS: the RVDS of the bench's Case 1 row
        state = state.with_(rvds=case1_rvds(state))
    problem = StateLPs(state, "eliminated", "highs")
    answers = []
    for w in state.refs:
        for r in state.rvds:
            if np.any(r != 0.0):
                answers.append((w, r, np.inf, problem.solve(w, r).solution))
    together = problem.certify_many(answers)
    assert len(together) == len(answers) >= 4
    for (w, r, alpha_max, sol), got in zip(answers, together, strict=True):
        want = problem.certify(w, r, alpha_max, sol)
        assert got.ok and want.ok
        for field in ("primal", "dual", "gap", "bound"):
            assert getattr(got, field) == pytest.approx(getattr(want, field), rel=1e-9, abs=1e-15), field
