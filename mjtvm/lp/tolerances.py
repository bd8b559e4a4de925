r"""The measures of a certificate: its tolerances and the record of one check.

[`certify()`][mjtvm.lp.certificate.certify] and the batch checker
[`Certifier`][mjtvm.lp.certifier.Certifier] measure an answer's primal violation, what the
multipliers of the wrong sign move the dual bound by, and the duality gap, each relative
(``mjtvm.lp.certificate``'s module docstring); a [`Certificate`][mjtvm.lp.tolerances.Certificate]
holds the three, and is ``ok`` when each is within its tolerance here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["DUAL_TOL", "GAP_TOL", "PRIMAL_TOL", "Certificate", "clip", "finite_part"]

#: Largest violation of a row, relative to the magnitudes of its terms (the solvers hold
#: 1e-9 on the equilibrated rows; a row whose terms cancel keeps that scale here).
PRIMAL_TOL = 1e-8
#: Largest move of the dual bound by the multipliers and reduced costs of the wrong sign,
#: relative to the objective. HiGHS holds its dual tolerance (1e-9) on the equilibrated LP;
#: summed over a few hundred columns at their physical sizes that reaches a few 1e-8 on
#: Case 1's zero alphas, which are right. With GAP_TOL, a certified alpha is within 2e-7 of
#: the LP's maximum.
DUAL_TOL = 1e-7
#: Largest duality gap, relative to the objective (or ``floor``): with DUAL_TOL, alphas
#: reported as certified are within 2e-7 of the LP's maximum, five times inside the 1e-6 of
#: the differential tests.
GAP_TOL = 1e-7


@dataclass(frozen=True)
class Certificate:
    """The check of one answer (every measure relative, see ``mjtvm.lp.certificate``).

    Attributes
    ----------
    primal
        Largest relative violation of a row by the clipped solution.
    dual
        What the multipliers and reduced costs of the wrong sign move the bound by, relative
        to the objective (``inf`` without multipliers).
    gap
        ``|c^T x - D| / max(|c^T x|, |D|, floor)`` (``inf`` without multipliers).
    bound
        The dual objective ``D``: for a minimisation, a lower bound of the optimum.
    """

    primal: float
    dual: float
    gap: float
    bound: float

    @property
    def ok(self) -> bool:
        """Whether every measure is within its tolerance."""
        return self.primal <= PRIMAL_TOL and self.dual <= DUAL_TOL and self.gap <= GAP_TOL

    def describe(self) -> str:
        """One line: the measures against their tolerances."""
        return (
            f"primal violation {self.primal:.1e} (tol {PRIMAL_TOL:.0e}), dual {self.dual:.1e} "
            f"(tol {DUAL_TOL:.0e}), gap {self.gap:.1e} (tol {GAP_TOL:.0e})"
        )


def clip(
    x: NDArray[np.float64], lower: NDArray[np.float64], upper: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``x`` clipped to its bounds (infinite bounds leave it as it is)."""
    return np.minimum(np.maximum(x, lower), upper)


def finite_part(bound: NDArray[np.float64]) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """Where ``bound`` is finite, and ``bound`` with its infinite entries 0.

    Parameters
    ----------
    bound
        Row or column bounds, some of them infinite.

    Returns
    -------
    tuple[NDArray[np.bool_], NDArray[np.float64]]
        The mask of the finite entries, and ``bound`` with every other entry 0.
    """
    ok = np.isfinite(bound)
    return ok, np.where(ok, bound, 0.0)
