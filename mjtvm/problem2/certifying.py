r"""The unscaled LPs of one state's pairs (eq. 31-35) and the certificates of their answers.

[`StateCertificates`][mjtvm.problem2.certifying.StateCertificates] holds what a pair's LP is
made of beside the solver's copy: its alpha column per RVDS vertex (round-off dropped,
[`roundoff`][mjtvm.lp.roundoff]), its bounds per REFS vertex, and the dense unscaled
``[A | A_twist r]`` every answer is certified on ([`certificate`][mjtvm.lp.certificate],
[`Certifier`][mjtvm.lp.certifier.Certifier]). [`StateLPs`][mjtvm.problem2.lps.StateLPs]
solves the LPs on it.
"""

from __future__ import annotations

from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.certificate import Certificate, Certifier
from mjtvm.lp.lp import LPSolution
from mjtvm.lp.roundoff import drop_cancellation, drop_data_roundoff
from mjtvm.model.state import GraspState
from mjtvm.problem2.assembly import Assembly
from mjtvm.problem2.sizes import physical_sizes
from mjtvm.problem2.verdict import Check

__all__ = ["ZERO_ALPHA", "StateCertificates"]

ZERO_ALPHA = 1e-9  # alpha moving no equilibrated row by more than this is an exact 0 (solver tolerance 1e-9)


class StateCertificates:
    """The unscaled pair LPs of one state, variables of the assembly then ``alpha`` (last
    column), and the certificates of their answers.

    ``twist_scale`` ``(D,)``, the factors of the twist columns in the equilibrated LP, is
    the solver's (set by [`StateLPs`][mjtvm.problem2.lps.StateLPs]); `zero_alpha()` reads it.
    """

    twist_scale: NDArray[np.float64]
    #: [`products_jit`][mjtvm.lp.products_jit] for the certificates' products (the batch
    #: paths: [`StateLPs`][mjtvm.problem2.lps.StateLPs] with ``compiled``), else None.
    products_jit: ModuleType | None = None

    def __init__(self, state: GraspState, asm: Assembly, twist: NDArray[np.float64]) -> None:
        """``twist`` ``(m, D)``: ``asm.twist_csc`` dense."""
        self.state, self.asm = state, asm
        n = asm.num_variables
        self.alpha_col = n
        self.c = np.zeros(n + 1)
        self.c[n] = -1.0  # maximise alpha
        self.col_lower = np.append(asm.col_lower, 0.0)  # alpha >= 0 (the gauge of eq. 31)
        self.col_upper = np.append(asm.col_upper, np.inf)
        # The rows alpha enters: the kinematics (A_twist r_l) and the joint limits' horizon
        # rows (-rate s(r_l), mjtvm.model.limits), last.
        self.kin = np.concatenate([asm.kinematic_rows, asm.horizon_rows])
        self._num_kinematic = len(asm.kinematic_rows)
        self.physical_sizes, self.row_cap = physical_sizes(state, asm)
        self.force_like = np.zeros(asm.num_variables + 1, dtype=bool)  # the lam and rho columns
        for name, sl in asm.blocks.items():
            if name.startswith("lam") or name == "rho":
                self.force_like[sl] = True
        self.twist_rows = twist[self.kin]
        self.abs_twist_rows = np.abs(self.twist_rows)
        self._dense: NDArray[np.float64] | None = None  # pair_matrix's
        self._abs_dense: NDArray[np.float64] | None = None
        self._cert: Certifier | None = None  # _certifier's
        # Per RVDS vertex r (its bytes): its alpha column and zero threshold, asked by every
        # LP of that r (its session, its certificate, tvmmp's rounding).
        self._of_r: dict[bytes, tuple[NDArray[np.float64], float]] = {}
        # bounds()' answers per (w, alpha_max): one per REFS vertex, asked again for every l.
        self._bounds_of: dict[tuple[bytes, float], tuple[NDArray[np.float64], ...]] = {}
        self._matrix_of: bytes | None = None  # the r whose column pair_matrix holds

    def column(self, r: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(len(kin),)`` the alpha column ``A_twist r`` on the kinematic rows (then the joint
        limits' horizon rows, ``-rate s(r)``: `horizon_column()`), without
        round-off ([`roundoff`][mjtvm.lp.roundoff]): components of ``r`` at most DROP_REL times
        its largest, and entries at most DROP_REL times the sum of the magnitudes they were
        computed from. A twist written with 1e-16 in a component that is exactly 0 (a
        projection onto the TVMS's span) would otherwise ask for a motion the fingers
        cannot make, and the exact LP's alpha would be 0."""
        return self._r_values(r)[0]

    def zero_alpha(self, r: NDArray[np.float64]) -> float:
        """The alpha below which the twist alpha r_l is within ZERO_ALPHA (the solver's
        tolerance) of 0 in the equilibrated twist variables (the columns of ``A_twist``,
        whose factors follow the units of the state): such an alpha is reported as 0, the
        same in every unit system."""
        return self._r_values(r)[1]

    def _r_values(self, r: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
        """`column()` and `zero_alpha()` of ``r``, computed once per state."""
        key = r.tobytes()
        if key not in self._of_r:
            big = float((np.abs(r) / self.twist_scale).max(initial=0.0))
            rr = drop_data_roundoff(r)  # an RVDS vertex's round-off (roundoff module) is 0 too
            col = drop_cancellation(self.twist_rows @ rr, self.abs_twist_rows @ np.abs(rr))
            if len(self.asm.horizon_rows):  # the horizon rows: -rate_j s(r) (mjtvm.model.limits)
                col[self._num_kinematic :] = self.asm.horizon_column(self.state, rr)
            col.setflags(write=False)
            self._of_r[key] = (col, ZERO_ALPHA / big if big > 0.0 else ZERO_ALPHA)
        return self._of_r[key]

    def pair_matrix(self, r: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(m, n + 1)`` the unscaled ``[A | A_twist r]`` of the pair (nothing dropped but the
        state's round-off), dense, and its magnitudes: the LP every answer is certified on.
        Dense: a state's LP has a few hundred rows and columns, where numpy's dense products
        cost a fraction of scipy's sparse ones (both arrays are the state's, overwritten)."""
        if self._dense is None:
            m, n = self.asm.csc.shape
            self._dense = np.zeros((m, n + 1))
            self._dense[:, :n] = self.asm.csc.toarray()
            self._abs_dense = np.abs(self._dense)
        assert self._abs_dense is not None
        key = r.tobytes()
        if self._matrix_of != key:
            col = np.zeros(self._dense.shape[0])
            col[self.kin] = self.column(r)
            self._dense[:, -1] = col
            self._abs_dense[:, -1] = np.abs(col)
            self._matrix_of = key
        return self._dense, self._abs_dense

    def certify(
        self, w: NDArray[np.float64], r: NDArray[np.float64], alpha_max: float, sol: LPSolution
    ) -> Certificate:
        """The certificate ([`certificate`][mjtvm.lp.certificate]) of an optimal ``sol`` of pair (w, r)."""
        lower, upper, cu = self.bounds(w, alpha_max)
        assert sol.x is not None
        return self._certifier(r).check(
            self.c, lower, upper, cu, sol.x, sol.row_dual, floor=self.zero_alpha(r)
        )

    def certify_many(
        self, answers: list[tuple[NDArray[np.float64], NDArray[np.float64], float, LPSolution]]
    ) -> list[Certificate]:
        """`certify()` of several optimal answers ``(w, r, alpha_max, sol)`` of this
        state at once ([`check_many()`][mjtvm.lp.certifier.Certifier.check_many]): the same
        measures, one matrix product instead of one matrix-vector product per answer."""
        if not answers:
            return []
        cert = self._certifier(answers[0][1])
        # Stacked from lists (one copy each): the answers' bounds, columns and solutions.
        bounds = [self.bounds(w, alpha_max) for w, _, alpha_max, _ in answers]
        lower, upper, cu = (np.array([b[i] for b in bounds]) for i in range(3))
        of_r = [self._r_values(r) for _, r, _, _ in answers]
        last = np.zeros((len(answers), cert.a.shape[0]))
        last[:, self.kin] = np.array([col for col, _ in of_r])
        floor = np.array([fl for _, fl in of_r])
        assert all(sol.x is not None and sol.row_dual is not None for *_, sol in answers)
        x = np.array([sol.x for *_, sol in answers])
        y = np.array([sol.row_dual for *_, sol in answers])
        return cert.check_many(self.c, lower, upper, cu, x, y, last, floor=floor)

    def _certifier(self, r: NDArray[np.float64]) -> Certifier:
        """The state's [`Certifier`][mjtvm.lp.certifier.Certifier], its alpha column that of ``r``."""
        a, abs_a = self.pair_matrix(r)
        if self._cert is None:
            primal = np.where(self.force_like, 0.0, self.physical_sizes)  # forces, slips: their own values
            self._cert = Certifier(
                a,
                self.col_lower,
                col_ref=primal,
                abs_a=abs_a,
                row_groups=self.asm.row_groups,
                dual_ref=self.physical_sizes,
                row_cap=self.row_cap,
                pattern=self.asm.csc,  # pair_matrix's nonzeros
                jit=self.products_jit,
            )
        return self._cert

    def bounds(
        self, w: NDArray[np.float64], alpha_max: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """The row bounds of pair (w, .) and the column upper bounds with ``alpha <= alpha_max``
        (read only: kept for the LPs of the same w)."""
        key = (w.tobytes(), alpha_max)
        if key not in self._bounds_of:
            lower, upper = self.asm.statics_bounds(w)
            cu = self.col_upper.copy()
            cu[-1] = alpha_max
            for a in (lower, upper, cu):
                a.setflags(write=False)
            self._bounds_of[key] = (lower, upper, cu)
        lower, upper, cu = self._bounds_of[key]
        return lower, upper, cu

    def proves_infeasible(
        self, w: NDArray[np.float64], r: NDArray[np.float64], alpha_max: float, sol: LPSolution
    ) -> bool:
        """Whether ``sol``'s Farkas multipliers (HiGHS' dual ray, Clarabel's certificate) prove
        pair (w, r) infeasible on the unscaled LP ([`farkas()`][mjtvm.lp.certificate.farkas])."""
        lower, upper, cu = self.bounds(w, alpha_max)
        return self._certifier(r).farkas(lower, upper, cu, sol.row_dual)

    def check(
        self, w: NDArray[np.float64], r: NDArray[np.float64], alpha_max: float, sol: LPSolution
    ) -> Check:
        """``(certified, certificate)`` of an optimal or infeasible ``sol``; ``None`` for an
        unbounded one (no certificate)."""
        if sol.status == "optimal":
            cert = self.certify(w, r, alpha_max, sol)
            return cert.ok, cert
        if sol.status == "infeasible":
            return self.proves_infeasible(w, r, alpha_max, sol), None
        return None
