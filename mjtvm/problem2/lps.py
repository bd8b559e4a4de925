r"""The LPs of Problem 2 for one grasp state (eq. 31-35), solved and certified.

[`StateLPs`][mjtvm.problem2.lps.StateLPs] assembles a state's constraints once (`assemble()`)
and equilibrates them once; the LP of a pair (k, l) differs from the others only in the
column of ``alpha`` (``A_twist r_l``) and the right-hand side of the balance rows
(``-w_k``), so one HiGHS session is modified and re-solved from its last basis (on the
batch paths most of them by the compiled dual simplex instead, [`warm`][mjtvm.lp.warm]). Every
answer is certified on the unscaled LP ([`certifying`][mjtvm.problem2.certifying], its columns,
bounds and certificates) and solved again other ways when it is not ([`StateLPs.certified()`][mjtvm.problem2.lps.StateLPs.certified]). [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp]
runs the pairs and reports them. The sizes the certificates measure against come from the
state alone ([`physical_sizes()`][mjtvm.problem2.sizes.physical_sizes]).
"""

from __future__ import annotations

from dataclasses import replace
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import SolverError
from mjtvm.lp.lp import LPSolution
from mjtvm.lp.scaling import ScaledMatrix
from mjtvm.lp.solvers import (
    HighsSession,
    LinearProgram,
    Scaling,
    Settled,
    clarabel_checked,
    column_factor,
    cost_scale,
    equilibrate,
    fallback,
)
from mjtvm.model.state import GraspState
from mjtvm.problem2.assembly import BoxForm, assemble
from mjtvm.problem2.certifying import StateCertificates
from mjtvm.problem2.verdict import Check, Verdict, other_ways

if TYPE_CHECKING:
    from mjtvm.lp.warm import WarmBasis, WarmRows

__all__ = ["P2_HIGHS_OPTIONS", "StateLPs"]

#: HiGHS options of Problem 2's sessions: dual edge weights Devex (1) rather than HiGHS'
#: choice (steepest edge here). On Case 2's initial state the 4 runs take 1.59 ms instead of
#: 1.70 ms (medians of 200 states, back to back; the cold first LP 87 iterations instead of 94).
#: The vertex is the same, reached along another path: over 378 solves (Case 1, 1-S, 2 in
#: three unit systems, the pinch, 120 lift states, 60 random states; both box forms) the
#: alphas moved by at most 1.0e-11 relative and no status, note or backend changed. Rejected:
#: HiGHS' scaling off (simplex_scale_strategy 0; the LP is equilibrated already), 1.10 ms, but
#: it certified Case 2 "unbounded" in a rescaled unit system (tests/problem2/test_units.py, length
#: x1e6, force x1e-6, time x1e-3); scaling by largest values (4), 1.29 ms, but the pinch in
#: lengths of 1e12 m and forces of 1e-11 N came out 0.5 % low.
P2_HIGHS_OPTIONS: dict[str, object] = {"simplex_dual_edge_weight_strategy": 1}


class StateLPs(StateCertificates):
    """The LPs of one state: variables of the assembly, then ``alpha`` (last column).

    The equilibration (`equilibrate()`) is computed once per state, on
    ``A`` with the largest REFS magnitudes as right-hand side (rows of twist coefficients
    only are scaled to the twist's); only the factor of the alpha column is chosen per RVDS
    vertex (its largest entry ``A_twist r_l`` brought to 1, `column_factor()`).
    """

    def __init__(self, state: GraspState, box: BoxForm, solver: str, *, compiled: bool = False) -> None:
        self.state, self.solver, self.box = state, solver, box
        # The compiled re-solves of the LPs that differ from HiGHS' last only in the balance
        # rows' bounds (mjtvm.lp.warm; numba, imported here on the batch paths only).
        self._jit = None
        if compiled and solver == "highs":
            from mjtvm.lp.warm import kernels

            self._jit = kernels()
        self._warm: WarmRows | None = None  # the re-solver from HiGHS' last basis (its alpha_max)
        self._warm_r = b""  # the r whose alpha column the re-solver holds
        # The re-solver's optimal bases at each change of r, each a start for a later r whose
        # alpha column, swapped in, leaves it dual feasible (WarmRows.set_column).
        self._bases: list[WarmBasis] = []
        self._compiled: dict[int, LPSolution] = {}  # the re-solver's answers, by id()
        self._alpha_seen = 0.0  # the largest alpha of an optimal answer so far
        self._last_optimal = False  # whether HiGHS' last solve was optimal (its basis serves)
        self._last_w = np.zeros(0)  # the w of HiGHS' last solve
        asm = assemble(state, copies=1, box=box, horizon=True)
        twist = asm.twist_csc.toarray()  # (m, D), D <= 6: dense is cheaper than sparse slicing
        super().__init__(state, asm, twist)
        self.wrench_rows = np.concatenate([np.arange(sl.start, sl.stop) for sl in asm.wrench_rows])
        lower, upper = asm.statics_bounds(np.max(np.abs(state.refs), axis=0))
        rhs = np.fmax(
            np.where(np.isfinite(lower), np.abs(lower), 0.0), np.where(np.isfinite(upper), np.abs(upper), 0.0)
        )
        passes: ModuleType | None = None
        if self._jit is not None:  # numba imports: its equilibration passes too (the same factors)
            from mjtvm.lp import scaling_jit as passes
        s = equilibrate(asm.csc, rhs=rhs, jit=passes)
        # The twist columns are scaled after the rows, each so that its largest entry is 1:
        # the kinematic rows are homogeneous (J qd = G^T rdot), their scale comes from the
        # J qd side, whose speeds the operation ranges pin; equilibrated together, a twist
        # coefficient 1 of G^T dominated rows in small units and alpha r_l ended 1e-11 in
        # the scaled rows, below the solver's tolerance (Case 1 in ms: alpha -19.95).
        has_a = np.bincount(asm.csc.indices, minlength=asm.csc.shape[0]) > 0
        tw_max = np.max(np.abs(twist[has_a] * s.row[has_a, None]), axis=0, initial=0.0)
        self.twist_scale = np.where(
            tw_max > 0.0, np.exp2(np.round(-np.log2(np.where(tw_max > 0.0, tw_max, 1.0)))), 1.0
        )
        # A row of twist coefficients only (a support no joint moves: n^T G^T rdot >= 0) has
        # no J qd side: its factor brings its twist coefficients to those of the other rows
        # (largest 1 in the scaled twist). Left at 1, a table's row in um and ms held the
        # largest entry of every alpha column, 1e9 times the rest.
        only_twist = ~has_a & np.any(twist != 0.0, axis=1)
        if only_twist.any():
            big = np.max(np.abs(twist[only_twist] * self.twist_scale), axis=1)
            row = s.row.copy()
            row[only_twist] = np.exp2(np.clip(np.round(-np.log2(big)), -400.0, 400.0))
            s = replace(s, row=row)
        self.row_scale, self.col_scale = s.row, s.col
        self._scaled_a = ScaledMatrix(asm.csc, s)
        if self._jit is not None:  # numba imports: the certificates' products too
            from mjtvm.lp import products_jit

            self.products_jit = products_jit
        self.session: HighsSession | None = None
        # The (w, r, alpha_max) the session holds: only what changed is sent to HiGHS.
        self._last: tuple[bytes, bytes, float] = (b"", b"", np.nan)  # as bytes: cheaper to compare

    def lp(
        self, w: NDArray[np.float64], r: NDArray[np.float64], *, alpha_max: float = np.inf
    ) -> tuple[LinearProgram, Scaling]:
        """The LP of pair (w, r) and its scaling (the alpha factor from its column)."""
        import scipy.sparse as sp  # the fallbacks' and Clarabel's LP only (module csc)

        kin_col = self.column(r)
        col = np.zeros(self.asm.csc.shape[0])
        col[self.kin] = kin_col
        lower, upper, cu = self.bounds(w, alpha_max)
        lp = LinearProgram(
            self.c,
            sp.hstack([self.asm.A, sp.csc_matrix(col.reshape(-1, 1))], format="csc"),
            lower,
            upper,
            self.col_lower,
            cu,
        )
        factor = column_factor(self.row_scale[self.kin] * kin_col)
        col_s = np.append(self.col_scale, factor)
        return lp, Scaling(self.row_scale, col_s, cost_scale(self.c, col_s))

    def _session(self, w: NDArray[np.float64], r: NDArray[np.float64], alpha_max: float) -> HighsSession:
        """A HiGHS session holding the LP of (w, r), built from the per-state scaled matrix
        (the arrays `lp()` then ``scale_lp`` would give, without their sparse copies)."""
        kin_col = self.column(r)
        factor = column_factor(self.row_scale[self.kin] * kin_col)
        col_s = np.append(self.col_scale, factor)
        s = Scaling(self.row_scale, col_s, cost_scale(self.c, col_s))
        lower, upper, cu = self.bounds(w, alpha_max)
        nz = np.flatnonzero(kin_col)
        a_s = self._scaled_a.with_column(self.kin[nz], kin_col[nz], factor)
        with np.errstate(invalid="ignore"):  # inf * positive stays inf (as in scale_lp)
            slp = LinearProgram(
                s.cost * col_s * self.c, a_s, s.row * lower, s.row * upper, self.col_lower / col_s, cu / col_s
            )
        session = HighsSession.from_scaled(slp, s, self.c, self.col_lower, cu, options=P2_HIGHS_OPTIONS)
        # The torques are free and fixed by their rows (tau - J^T E lam = g_f, eq. 19): basic
        # there from the start, the cold first LP of Case 2 takes 45 iterations instead of 87
        # (0.41 ms instead of 0.61; HiGHS' slack basis has every free column to bring in).
        if self.state.transmission is None:  # then tau and the torque rows pair one to one
            tau, rows = self.asm.blocks["tau[0]"], self.asm.torque_rows[0]
            session.start_basis(np.arange(tau.start, tau.stop), np.arange(rows.start, rows.stop))
        return session

    def solve(self, w: NDArray[np.float64], r: NDArray[np.float64], *, alpha_max: float = np.inf) -> Settled:
        """The settled LP of (w, r): HiGHS warm, Clarabel on failure; or Clarabel checked."""
        if self.solver != "highs":
            lp, s = self.lp(w, r, alpha_max=alpha_max)
            return clarabel_checked(lp, scaling=s)
        if self._jit is not None and self.session is not None:
            sol = self._warm_solve(w, r, alpha_max)
            if sol is not None:
                self._compiled[id(sol)] = sol
                return Settled(sol, "highs")
        return self._highs(w, r, alpha_max)

    def _highs(self, w: NDArray[np.float64], r: NDArray[np.float64], alpha_max: float) -> Settled:
        """`solve()` by the HiGHS session, warm from its last basis (Clarabel on failure)."""
        try:
            if self.session is None:
                self.session = self._session(w, r, alpha_max)
                self._bases = []  # another session's matrix (its round-off dropped afresh)
            else:
                ses = self.session
                # The column changes with l, the bounds with k (set_column re-sends alpha's
                # bounds when it rescales).
                if r.tobytes() != self._last[1]:
                    ses.set_column(self.alpha_col, self.kin, self.column(r), rescale=True)
                if w.tobytes() != self._last[0]:
                    ses.set_row_bounds(self.wrench_rows, -w, -w)
                if alpha_max != self._last[2]:
                    ses.set_col_bounds(self.alpha_col, 0.0, alpha_max)
            self._last = (w.tobytes(), r.tobytes(), alpha_max)
            self._last_w = w
            self._warm = None  # HiGHS' basis moved: a re-solver starts from it
            sol = self.session.solve(duals=True)
            self._last_optimal = sol.status == "optimal"
            if sol.x is not None:
                self._alpha_seen = max(self._alpha_seen, float(sol.x[-1]))
            return Settled(sol, "highs")
        except SolverError as e:
            self.session = None  # its basis may be what went wrong: the next LP starts afresh
            self._warm = None
            lp, s = self.lp(w, r, alpha_max=alpha_max)
            return fallback(lp, e, scaling=s)

    def _warm_solve(
        self, w: NDArray[np.float64], r: NDArray[np.float64], alpha_max: float
    ) -> LPSolution | None:
        """The LP of (w, r) re-solved by the compiled dual simplex ([`WarmRows`][mjtvm.lp.warm.WarmRows]) from the basis
        of the last re-solve (else HiGHS' last), when it differs from the LP the kernel
        holds in the balance rows' bounds and the alpha column (a new r: the column HiGHS
        would hold, [`column_as_held()`][mjtvm.lp.highs.HighsSession.column_as_held]);
        ``None`` when alpha's bounds differ, or the kernel gave up (then HiGHS solves it,
        from its own basis). The answer is certified as HiGHS' are."""
        if alpha_max != self._last[2]:
            return None
        assert self.session is not None and self._jit is not None  # solve() asks only then
        key = r.tobytes()
        if self._warm is None:
            if not self._last_optimal or (key == self._last[1] and w.tobytes() == self._last[0]):
                return None  # no optimal basis to start from, or HiGHS' own last LP
            from mjtvm.lp.warm import WarmRows

            lower, upper, _ = self.bounds(self._last_w, alpha_max)
            try:
                self._warm = WarmRows(self.session, self._jit, lower, upper)
            except ValueError:  # a basis the kernel calls singular: HiGHS solves this LP
                return None
            self._warm_r = self._last[1]
        if key != self._warm_r:
            try:
                column = self.session.column_as_held(self.alpha_col, self.kin, self.column(r))
            except SolverError:  # HiGHS' set_column raises it too, and falls back
                self._warm = None
                return None
            self._bases.append(self._warm.basis())  # optimal for the last LP, of the last r
            # A start with alpha at twice the state's largest alpha so far, where no basis
            # takes the column (alpha of one state's RVDS vertices, one size: r and -r, the
            # axes); any cap above the optimum gives the same answer, one below gives up.
            cap = 2.0 * self._alpha_seen if self._alpha_seen > 0.0 else np.inf
            if not self._warm.set_column(column, self._bases[:-1], cap=cap):
                self._warm = None
                return None
            self._warm_r = key
        lower, upper, _ = self.bounds(w, alpha_max)
        sol = self._warm.solve(lower, upper)
        if sol is None:  # the kernel gave up: HiGHS solves this LP, its basis serves the next
            self._warm = None
        else:
            assert sol.x is not None
            self._alpha_seen = max(self._alpha_seen, float(sol.x[-1]))
        return sol

    def certified(
        self, w: NDArray[np.float64], r: NDArray[np.float64], *, alpha_max: float = np.inf
    ) -> Verdict:
        """The LP of (w, r) settled (`solve()`) and its answer certified on the unscaled LP.

        An optimal answer is certified by `certify()`, an infeasible one by its Farkas
        multipliers (`proves_infeasible()`). An answer that is not is solved again
        other ways, in turn: HiGHS from a cold start on the pair's own equilibration (which
        includes the alpha column), Clarabel, and HiGHS on the LP as assembled (its own
        scaling, no equilibration of ours); the first certified answer is reported, with a
        note. If none is, the first answer is reported with a note naming what failed, and
        ``certified`` False. An unbounded verdict (no certificate here) must be confirmed
        by the cold HiGHS solve.
        """
        settled = self.solve(w, r, alpha_max=alpha_max)
        return self.conclude(w, r, alpha_max, settled, self.check(w, r, alpha_max, settled.solution))

    def conclude(
        self,
        w: NDArray[np.float64],
        r: NDArray[np.float64],
        alpha_max: float,
        settled: Settled,
        cert: Check,
    ) -> Verdict:
        """The verdict of pair (w, r) from its settled LP and the check of its answer
        (`certified()`'s second half: the other ways where the check failed,
        [`other_ways()`][mjtvm.problem2.verdict.other_ways])."""
        if cert is not None and cert[0]:
            return Verdict(settled, cert[1], True)
        if self._compiled.get(id(settled.solution)) is settled.solution:
            # The compiled re-solve's answer stands only certified; else HiGHS solves the LP,
            # as it would have without the re-solves (their tolerance is HiGHS', 1e-9 on the
            # equilibrated rows: a degenerate vertex can sit within it and still miss the
            # certificate's, as on case1-s with six test wrenches, 1.3e-8 against 1e-8).
            del self._compiled[id(settled.solution)]
            settled = self._highs(w, r, alpha_max)
            cert = self.check(w, r, alpha_max, settled.solution)
            if cert is not None and cert[0]:
                return Verdict(settled, cert[1], True)
        lp, _ = self.lp(w, r, alpha_max=alpha_max)
        return other_ways(settled, cert, lp, lambda sol: self.check(w, r, alpha_max, sol))
