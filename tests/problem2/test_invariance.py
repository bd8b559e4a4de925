"""Invariances of Problem 2: rigid motions of the whole scene, permutations, solvers."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from benchmarks.synthetic import random_state
from mjtvm import Contact, GraspState, tvmmp

from ..helpers import rotation

FAST = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def moved(state: GraspState, rot: np.ndarray, shift: np.ndarray, *, rotate_tangents: bool) -> GraspState:
    """The same grasp seen after rotating by ``rot`` and translating by ``shift``.

    Points p -> R p + t; directions, Jacobian rows, forces, moments, v and omega -> R x
    (moments are about p_O, which moves with the scene). In the plane R is 2 x 2 and the
    scalar moment / angular speed is unchanged.
    """
    d = state.dim

    def twist_like(x: np.ndarray) -> np.ndarray:
        if d == 2:
            return np.concatenate([rot @ x[:2], x[2:]])
        return np.concatenate([rot @ x[:3], rot @ x[3:]])

    contacts = []
    for c in state.contacts:
        tangent = c.tangent
        if rotate_tangents and d == 3:
            from mjtvm.model.contacts import tangent_basis

            tangent = rot @ (tangent if tangent is not None else tangent_basis(c.normal)[0])
        contacts.append(
            Contact(
                c.name,
                c.type,
                rot @ c.position + shift,
                rot @ c.normal,
                rot @ c.jacobian,
                mu=c.mu,
                tangent=tangent,
                slide_direction=None if c.slide_direction is None else rot @ c.slide_direction,
            )
        )
    return state.with_(
        object_position=rot @ state.object_position + shift,
        contacts=tuple(contacts),
        refs=np.array([twist_like(w) for w in state.refs]),
        rvds=np.array([twist_like(r) for r in state.rvds]),
    )


def random_rotation(rng: np.random.Generator, d: int) -> np.ndarray:
    if d == 2:
        a = rng.uniform(0, 2 * np.pi)
        return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    return rotation(rng.normal(size=3), rng.uniform(0, 2 * np.pi))


def assert_same(a, b, rel=1e-6):
    assert a.status == b.status
    np.testing.assert_allclose(a.alpha, b.alpha, rtol=rel, atol=1e-9)


@FAST
@given(seed=st.integers(0, 10_000))
def test_rigid_motion_exact_in_the_plane(seed):
    """In the plane the friction cone is exact (two edges), so every alpha is invariant."""
    rng = np.random.default_rng(seed)
    state = random_state(
        rng, space=2, fingers=2, joints_per_finger=3, contact_types=("F", "S", "L", "D"), num_rvds=4
    )
    other = moved(state, random_rotation(rng, 2), rng.normal(size=2), rotate_tangents=False)
    assert_same(tvmmp(state), tvmmp(other))


@FAST
@given(seed=st.integers(0, 10_000))
def test_rigid_motion_exact_for_l_s_d_contacts(seed):
    """Without F-points no pyramid is involved: exact invariance in space."""
    rng = np.random.default_rng(seed)
    state = random_state(rng, contact_types=("L", "S", "L", "S", "D"))
    other = moved(state, random_rotation(rng, 3), rng.normal(size=3), rotate_tangents=False)
    assert_same(tvmmp(state), tvmmp(other))


@FAST
@given(seed=st.integers(0, 10_000))
def test_rigid_motion_exact_with_f_points_when_tangents_move_too(seed):
    """If each pyramid's t1 rotates with the scene, the pyramids do: exact invariance."""
    rng = np.random.default_rng(seed)
    state = random_state(rng, contact_types=("F", "F", "L", "S", "D"))
    other = moved(state, random_rotation(rng, 3), rng.normal(size=3), rotate_tangents=True)
    assert_same(tvmmp(state), tvmmp(other))


@FAST
@given(seed=st.integers(0, 10_000))
def test_rigid_motion_with_default_tangents_within_the_pyramid_approximation(seed):
    r"""The default t1 follows the world axes, so a rotated state gets other pyramids.

    Any n-edge pyramid inscribed in the cone of mu contains the cone of mu cos(pi/n) and
    is contained in the cone of mu, whatever its orientation; and alpha never shrinks as
    the friction set grows (F, L, D contacts). Hence
    alpha(mu cos(pi/n)) <= alpha_rotated(mu) <= alpha(mu / cos(pi/n)), all in the
    original frame.
    """
    rng = np.random.default_rng(seed)
    n = 16
    mu = 0.5
    state = random_state(rng, contact_types=("F", "F", "L", "F", "D"), mu=mu, load=0.3)
    rotated = tvmmp(moved(state, random_rotation(rng, 3), rng.normal(size=3), rotate_tangents=False))
    c = np.cos(np.pi / n)

    def with_mu(value):
        return state.with_(contacts=tuple(Contact(**{**vars(k), "mu": value}) for k in state.contacts))

    low, high = tvmmp(with_mu(mu * c)), tvmmp(with_mu(mu / c))
    assert rotated.status == low.status == high.status
    assert np.all(low.alpha <= rotated.alpha * (1 + 1e-7) + 1e-9)
    assert np.all(rotated.alpha <= high.alpha * (1 + 1e-7) + 1e-9)


@FAST
@given(seed=st.integers(0, 10_000), data=st.data())
def test_permuting_contacts_or_joints_changes_nothing(seed, data):
    rng = np.random.default_rng(seed)
    state = random_state(rng, contact_types=("F", "S", "L", "F", "D"))
    base = tvmmp(state)
    perm_c = data.draw(st.permutations(range(len(state.contacts))))
    perm_j = np.array(data.draw(st.permutations(range(state.num_joints))))
    contacts = [state.contacts[i] for i in perm_c]
    contacts = [Contact(**{**vars(c), "jacobian": c.jacobian[:, perm_j]}) for c in contacts]
    other = state.with_(
        contacts=tuple(contacts),
        joint_names=tuple(state.joint_names[j] for j in perm_j),
        operation_ranges=tuple(state.operation_ranges[j] for j in perm_j),
        gravity_torque=state.gravity_torque[perm_j],
    )
    assert_same(base, tvmmp(other), rel=1e-7)


@pytest.mark.parametrize("seed", range(12))
def test_two_solvers_agree_on_random_feasible_states(seed):
    """HiGHS (simplex) and Clarabel (interior point) agree to 1e-6 relative."""
    types = [("F", "L", "F", "L", "D"), ("F", "S", "F", "S", "D"), ("F", "F", "F")][seed % 3]
    space = 2 if seed % 4 == 3 else 3
    state = random_state(seed, space=space, contact_types=types, num_refs=1 + seed % 2, num_rvds=4)
    a, b = tvmmp(state, solver="highs"), tvmmp(state, solver="clarabel")
    assert a.feasible and a.status == b.status
    np.testing.assert_allclose(a.alpha, b.alpha, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("seed", range(8))
def test_eliminated_box_equals_literal_box(seed):
    """The reduction proved in OperationRange.mirrored_halfplanes gives the paper's alphas."""
    types = [("F", "L", "F", "L", "D"), ("F", "S", "F", "S", "D")][seed % 2]
    state = random_state(seed, contact_types=types, num_refs=2)
    a, b = tvmmp(state, box="eliminated"), tvmmp(state, box="literal")
    assert a.status == b.status
    np.testing.assert_allclose(a.alpha, b.alpha, rtol=1e-9, atol=1e-12)
