"""The speed test's set-ups built once per rollout or grasp give the values of the per-call
formulas they replace, to the bit, on a real state of the coupled Shadow hand (a transmission,
equality constraints): the central witness's QP (`WitnessProblem`), the equality rows and
their null space (`Rig`), the rig shared by a grasp's settles (`SettleCache`)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import clarabel
import mujoco
import numpy as np
import pytest
import scipy.sparse as sp

from mjtvm.errors import ParamError
from mjtvm.grasp.actuation.transmission import dense_efc_jacobian
from mjtvm.jobs.verify import cached_lift
from mjtvm.lift.states import lift_state
from mjtvm.model.state import GraspState
from mjtvm.model.transmission import joint_speed_limits
from mjtvm.physics.check import contact_types, motor_model
from mjtvm.physics.rig import Rig
from mjtvm.physics.simulate import SettleCache, SimSettings, rollout, settle, sim_model
from mjtvm.physics.witness import WitnessProblem, alpha_column, central_witness, witness_drive
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
    with pytest.raises(ParamError, match="problem"):
        witness_drive(other, 0, 2, alpha, 0.8, problem=qp)


def test_the_last_answer_is_kept_and_alphas_column_is_the_lps(coupled: tuple[GraspState, Any]) -> None:
    """Asked again for the same (l, alpha) (squeezed_drive after its drive) the problem returns
    its last answer unsolved; another alpha is solved afresh, as a new problem solves it. Alpha's
    column is A_twist r_l with the horizon rows of Problem 2 (the per-call assembly's)."""
    state, res = coupled
    assert state.rvds is not None
    qp = WitnessProblem(state, 0)
    alpha = float(res.alpha[0, 2]) * 0.8
    first = qp.solve(2, alpha)
    assert qp.solve(2, alpha) is first
    other = qp.solve(2, 0.5 * alpha)
    assert other is not first
    fresh = WitnessProblem(state, 0).solve(2, 0.5 * alpha)
    for key in fresh:
        assert np.array_equal(fresh[key], other[key]), key
    asm = qp.asm
    want = np.asarray(asm.A_twist @ state.rvds[2], dtype=float).reshape(-1)
    want[asm.horizon_rows] = asm.horizon_column(state, np.asarray(state.rvds[2]))
    assert np.array_equal(alpha_column(state, asm, 2), want)


@pytest.fixture(scope="module")
def coupled_sim(coupled: tuple[GraspState, Any]) -> tuple[mujoco.MjModel, Any, Any]:
    """The coupled hand's simulated model, the lift and a drive of direction 2 at 0.8 alpha."""
    state, res = coupled
    lift = cached_lift(COUPLED, 2)
    model = sim_model(
        motor_model(lift.scenario),
        contact_types(state),
        mu=0.6,
        mg=0.4905,
        object_body=lift.scenario.object_body,
    )
    return model, lift, witness_drive(state, 0, 2, float(res.alpha[0, 2]), 0.8)


def _moving(model: mujoco.MjModel, lift: Any, drive: Any) -> tuple[Rig, mujoco.MjData]:
    """A rig and data a few steps into a rollout (the joints moving, the fingers in contact)."""
    rig = Rig(model, drive, lift.scenario.object_body)
    d, _ = settle(model, lift.qpos[0], rig, drive, SimSettings())
    d.qvel[rig.dofs] = drive.speeds
    for _ in range(5):
        mujoco.mj_step(model, d)
    return rig, d


@pytest.mark.parametrize("jacobian", ["dense", "sparse"])
def test_equality_rows_are_the_dense_jacobians(coupled_sim: tuple[Any, ...], jacobian: str) -> None:
    """`Rig.equality_rows` is the equality rows of the full ``efc_J`` (``dense_efc_jacobian``,
    the old formula) over the drive's joints, with efc_J dense or sparse."""
    model, lift, drive = coupled_sim
    model = copy.deepcopy(model)
    model.opt.jacobian = int(getattr(mujoco.mjtJacobian, f"mjJAC_{jacobian.upper()}"))
    rig, d = _moving(model, lift, drive)
    assert bool(mujoco.mj_isSparse(model)) == (jacobian == "sparse")
    eq = int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    rows = [r for r in range(int(d.nefc)) if int(d.efc_type[r]) == eq]
    old = dense_efc_jacobian(model, d)[rows][:, rig.dofs]
    assert len(rows) > 0 and int(d.nefc) > len(rows)  # equality rows among contacts
    assert np.array_equal(rig.equality_rows(d), old)


def test_null_space_is_the_svd_and_kept_while_unchanged(coupled_sim: tuple[Any, ...]) -> None:
    """`Rig.null_space` is the SVD's row and null space of ``J_eq`` (rank at 1e-10 of the
    largest singular value); the kept one serves an equal ``J_eq``, another is solved anew."""
    model, lift, drive = coupled_sim
    rig, d = _moving(model, lift, drive)
    jeq = rig.equality_rows(d)
    _u, sv, vt = np.linalg.svd(jeq)
    rank = int(np.sum(sv > 1e-10 * sv.max()))
    vr, null = rig.null_space(jeq)
    assert np.array_equal(vr, vt[:rank]) and np.array_equal(null, vt[rank:].T)
    assert rank == jeq.shape[0] and null.shape == (len(rig.dofs), len(rig.dofs) - rank)
    again = rig.null_space(jeq.copy())
    assert again[0] is vr
    other = jeq.copy()
    other[0, np.flatnonzero(other[0])[0]] *= 2.0
    vt2 = np.linalg.svd(other)[2]
    assert np.array_equal(rig.null_space(other)[1], vt2[rank:].T)
    assert np.max(np.abs(jeq @ null)) < 1e-12


def test_settle_cache_shares_the_rig_and_changes_no_rollout(
    coupled: tuple[GraspState, Any], coupled_sim: tuple[Any, ...]
) -> None:
    """Drives of two directions (other torques: two settles) share one rig through the cache;
    their rollouts are those without the cache, field by field."""
    state, res = coupled
    model, lift, _ = coupled_sim
    drives = [witness_drive(state, 0, l, float(res.alpha[0, l]), 0.8) for l in (0, 2)]
    assert not np.array_equal(drives[0].torques, drives[1].torques)
    cache, body = SettleCache(), lift.scenario.object_body
    shared = [rollout(model, lift.qpos[0], dr, object_body=body, settled=cache) for dr in drives]
    alone = [rollout(model, lift.qpos[0], dr, object_body=body) for dr in drives]
    assert len({id(v[0]) for v in cache._done.values()}) == 1 and len(cache._done) == 2
    for a, b in zip(shared, alone, strict=True):
        for name in (
            "passed",
            "reason",
            "speed_error",
            "angle_error",
            "slip_ratio",
            "gap",
            "saturated",
            "clamp_fraction",
            "settle_drift",
            "limit_margin",
        ):
            assert getattr(a, name) == getattr(b, name), name
        for g in a.friction:
            assert np.array_equal(a.friction[g][0], b.friction[g][0])
