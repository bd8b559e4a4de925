"""Force closure, the Ferrari-Canny epsilons and the grasp matrix against closed forms and
independent computations (exact Minkowski sums, LP membership, sampled support functions);
the epsilons' checks with the numpy and the compiled hull insertion alike (`_both_paths()`)."""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import TypeVar

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

from mjtvm import Contact, GraspState, OperationRange, ParamError
from mjtvm.measures import classic_measures, hull, hull_jit
from mjtvm.measures.wrenches import (
    closure_margin,
    default_torque_scale,
    epsilon_l1,
    epsilon_linf,
    grasp_matrix,
    primitive_wrenches,
)

T = TypeVar("T")


def _both_paths(fn: Callable[[], T]) -> list[T]:
    """``fn()`` with the hull's numpy insertion, then with the compiled one (mjtvm.measures.hull_jit)."""
    out = []
    for kernels in (None, hull_jit):
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(hull, "_kernels", lambda compiled, k=kernels: None if compiled is False else k)
            out.append(fn())
    return out


BOX = OperationRange(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 10.0], [0.0, 10.0]]))


def _state(space: int, contacts: list[Contact], joints: int = 1, friction_edges: int = 16) -> GraspState:
    return GraspState(
        space=space,
        object_position=np.zeros(space),
        joint_names=tuple(f"j{i}" for i in range(joints)),
        operation_ranges=(BOX,) * joints,
        gravity_torque=np.zeros(joints),
        contacts=tuple(contacts),
        refs=np.zeros((1, 3 if space == 2 else 6)),
        friction_edges=friction_edges,
    )


def antipodal_disk(mu: float, radius: float = 0.05, kind: str = "F") -> GraspState:
    """Two contacts at (+-R, 0) on a disk, normals into it (planar)."""
    jac = np.zeros((2, 1))
    return _state(
        2,
        [
            Contact("a", kind, [radius, 0.0], [-1.0, 0.0], jac, mu=mu),  # type: ignore[arg-type]
            Contact("b", kind, [-radius, 0.0], [1.0, 0.0], jac, mu=mu),  # type: ignore[arg-type]
        ],
    )


def equator_sphere(mu: float, kind: str = "F", friction_edges: int = 16) -> GraspState:
    """Three contacts at 120 degrees on the unit sphere's equator, normals to the centre."""
    cs = []
    for k in range(3):
        th = 2.0 * np.pi * k / 3.0
        p = np.array([np.cos(th), np.sin(th), 0.0])
        cs.append(Contact(f"c{k}", kind, p, -p, np.zeros((3, 1)), mu=mu))  # type: ignore[arg-type]
    return _state(3, cs, friction_edges=friction_edges)


@pytest.mark.parametrize("mu", [0.1, 0.5, 1.0, 1.5])
def test_antipodal_disk_epsilons_in_closed_form(mu: float) -> None:
    """With the torque scale R the primitive wrenches are (-1, -m, -m), (-1, m, m), (1, m, -m),
    (1, -m, m): a tetrahedron whose four faces are equivalent under (x, y) -> (-x, -y) and
    (y, z) -> (-y, -z), the face through the last three at distance m / sqrt(m^2 + 2) (L1).
    The L-infinity sum conv(0, w1, w2) + conv(0, w3, w4) is nearest the origin along
    (a, p/2, p/2) with a = m p (h = a, a^2 + p^2/2 = 1): sqrt(2) m / sqrt(1 + 2 m^2)."""
    for m in _both_paths(lambda: classic_measures(antipodal_disk(mu), polytope=False)):
        assert m.torque_scale == pytest.approx(0.05)
        assert m.force_closure
        assert m.closure_margin == pytest.approx(1.0)  # the four wrenches sum to 0
        assert m.epsilon_l1 == pytest.approx(mu / np.sqrt(mu**2 + 2.0), rel=1e-9)
        assert m.epsilon_linf == pytest.approx(np.sqrt(2.0) * mu / np.sqrt(1.0 + 2.0 * mu**2), rel=1e-9)
        assert m.epsilon_linf_gap <= 1e-9


def test_antipodal_disk_is_force_closure_iff_mu_is_positive() -> None:
    for mu, closure in [(0.0, False), (1e-3, True), (0.3, True)]:
        m = classic_measures(antipodal_disk(mu), polytope=False)
        assert m.force_closure is closure
        assert (m.epsilon_l1 > 0.0) is closure and (m.epsilon_linf > 0.0) is closure
    frictionless = classic_measures(antipodal_disk(0.5, kind="L"), polytope=False)
    assert not frictionless.force_closure and frictionless.epsilon_l1 == 0.0


def test_equator_grasp_of_a_sphere() -> None:
    """Three frictional contacts at 120 degrees hold a sphere; without friction the torque
    about the axis and the vertical force are not resisted. G G^T = diag(3 I, 3 I - sum r r^T)
    = diag(3, 3, 3, 3/2, 3/2, 3) with rho = 1: sigma_min = sqrt(3/2)."""
    m0 = classic_measures(equator_sphere(0.0, friction_edges=8), polytope=False)
    assert not m0.force_closure and m0.epsilon_l1 == 0.0 and m0.epsilon_linf == 0.0
    m = classic_measures(equator_sphere(0.5, friction_edges=8), polytope=False)
    assert m.force_closure
    assert m.torque_scale == pytest.approx(1.0)
    assert m.grasp_rank == 6
    assert m.grasp_sigma_min == pytest.approx(np.sqrt(1.5), rel=1e-12)
    # The same contacts frictionless (L): three normals in the equator's plane through the
    # centre, no moment: G is 6 x 3 of rank 2, sigma_min 0.
    ml = classic_measures(equator_sphere(0.5, kind="L"), polytope=False)
    assert ml.grasp_rank == 2 and ml.grasp_sigma_min == 0.0


def test_grasp_matrix_of_two_contacts_by_hand() -> None:
    """F contacts at (+-R, 0), rho = R: G = [[1, 0, 1, 0], [0, 1, 0, 1], [0, 1, 0, -1]],
    G G^T = 2 I, every singular value sqrt(2); as L contacts only the normals: rank 1."""
    g = grasp_matrix(antipodal_disk(0.5), 0.05)
    assert g == pytest.approx(np.array([[1, 0, 1, 0], [0, 1, 0, 1], [0, 1, 0, -1]], float))
    m = classic_measures(antipodal_disk(0.5), polytope=False)
    assert m.grasp_sigma_min == pytest.approx(np.sqrt(2.0), rel=1e-12)
    # A torque scale of 2R halves the moment row: singular values sqrt(2), sqrt(2), sqrt(2)/2.
    half = classic_measures(antipodal_disk(0.5), torque_scale=0.1, polytope=False)
    assert half.torque_scale_source == "given"
    assert half.grasp_sigma_min == pytest.approx(np.sqrt(2.0) / 2.0, rel=1e-12)
    assert grasp_matrix(antipodal_disk(0.5, kind="L"), 0.05) == pytest.approx(
        np.array([[-1, 1], [0, 0], [0, 0]])
    )


def _minkowski_epsilon(groups: list[np.ndarray]) -> float:
    """Exact L-infinity epsilon of small cases: the hull of all sums of one point of each
    conv(0, W_i) (the Minkowski sum's vertices are among them)."""
    sets = [np.hstack([np.zeros((w.shape[0], 1)), w]).T for w in groups]
    sums = np.array([sum(choice) for choice in itertools.product(*sets)])
    return float(np.min(-ConvexHull(sums).equations[:, -1]))


def test_linf_epsilon_equals_the_exact_minkowski_sum() -> None:
    """Three frictional contacts, 4-edge pyramids: 5^3 vertex sums, hulled directly."""
    state = equator_sphere(0.4, friction_edges=4)
    groups = primitive_wrenches(state, 1.0)
    exact = _minkowski_epsilon(groups)
    for eps, gap in _both_paths(lambda: epsilon_linf(groups)):
        assert eps == pytest.approx(exact, rel=1e-9)
        assert gap <= 1e-9
    # Ferrari & Canny: W_L1 inside W_Linf inside L W_L1, so eps_L1 <= eps_Linf <= L eps_L1.
    l1 = epsilon_l1(np.hstack(groups))
    assert l1 <= eps <= 3 * l1


def _random_contacts(rng: np.random.Generator, n: int, edges: int) -> list[np.ndarray]:
    """``n`` fingertip pyramids of ``edges`` edges at random points of the unit sphere, normals
    inwards, random friction, as primitive wrenches (force; position x force)."""
    out = []
    for _ in range(n):
        p = rng.normal(size=3)
        p /= np.linalg.norm(p)
        a = np.cross(-p, [1.0, 0.0, 0.0] if abs(p[0]) < 0.9 else [0.0, 1.0, 0.0])
        a /= np.linalg.norm(a)
        b = np.cross(-p, a)
        th = 2.0 * np.pi * np.arange(edges) / edges
        f = -p[:, None] + rng.uniform(0.2, 1.5) * (np.outer(a, np.cos(th)) + np.outer(b, np.sin(th)))
        out.append(np.vstack([f, np.cross(p, f.T).T]))
    return out


@pytest.mark.parametrize("seed", range(12))
def test_linf_epsilon_of_random_grasps_equals_the_exact_minkowski_sum(seed: int) -> None:
    """Three or four random contacts with 4-edge pyramids (up to 5^4 vertex sums, hulled
    directly): the growing hull's epsilon is the exact one, or 0 exactly without closure."""
    rng = np.random.default_rng(seed)
    groups = _random_contacts(rng, 3 + seed % 2, 4)
    exact = max(0.0, _minkowski_epsilon(groups))
    for eps, gap in _both_paths(lambda: epsilon_linf(groups)):
        if closure_margin(np.hstack(groups)) > 1e-9:
            assert eps == pytest.approx(exact, rel=1e-9, abs=1e-12) and gap <= 1e-9
        else:
            assert eps == 0.0 and exact <= 1e-9


def test_l1_epsilon_by_lp_membership_and_sampled_support() -> None:
    """The ball of radius eps_L1 lies in the hull (an LP finds weights for eps u, u random),
    a slightly larger ball does not in some direction, and the support function sampled on
    the sphere never falls below eps_L1 (each sample is an upper bound)."""
    state = equator_sphere(0.5, friction_edges=8)
    w = np.hstack(primitive_wrenches(state, 1.0))
    eps = epsilon_l1(w)
    rng = np.random.default_rng(7)
    dirs = rng.normal(size=(2000, 6))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    support = np.max(dirs @ w, axis=1)
    assert support.min() >= eps * (1 - 1e-12)
    assert support.min() <= eps * 1.5  # the sampled bound is near

    def inside(point: np.ndarray) -> bool:
        n = w.shape[1]
        a_eq = np.vstack([w, np.ones((1, n))])
        res = linprog(
            np.zeros(n), A_eq=a_eq, b_eq=np.append(point, 1.0), bounds=[(0, None)] * n, method="highs"
        )
        return res.status == 0

    assert all(inside(eps * (1 - 1e-7) * u) for u in dirs[:40])
    nearest = dirs[int(np.argmin(support))]
    assert not inside(support.min() * 1.01 * nearest)


def test_closure_margin_of_one_sided_wrenches_is_zero() -> None:
    """All wrenches with a positive first component: the origin is no positive combination."""
    w = np.array([[1.0, 2.0, 1.0], [0.0, 1.0, -1.0], [0.5, 0.0, 0.0]])
    assert closure_margin(w) == 0.0
    assert epsilon_l1(w) == 0.0


def test_epsilons_are_invariant_under_scaling_the_object() -> None:
    """The default torque scale follows the object's size: scaled wrenches do not change."""
    small, big = antipodal_disk(0.4, radius=0.01), antipodal_disk(0.4, radius=3.0)
    assert default_torque_scale(big) == pytest.approx(3.0)
    a, b = classic_measures(small, polytope=False), classic_measures(big, polytope=False)
    assert a.epsilon_l1 == pytest.approx(b.epsilon_l1, rel=1e-12)
    assert a.epsilon_linf == pytest.approx(b.epsilon_linf, rel=1e-9)


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf"), "1", True])
def test_bad_torque_scale_is_one_line(bad: object) -> None:
    with pytest.raises(ParamError, match=r"torque_scale.*expected a (finite )?number > 0"):
        classic_measures(antipodal_disk(0.5), torque_scale=bad, polytope=False)  # type: ignore[arg-type]


@pytest.mark.parametrize("dim", [3, 6])
def test_closure_lp_agrees_with_the_hull_on_random_wrenches(dim: int) -> None:
    """The margin LP with the rank and the hull's facet distances are two tests of "the
    origin strictly inside": on random wrench sets, some shifted off the origin, they agree."""
    rng = np.random.default_rng(11)
    seen = set()
    for trial in range(40):
        w = rng.normal(size=(dim, 3 * dim)) + rng.uniform(0.0, 2.0) * rng.normal(size=(dim, 1))
        inside = closure_margin(w) > 1e-9
        eps = epsilon_l1(w)
        assert inside == (eps > 1e-9), trial
        seen.add(inside)
    assert seen == {True, False}


def test_a_nearly_degenerate_wrench_set_does_not_end_the_process() -> None:
    """A Shadow grasp of ``mjtvm rank``'s mesh dataset (``make_rank_dataset.py -n 240 --mesh 6``,
    grasp 159): Qhull's incremental mode ended the process there with exit code 7 (a facet
    wider than its precision allows) instead of raising; the L-inf epsilon's growing hull is
    rebuilt from all its points instead."""
    from pathlib import Path

    from mjtvm import load_state
    from mjtvm.measures import classic_measures

    state = load_state(Path(__file__).parent / "data" / "qhull-wide-shadow.json")
    numpy_path, compiled = _both_paths(lambda: classic_measures(state, polytope=False))
    for m in (numpy_path, compiled):
        assert m.force_closure and m.epsilon_linf > m.epsilon_l1 > 0.0
        assert m.epsilon_linf_gap < 1e-12 * m.epsilon_linf + 1e-15
    assert compiled.epsilon_linf == pytest.approx(numpy_path.epsilon_linf, rel=1e-12)
    assert compiled.epsilon_l1 == pytest.approx(numpy_path.epsilon_l1, rel=1e-12)


def test_a_state_without_contacts_has_no_closure_and_no_crash() -> None:
    from importlib import resources

    from mjtvm import load_state
    from mjtvm.measures import classic_measures

    pinch = load_state(resources.files("mjtvm.data").joinpath("examples/pinch.json").read_text())
    m = classic_measures(pinch.with_(contacts=()), polytope=False)
    assert (m.force_closure, m.num_wrenches, m.epsilon_l1, m.grasp_rank) == (False, 0, 0.0, 0)
