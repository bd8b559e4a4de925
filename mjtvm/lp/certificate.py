r"""Certificates: an LP's answer checked against the original, unscaled LP before it is reported.

The solvers see an equilibrated LP whose round-off has been dropped
(`scaling`); their tolerances hold there. A wrong scaling, a dropped
coefficient that was not round-off, or a solver's own slip can make an answer that is
"optimal" for the solver and wrong for the grasp. So every optimal answer of Problem 2 is
checked on the LP as assembled from the state (`assemble()`: the
paper's statics, friction, kinematics and operation ranges, unscaled, nothing dropped but
the state's own round-off, [`roundoff`][mjtvm.lp.roundoff]), for ``min c^T x`` s.t.
``l <= A x <= u``, ``lc <= x <= uc``:

* **primal**: the solution clipped to its bounds (so ``alpha >= 0`` and ``lam >= 0`` hold
  exactly) satisfies every row to `PRIMAL_TOL` relative to the magnitudes of the
  row's terms, ``|A_i| s + |bound|`` with ``s_j = max(|x_j|, ref_j)`` and ``ref_j`` a
  physical size of the variable given by the caller (Problem 2: each joint's largest speed
  and torque), so that a kinematic row of joint speeds that are ~0 in this solution is
  still measured at the speeds the joints can reach; rows that are the components of one
  vector (a force balance, a contact's relative velocity) share the largest of their
  scales, so that the check does not depend on the frame (the x balance of two forces
  that are vertical is measured against the forces, not against their x components); a
  term at its variable's size may be capped by a physical size of its row (``row_cap``:
  Problem 2 caps a contact velocity's terms at the speed the hand's joints move a contact
  at, [`problem2`][mjtvm.problem2.lps]), where ``|A_ij| ref_j`` overstates what the row can
  reach: one Jacobian entry of 1e12 times its joint's top speed would make the row's
  scale 1e12 m/s, and a contact velocity missed by 100 % would pass for round-off. The
  term's value in this solution, ``|A_ij x_j|``, is never capped;
* **dual**: the solver's row multipliers ``y`` (HiGHS' signs: ``y_i >= 0`` where the lower
  bound binds, ``<= 0`` the upper) and the reduced costs ``d = c - A^T y`` computed here on
  the unscaled ``A`` have the signs their bounds allow; those that do not are taken as 0,
  and what that moves the dual bound by (their sizes times the typical sizes of their
  rows and variables) must stay within `DUAL_TOL` of the objective, or within
  ``floor`` absolute;
* **gap**: the dual objective ``D`` (weak duality: ``D <= c^T x*`` for any such ``y``)
  meets the primal one within `GAP_TOL` relative, or within ``floor`` absolute (for
  alpha: the value below which alpha is reported as 0, so that an alpha of 0 is certified
  by a bound below that value).

For Problem 2 (``c = -e_alpha``) the dual bound bounds the true alpha from above: the
reported alpha is feasible and within ``GAP_TOL + DUAL_TOL`` (2e-7) of the maximum. The
bound holds to ``DUAL_TOL``, not rigorously: that would need finite bounds on every
variable, and the forces and slip speeds have none. An infeasible verdict is certified by
Farkas multipliers ([`farkas()`][mjtvm.lp.certificate.farkas]): the same dual bound with zero costs, positive.

The tolerances and the record of a check are [`tolerances`][mjtvm.lp.tolerances]'; the batch
checker that every function here runs is [`Certifier`][mjtvm.lp.certifier.Certifier]
(``mjtvm.lp.certifier``). Their names are importable from here too.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.certifier import BATCH_ENTRIES, Certifier, Matrix
from mjtvm.lp.tolerances import DUAL_TOL, GAP_TOL, PRIMAL_TOL, Certificate, clip, finite_part

__all__ = [
    "BATCH_ENTRIES",
    "DUAL_TOL",
    "GAP_TOL",
    "PRIMAL_TOL",
    "Certificate",
    "Certifier",
    "certify",
    "clip",
    "farkas",
    "primal_violation",
]


def primal_violation(
    a: Matrix,
    x: NDArray[np.float64],
    lower: NDArray[np.float64],
    upper: NDArray[np.float64],
    abs_a: Matrix | None = None,
    size: NDArray[np.float64] | None = None,
    groups: NDArray[np.int64] | None = None,
) -> float:
    """Largest violation of ``lower <= a x <= upper`` relative to ``|a| size + |bound|``,
    ``size`` the typical magnitudes of the variables (default ``|x|``): a row whose
    variables are all ~0 in this solution is still measured at its usual scale. Rows with
    one ``groups`` id (the components of one vector, consecutive) share the largest of
    their scales."""
    one = Certifier(a, np.zeros(a.shape[1]), abs_a=abs_a, row_groups=groups)
    terms = one.abs_a @ (np.abs(x) if size is None else size)
    return float(one.violation(a @ x, terms, finite_part(lower), finite_part(upper)))


def certify(
    c: NDArray[np.float64],
    a: Matrix,
    row_lower: NDArray[np.float64],
    row_upper: NDArray[np.float64],
    col_lower: NDArray[np.float64],
    col_upper: NDArray[np.float64],
    x: NDArray[np.float64],
    y: NDArray[np.float64] | None,
    *,
    floor: float = 0.0,
    col_ref: NDArray[np.float64] | None = None,
    abs_a: Matrix | None = None,
    row_groups: NDArray[np.int64] | None = None,
    row_cap: NDArray[np.float64] | None = None,
) -> Certificate:
    """Check a solution ``x`` and row multipliers ``y`` of ``min c^T x`` s.t.
    ``row_lower <= a x <= row_upper``, ``col_lower <= x <= col_upper`` (unscaled).

    Parameters
    ----------
    c, a, row_lower, row_upper, col_lower, col_upper
        The LP: ``(n,)``, ``(m, n)`` (dense or sparse), ``(m,)``, ``(m,)``, ``(n,)``, ``(n,)``.
    x
        ``(n,)`` the solution; it is clipped to its bounds first.
    y
        ``(m,)`` the row multipliers (HiGHS' signs), or ``None`` (primal check only).
    floor
        An error of the objective that does not matter (for alpha: the value below which
        it is reported as 0): the gap may reach it, and so may what the multipliers of the
        wrong sign move the bound by.
    col_ref
        ``(n,)`` physical sizes of the variables (0 where none is known), or ``None``
        (``|x|`` alone): with ``|x|``, the scale of the rows' violations and of what a
        reduced cost of the wrong sign moves the bound by.
    abs_a
        ``|a|``, when the caller keeps it.
    row_groups
        ``(m,)`` ids of the vectors the rows are components of, the rows of one vector
        consecutive ([`primal_violation()`][mjtvm.lp.certificate.primal_violation]).
    row_cap
        ``(m,)`` the largest a term at its variable's size may add to its row's scale
        ([`Certifier`][mjtvm.lp.certifier.Certifier]).

    Returns
    -------
    Certificate
    """
    one = Certifier(a, col_lower, col_ref=col_ref, abs_a=abs_a, row_groups=row_groups, row_cap=row_cap)
    return one.check(c, row_lower, row_upper, col_upper, x, y, floor=floor)


def farkas(
    a: Matrix,
    row_lower: NDArray[np.float64],
    row_upper: NDArray[np.float64],
    col_lower: NDArray[np.float64],
    col_upper: NDArray[np.float64],
    y: NDArray[np.float64] | None,
    *,
    col_ref: NDArray[np.float64] | None = None,
    abs_a: Matrix | None = None,
) -> bool:
    """Whether row multipliers ``y`` prove ``row_lower <= a x <= row_upper``,
    ``col_lower <= x <= col_upper`` infeasible (Farkas): with zero costs, the dual bound
    of [`certify()`][mjtvm.lp.certificate.certify] is positive, and what the multipliers of the wrong sign move it by
    is within ``DUAL_TOL`` of it. Either sign of ``y`` is tried (solvers differ)."""
    one = Certifier(a, col_lower, col_ref=np.ones(a.shape[1]) if col_ref is None else col_ref, abs_a=abs_a)
    return one.farkas(row_lower, row_upper, col_upper, y)
