r"""Problem 2 does not depend on the unit system (issue 12, item 2).

A state is rewritten in a unit system whose length, force and time units are the SI ones
divided by ``l``, ``f`` and ``t`` (a quantity of dimension L^a F^b T^c gets multiplied by
``l^a f^b t^c``). Field by field (the state format, docs/result-format.md):

* positions ``p_C``, ``p_O``: L, times ``l``; normals, tangents, slide directions: unit
  vectors, unchanged;
* contact Jacobians ``J`` (``d x M``, contact-point velocity per joint speed, revolute
  joints): L, times ``l``;
* operation ranges: torque axis F L (times ``f l``), speed axis 1/T (times ``1 / t``);
* gravity torques ``g_f``: F L, times ``f l``;
* REFS ``w = [force; moment]``: force rows times ``f``, moment rows times ``f l``;
* RVDS ``r = [v; omega]``: linear rows L/T (times ``l / t``), angular rows 1/T (times ``1 / t``).

Then every row of eq. (26)/(31) is multiplied by one factor and every variable by one
factor (lam, tau: F and F L; qd: 1/T; the twist like the RVDS), and ``rdot = alpha r_l``
(eq. 31) holds with the same ``alpha``: **alpha is dimensionless, its factor is 1**. The
test asserts the same alphas and statuses to 1e-7 relative (the solver's tolerance is 1e-9
on the equilibrated LP; the equilibration is by powers of 2, so a power-of-2 factor gives
the very same scaled LP and a decimal one an LP within a factor 2 per row and column).
An RVDS multiplied by ``s`` alone divides alpha by ``s`` (eq. 31: ``alpha r`` is fixed).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mjtvm import tvmmp
from mjtvm.formats.state_file import load_state
from mjtvm.model.contacts import Contact
from mjtvm.model.state import GraspState
from mjtvm.paper_hand.scenario import load_scenario
from tests.support.perturb import rescale

EXAMPLES = Path(__file__).resolve().parents[2] / "mjtvm" / "data" / "examples"
FACTORS = (1e-6, 1e-3, 1.0, 1e3, 1e6)


@pytest.fixture(scope="module")
def states() -> dict[str, GraspState]:
    out = {"pinch": load_state(EXAMPLES / "pinch.json")}
    # Case 1 is a Problem 1 state: Problem 2 with +-e_y, +-omega_x, +-omega_z (the paper's
    # timing directions; alphas 0.50, 4.27, 19.95).
    dirs = np.eye(6)[[1, 1, 3, 3, 5, 5]] * np.array([1.0, -1.0] * 3)[:, None]
    out["case1"] = replace(load_scenario("case1").state(), rvds=dirs)
    out["case2"] = load_scenario("case2").state()
    return out


def assert_same_alphas(a, b, *, rtol: float = 1e-7) -> None:  # type: ignore[no-untyped-def]
    assert a.status == b.status
    assert a.feasible == b.feasible
    np.testing.assert_allclose(b.alpha, a.alpha, rtol=rtol, atol=0.0)
    assert (a.tvmmp is None) == (b.tvmmp is None)
    if a.tvmmp is not None:
        assert b.tvmmp == pytest.approx(a.tvmmp, rel=rtol)


@pytest.mark.parametrize(
    "solver,name",
    [
        ("highs", "pinch"),
        ("highs", "case1"),
        ("highs", "case2"),
        ("clarabel", "pinch"),
        ("clarabel", "case1"),
        ("clarabel", "case2"),
    ],
)
@pytest.mark.parametrize("unit", ["length", "force", "time"])
def test_alphas_do_not_depend_on_one_unit(states, name, unit, solver):
    """Each unit alone, 1e-6 .. 1e6: the same alphas, scaled. Clarabel on Case 1 (a 4-D TVMS
    in 6-D: the rotation alphas sit on a degenerate face, exactly so since the pyramid edges
    carry exact zeros) is an interior point's answer there: within 3e-8 of HiGHS' vertex in
    SI, within 2.2e-5 in some rescaled systems (the power-of-2 equilibration differs by its
    rounding). It is held to HiGHS' answer in the same units with 5e-5; everywhere else 1e-7."""
    state = states[name]
    ref = tvmmp(state, solver=solver, witnesses=False)
    assert ref.feasible and ref.tvmmp is not None and ref.tvmmp > 0.1  # a real value to compare
    for factor in FACTORS:
        scaled = rescale(state, **{unit: factor})
        got = tvmmp(scaled, solver=solver, witnesses=False)
        if (solver, name) == ("clarabel", "case1"):
            assert_same_alphas(tvmmp(scaled, witnesses=False), got, rtol=5e-5)
            assert_same_alphas(ref, got, rtol=1e-4)
        else:
            assert_same_alphas(ref, got, rtol=1e-7)


@pytest.mark.parametrize("name", ["pinch", "case1", "case2"])
def test_alphas_do_not_depend_on_the_unit_system(states, name):
    """Combined changes (mm/mN/ms, km/kN/ks, ...), HiGHS. Not (1e-6, 1e-6, 1e-6): there an
    operation range's torque axis (F L, 1e-12) and speed axis (1/T, 1e6) differ by 1e18
    inside one row, beyond what double precision resolves (its speed coefficient is
    round-off of that row and is dropped: unbounded)."""
    state = states[name]
    ref = tvmmp(state, witnesses=False)
    systems = [(f, f, f) for f in (1e-3, 1.0, 1e3)] + [
        (1e-3, 1e-3, 1 / 3600),
        (1e6, 1e-6, 1e-3),
        (1e3, 1e-3, 1e3),
    ]
    for length, force, time in systems:
        assert_same_alphas(ref, tvmmp(rescale(state, length=length, force=force, time=time), witnesses=False))


@pytest.mark.parametrize("name", ["pinch", "case2"])
def test_clarabel_alphas_in_other_unit_systems(states, name):
    """Clarabel, settled with its cross-checks (a stalled or infeasible 'Solved' falls back to
    HiGHS, noted): the same alphas to 1e-7 in mm/mN/ms and km/kN/ks."""
    state = states[name]
    ref = tvmmp(state, solver="clarabel", witnesses=False)
    for f in (1e-3, 1e3):
        assert_same_alphas(
            ref, tvmmp(rescale(state, length=f, force=f, time=f), solver="clarabel", witnesses=False)
        )


def test_witnesses_scale_with_their_units(states):
    """The witness of a pair transforms like its fields: forces times f, torques times f l,
    speeds times 1/t, twist like the RVDS (equal up to the solver's tolerance only where
    the optimum is unique, so compared through the constraints they satisfy: forces balance
    the scaled REFS)."""
    state = states["case2"]
    length, force, time = 1e-3, 1e3, 1e2
    scaled = rescale(state, length=length, force=force, time=time)
    a, b = tvmmp(state), tvmmp(scaled)
    for wa, wb in zip(a.witnesses[0], b.witnesses[0]):
        assert wa is not None and wb is not None
        # A component that balances to 0 is compared to the forces' size: the witness is clipped
        # to lam >= 0 (never a negative force), which moves a sum by round-off of the forces.
        big = float(np.abs(wb.forces).max())
        np.testing.assert_allclose(
            wb.forces.sum(axis=0), wa.forces.sum(axis=0) * force, rtol=1e-7, atol=1e-11 * big
        )
        np.testing.assert_allclose(wb.twist, wa.twist * np.r_[[length / time] * 3, [1 / time] * 3], rtol=1e-6)


def test_tiny_jacobian_units_keep_their_coefficients(states):
    """Lengths in units of 1e12 m and forces in units of 1e-11 N: Jacobian entries <= 1.2e-12,
    mostly below the former absolute drop tolerance 1e-12, which zeroed them (alpha 0 where it
    is not); the same alphas as in SI, both solvers."""
    state = states["pinch"]
    tiny = rescale(state, length=1e-12, force=1e11)
    jac = np.concatenate([c.jacobian.ravel() for c in tiny.contacts])
    assert (
        0 < np.max(np.abs(jac)) <= 1.2e-12
        and np.sum((jac != 0) & (np.abs(jac) <= 1e-12)) > 0
        and np.max(np.abs(tiny.refs)) <= 1e12
    )
    for solver in ("highs", "clarabel"):
        assert_same_alphas(tvmmp(state, solver=solver), tvmmp(tiny, solver=solver))


@pytest.mark.parametrize("s", [1e-9, 1e-3, 1e3, 1e9, 1e12])
def test_a_longer_rvds_vertex_divides_alpha(states, s):
    """eq. (31): alpha r_l is what the constraints see, so r_l -> s r_l gives alpha / s. The
    vertices after the first one are changed in the warm HiGHS session (changeCoeff); one
    1e15 times longer was dropped by HiGHS unchecked (alpha 1.8 for 0 before; the loader now
    bounds inputs at 1e12, and the session rescales the column, so the longest allowed
    vertex gives alpha / 1e12 exactly)."""
    state = states["pinch"]
    ref = tvmmp(state)
    factors = np.ones(len(state.rvds))
    factors[1:] = s
    got = tvmmp(replace(state, rvds=state.rvds * factors[:, None]))
    assert got.status == ref.status and got.notes == ()
    np.testing.assert_allclose(got.alpha * factors, ref.alpha, rtol=1e-9)


def test_contact_dataclass_is_what_rescale_replaces():
    """rescale() relies on these field names; a renamed field must fail here, not silently."""
    assert {"position", "jacobian", "normal"} <= set(Contact.__dataclass_fields__)
