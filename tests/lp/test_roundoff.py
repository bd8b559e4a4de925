"""The round-off rules (mjtvm.lp.roundoff) and their effect on the assembled LP."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from mjtvm.formats.state_file import load_state
from mjtvm.lp.roundoff import DROP_REL, LONE_ENTRY, drop_cancellation, drop_data_roundoff, jacobian_scale
from mjtvm.problem2.assembly import assemble, grasp_map_transpose
from tests.support.perturb import add_jacobian_roundoff

EXAMPLES = Path(__file__).resolve().parents[2] / "mjtvm" / "data" / "examples"


def test_data_rule_is_relative_to_the_largest_entry_or_a_given_reference():
    j = np.array([[0.1, 1e-18, 0.0], [-0.05, 0.02, 9e-14]])  # 9e-13 and 1e-17 of 0.1
    out = drop_data_roundoff(j)
    np.testing.assert_array_equal(out, [[0.1, 0.0, 0.0], [-0.05, 0.02, 0.0]])
    assert j[0, 1] == 1e-18  # the input is left as it is
    # a support's Jacobian of noise only, relative to the state's largest entry (0.1)
    np.testing.assert_array_equal(drop_data_roundoff(np.array([[3e-15, -1e-17]]), 0.1), [[0.0, 0.0]])
    # the same entries are data when nothing larger is around (a state in tiny units)
    np.testing.assert_array_equal(drop_data_roundoff(np.array([[3e-15, -1e-17]])), [[3e-15, -1e-17]])
    # at exactly DROP_REL of the largest an entry is round-off, just above it is data
    np.testing.assert_array_equal(
        drop_data_roundoff(np.array([1.0, DROP_REL, 2 * DROP_REL])), [1.0, 0.0, 2e-12]
    )


def test_cancellation_rule_is_relative_to_the_terms():
    a, b = np.array([0.3, 0.1]), np.array([0.1, -0.3])
    v = np.array([a @ b])  # 0.03 - 0.03: 0 exactly or a few 1e-18
    np.testing.assert_array_equal(drop_cancellation(v, np.array([np.abs(a) @ np.abs(b)])), [0.0])
    # a genuine small product of small terms is kept, whatever the units
    v = np.array([1e-20 * 3e-20])
    np.testing.assert_array_equal(drop_cancellation(v.copy(), v.copy()), v)


def test_grasp_map_of_a_position_with_round_off():
    """p_C - p_O = (-0.05, 1e-17, 0): the 1e-17 is round-off of the vector (|r| = 0.05), and
    G^T has exact zeros where it has, as for (-0.05, 0, 0)."""
    np.testing.assert_array_equal(
        grasp_map_transpose(np.array([-0.05, 1e-17, 0.12]), np.array([0.0, 0.0, 0.12])),
        grasp_map_transpose(np.array([-0.05, 0.0, 0.12]), np.array([0.0, 0.0, 0.12])),
    )


def test_noise_in_the_zero_entries_of_a_state_gives_the_same_lp():
    """Every zero of pinch.json's Jacobians set to +-1e-18..1e-14 (other tools' round-off):
    the assembled matrix is the same, entry for entry."""
    clean = load_state(EXAMPLES / "pinch.json")
    noisy = add_jacobian_roundoff(clean, np.random.default_rng(1))
    assert any(np.any(c.jacobian != d.jacobian) for c, d in zip(clean.contacts, noisy.contacts))
    a, b = assemble(clean), assemble(noisy)
    assert (a.A != b.A).nnz == 0 and (a.A_twist != b.A_twist).nnz == 0


def test_the_jacobians_scale_is_their_largest_entry_unless_it_stands_alone():
    j1, j2 = np.array([[0.1, -0.05], [0.0, 0.02]]), np.array([[0.08, 1e-17]])
    assert jacobian_scale([j1, j2]) == 0.1  # the largest, 1.25 times the second
    assert jacobian_scale([j1, j2 * 10.0]) == 0.8  # 8 times the second: still the largest
    lone = j2.copy()
    lone[0, 1] = 1e12  # one entry alone far above the hand's lever arms
    assert jacobian_scale([j1, lone]) == LONE_ENTRY * 0.1
    assert jacobian_scale([np.array([[0.3]])]) == 0.3 and jacobian_scale([]) == 0.0


def test_one_entry_of_1e12_keeps_the_other_entries_of_the_lp():
    """pinch.json with one entry at 1e12: relative to it every lever arm (<= 0.1) would be
    round-off (0.1 < 1e-12 x 1e12); the assembled kinematic rows keep every other entry."""
    state = load_state(EXAMPLES / "pinch.json")
    c = state.contacts[0]
    jac = c.jacobian.copy()
    i, j = np.argwhere(jac != 0.0)[0]
    jac[i, j] = 1e12
    big = state.with_(contacts=(replace(c, jacobian=jac), *state.contacts[1:]))
    rows = assemble(state).kinematic_rows
    a, b = assemble(state).A.toarray()[rows], assemble(big).A.toarray()[rows]
    changed = a != b
    assert changed.sum() == 1 and b[changed][0] == 1e12


def test_two_entries_far_above_the_rest_are_both_outliers():
    """Eight non-zero entries: up to a quarter (two) may stand above a gap of LONE_ENTRY."""
    j = np.array([[0.1, -0.05, 0.02, 0.03], [0.04, 0.06, 0.07, 0.08]])
    two = j.copy()
    two[0, 0], two[1, 3] = 1e12, -3e10  # two outliers, in either sign
    assert jacobian_scale([two]) == LONE_ENTRY * 0.07  # the largest of the bulk
    three = two.copy()
    three[1, 2] = 1e11  # three of eight: more than a quarter, no longer outliers
    assert jacobian_scale([three]) == 1e12
    noise = j.copy()
    noise[0, 2] = 1e-17  # round-off at the bottom is no gap among the largest
    assert jacobian_scale([noise]) == 0.1
