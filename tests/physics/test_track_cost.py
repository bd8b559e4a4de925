"""The speed test's set-ups built once per rollout or grasp give the values of the per-call
formulas they replace, to the bit, on a real state of the coupled Shadow hand (a transmission,
equality constraints): the central witness's QP (`WitnessProblem`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import clarabel
import numpy as np
import pytest
import scipy.sparse as sp

from mjtvm.jobs.verify import cached_lift
from mjtvm.lift.states import lift_state
from mjtvm.model.state import GraspState
from mjtvm.model.transmission import joint_speed_limits
from mjtvm.physics.witness import WitnessProblem, central_witness, witness_drive
from mjtvm.problem2.assembly import assemble
from mjtvm.problem2.tvmmp import tvmmp

COUPLED = Path(__file__).resolve().parents[2] / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml"


@pytest.fixture(scope="module")
def coupled() -> tuple[GraspState, Any]:
    state = lift_state(cached_lift(COUPLED, 2), 0, variant="L", mu=0.6, mg=0.4905)
    return state, tvmmp(state)


def _old_qp(state: GraspState, k: int, l: int, alpha: float) -> tuple[Any, ...]:
    """The QP data as `central_witness` assembled them per call before `WitnessProblem`."""
    asm = assemble(state, horizon=True)
    assert state.rvds is not None
    w, r = state.refs[k], state.rvds[l]
    n = asm.num_variables
    col = np.asarray(asm.A_twist @ r, dtype=float).reshape(-1)
    col[asm.horizon_rows] = asm.horizon_column(state, r)
    a = sp.hstack([asm.A, sp.csc_matrix(col.reshape(-1, 1))], format="csr")
    lo, hi = asm.statics_bounds(w)
    cl, cu = np.append(asm.col_lower, alpha), np.append(asm.col_upper, alpha)
    eq = np.isfinite(lo) & (lo == hi)
    up, dn = np.isfinite(hi) & ~eq, np.isfinite(lo) & ~eq
    ceq = cl == cu
    cup, cdn = np.isfinite(cu) & ~ceq, np.isfinite(cl) & ~ceq
    eye = sp.identity(n + 1, format="csr")
    big = sp.vstack([a[eq], eye[ceq], a[up], -a[dn], eye[cup], -eye[cdn]], format="csc")
    b = np.concatenate([hi[eq], cu[ceq], hi[up], -lo[dn], cu[cup], -cl[cdn]])
    weight = np.zeros(n + 1)
    w0 = np.array([rng.max_speed for rng in state.operation_ranges])
    assert state.transmission is not None
    w0 = joint_speed_limits(state.transmission.moment, w0)
    weight[asm.blocks["qd"]] = 1.0 / w0**2
    weight[asm.blocks["lam[0]"]] = 1.0 / max(float(np.linalg.norm(w)), 1e-3) ** 2
    sizes = (int(eq.sum() + ceq.sum()), int(up.sum() + dn.sum() + cup.sum() + cdn.sum()))
    return sp.diags(2 * weight).tocsc(), big, b, sizes


def test_witness_problem_is_the_per_call_qp(coupled: tuple[GraspState, Any]) -> None:
    """Same CSC arrays, right-hand side and cones as the per-call assembly for every direction
    and two alphas; Clarabel's solution is then the same to the bit."""
    state, res = coupled
    qp = WitnessProblem(state, 0)
    assert state.rvds is not None
    for l in range(len(state.rvds)):
        for frac in (0.8, 1.0):
            alpha = float(res.alpha[0, l]) * frac * (1 - 1e-7)
            p_old, big, b, sizes = _old_qp(state, 0, l, alpha)
            new = qp.matrix(l)
            assert big.has_sorted_indices
            for name in ("indptr", "indices", "data"):
                assert np.array_equal(getattr(new, name), getattr(big, name)), (l, name)
            assert new.shape == big.shape
            assert np.array_equal(qp.vector(alpha), b)
            assert qp.cone_sizes == sizes
            for name in ("indptr", "indices", "data"):
                assert np.array_equal(getattr(qp.objective, name), getattr(p_old, name))
            opts = clarabel.DefaultSettings()
            opts.verbose = False
            cones = [clarabel.ZeroConeT(sizes[0]), clarabel.NonnegativeConeT(sizes[1])]
            x_old = np.array(
                clarabel.DefaultSolver(p_old, np.zeros(big.shape[1]), big, b, cones, opts).solve().x
            )
            sol = qp.solve(l, alpha)
            assert np.array_equal(sol["speeds"], x_old[qp.asm.blocks["qd"]])
            assert np.array_equal(sol["torques"], x_old[qp.asm.blocks["tau[0]"]])
            fresh = central_witness(state, 0, l, alpha)
            for key in fresh:
                assert np.array_equal(fresh[key], sol[key]), key


def test_witness_drive_with_a_shared_problem(coupled: tuple[GraspState, Any]) -> None:
    """A drive from a shared problem equals the one that builds its own; another state's refused."""
    state, res = coupled
    qp = WitnessProblem(state, 0)
    alpha = float(res.alpha[0, 2])
    a, b = witness_drive(state, 0, 2, alpha, 0.8), witness_drive(state, 0, 2, alpha, 0.8, problem=qp)
    for name in ("speeds", "torques", "twist"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert a.slips.keys() == b.slips.keys()
    other = lift_state(cached_lift(COUPLED, 2), 1, variant="L", mu=0.6, mg=0.4905)
    with pytest.raises(Exception, match="problem"):
        witness_drive(other, 0, 2, alpha, 0.8, problem=qp)
