r"""Cross-check of :func:`mjtvm.problem2.tvmmp` against the independent cvxpy transcription.

:mod:`oracles.reference` writes Problem 2 from the paper's equations in their literal
forms (H-form friction pyramids, the four box variables of eq. 2 with convex
combinations of mirrored vertices); :func:`mjtvm.problem2.tvmmp` uses the sparse assembly with
force generators. Both must give the same statuses and alphas.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from benchmarks.synthetic import random_state
from mjtvm.model.contacts import Contact, tangent_basis
from mjtvm.model.operation_range import default_operation_range
from mjtvm.model.state import GraspState
from mjtvm.problem2.tvmmp import tvmmp
from oracles.reference import pyramid_halfspaces, reference_alpha, reference_tvmmp

RTOL, ATOL = 1e-6, 1e-8
SOLVERS = ("highs", "clarabel")
BOXES = ("eliminated", "literal")

# name -> (seed, random_state keyword arguments, slip)
CASES: dict[str, tuple[int, dict[str, object], str]] = {
    "space-FL-0": (0, {}, "per_contact"),
    "space-FL-1": (1, {}, "per_contact"),
    "space-FSD-0": (0, {"contact_types": ("F", "S", "F", "S", "D")}, "per_contact"),
    "space-FSD-1": (1, {"contact_types": ("F", "S", "F", "S", "D")}, "per_contact"),
    "space-FSD-shared-1": (1, {"contact_types": ("F", "S", "F", "S", "D")}, "shared"),
    "space-LSD-2refs": (3, {"contact_types": ("F", "L", "S", "L", "D"), "num_refs": 2}, "per_contact"),
    "plane-FL-0": (0, {"space": 2}, "per_contact"),
    "plane-FL-3": (3, {"space": 2}, "per_contact"),
    "plane-FSD-shared-0": (0, {"space": 2, "contact_types": ("F", "S", "L", "S", "D")}, "shared"),
    "plane-FSD-1": (1, {"space": 2, "contact_types": ("F", "S", "L", "S", "D")}, "per_contact"),
}


def _state(name: str) -> GraspState:
    seed, kwargs, slip = CASES[name]
    state = random_state(seed, **kwargs)  # type: ignore[arg-type]
    return state.with_(slip=slip) if slip != "per_contact" else state


@functools.cache
def _reference(name: str) -> tuple[np.ndarray, tuple[tuple[str, ...], ...]]:
    return reference_tvmmp(_state(name))


def _assert_agree(
    state: GraspState, ref: tuple[np.ndarray, tuple[tuple[str, ...], ...]], solver: str, box: str
):
    alpha_ref, status_ref = ref
    result = tvmmp(state, solver=solver, box=box, witnesses=False)  # type: ignore[arg-type]
    assert result.status == status_ref
    np.testing.assert_allclose(result.alpha, alpha_ref, rtol=RTOL, atol=ATOL, equal_nan=True)


@pytest.mark.parametrize("box", BOXES)
@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("name", list(CASES))
def test_tvmmp_matches_reference(name: str, solver: str, box: str) -> None:
    alpha_ref, status_ref = _reference(name)
    assert all(s == "optimal" for row in status_ref for s in row)  # feasible by construction
    _assert_agree(_state(name), (alpha_ref, status_ref), solver, box)


def test_reference_solvers_agree() -> None:
    state = _state("space-FSD-0")
    a_clarabel, s_clarabel = _reference("space-FSD-0")
    a_highs, s_highs = reference_tvmmp(state, solver="HIGHS")
    assert s_highs == s_clarabel
    np.testing.assert_allclose(a_highs, a_clarabel, rtol=RTOL, atol=ATOL)


def test_origin_vertex_skipped() -> None:
    state = _state("space-FL-0")
    state = state.with_(rvds=np.vstack([state.rvds, np.zeros(6)]))
    ref = reference_tvmmp(state)
    assert ref[1][0][-1] == "skipped"
    for solver in SOLVERS:
        _assert_agree(state, ref, solver, "eliminated")


def test_infeasible_when_refs_too_large() -> None:
    state = _state("space-FSD-0")
    state = state.with_(refs=1000.0 * state.refs)
    ref = reference_tvmmp(state)
    assert all(s == "infeasible" for row in ref[1] for s in row)
    for solver in SOLVERS:
        for box in BOXES:
            _assert_agree(state, ref, solver, box)


def _sphere_on_l_points() -> GraspState:
    """A unit-weight sphere resting on three frictionless points below its centre."""
    centre = np.array([0.0, 0.0, 0.1])
    contacts = []
    for i, phi in enumerate(2.0 * np.pi * np.arange(3) / 3):
        direction = np.array([0.5 * np.cos(phi), 0.5 * np.sin(phi), -np.sqrt(0.75)])
        contacts.append(Contact(f"l{i}", "L", centre + 0.1 * direction, -direction, np.zeros((3, 1))))
    return GraspState(
        space=3,
        object_position=centre,
        joint_names=("j0",),
        operation_ranges=(default_operation_range(),),
        gravity_torque=np.zeros(1),
        contacts=tuple(contacts),
        refs=np.array([[0.0, 0.0, -1.0, 0.0, 0.0, 0.0]]),
        rvds=np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]]),
    )


def test_unbounded_spin_on_frictionless_points() -> None:
    state = _sphere_on_l_points()
    ref = reference_tvmmp(state)
    assert ref[1] == (("unbounded", "optimal"),)  # spinning about z is free; lifting is not
    assert reference_alpha(state, 0, 1) == ("optimal", pytest.approx(0.0, abs=ATOL))
    for solver in SOLVERS:
        for box in BOXES:
            _assert_agree(state, ref, solver, box)


@pytest.mark.parametrize("space", [2, 3])
def test_pyramid_halfspaces_contain_edges(space: int) -> None:
    n = np.eye(space)[-1]
    c = Contact("c", "F", np.zeros(space), n, np.zeros((space, 1)), mu=0.4)
    v = pyramid_halfspaces(c, 8)
    basis = tangent_basis(n)
    th = 2.0 * np.pi * np.arange(8) / 8
    edges = n + 0.4 * (np.outer(np.cos(th), basis[0]) + np.outer(np.sin(th), basis[-1]))
    if space == 2:
        edges = np.array([n + 0.4 * basis[0], n - 0.4 * basis[0]])
    assert np.all(v @ edges.T <= 1e-12)  # every edge inside or on the boundary
    assert np.all(v @ n < 0)  # the normal strictly inside
    assert np.any(v @ (n + 0.41 * basis[0]) > 0)  # a force just outside the cone is cut off
