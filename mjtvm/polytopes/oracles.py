r"""LP oracles on the TVMS $S_{ov}$, the projection of a lifted polytope (eq. 26, 34).

Each holds one HiGHS session over the lifted polytope's rows (built once, re-solved warm
after changing a few costs, bounds or coefficients) and answers in the working coordinates
of `project_lp()`:

* [`SupportOracle`][mjtvm.polytopes.oracles.SupportOracle]: $\max h^T s$ over $S_{ov}$ (a point, a ray, or empty);
* [`RayShooter`][mjtvm.polytopes.oracles.RayShooter]: where the segment from an interior point towards a point leaves
  $S_{ov}$, with a supporting hyperplane there from the duals;
* [`DistanceOracle`][mjtvm.polytopes.oracles.DistanceOracle]: the max-norm distance from a point to $S_{ov}$ and a
  separating hyperplane from the duals.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from mjtvm.errors import SolverError
from mjtvm.lp.solvers import HighsSession, LinearProgram, LPSolution
from mjtvm.polytopes.lifted import LiftedPolytope

__all__ = ["DistanceOracle", "RayShooter", "SupportOracle"]


class SupportOracle:
    r"""Support function of $S_{ov}$ by LPs on one HiGHS session.

    Only the costs of ``z`` change between LPs, and the primal simplex re-solves from the
    previous optimal basis (which stays primal feasible). An unbounded LP is followed by
    one on the recession cone ([`recession()`][mjtvm.polytopes.lifted.LiftedPolytope.recession]) for a ray.
    """

    def __init__(self, poly: LiftedPolytope, metric: NDArray[np.float64]) -> None:
        self.poly, self.metric = poly, metric
        self.session = self._session(poly)
        n = poly.A.shape[1]
        self.cols = np.arange(n, dtype=np.int32)[poly.twist_cols]
        self.ray_session: HighsSession | None = None
        self.num_lps = 0

    @staticmethod
    def _session(p: LiftedPolytope) -> HighsSession:
        lp = LinearProgram(np.zeros(p.A.shape[1]), p.A, p.row_lower, p.row_upper, p.col_lower, p.col_upper)
        session = HighsSession(lp)
        session.set_option("simplex_strategy", 4)  # primal: only the costs change
        # The LP is equilibrated already (solvers.equilibrate; the cost factor follows each
        # direction): HiGHS' own scaling stacked on it lets the primal simplex stop 1.2e-4
        # (relative) short of the optimum on Case 1-S's z-support, its reduced costs judged in
        # units where 1e-9 is not small. Without it the tolerances mean what ours say.
        session.set_option("simplex_scale_strategy", 0)
        return session

    def _solve(self, session: HighsSession, h: NDArray[np.float64]) -> LPSolution:
        cost = -(self.poly.generators.T @ (self.metric * h))  # max h^T (metric * rdot)
        session.set_costs(self.cols, cost)
        self.num_lps += 1
        return session.solve()

    def __call__(self, h: NDArray[np.float64]) -> tuple[str, NDArray[np.float64]]:
        """Maximise ``h^T s``: ``("optimal", s*)``, ``("unbounded", unit ray)`` or ``("infeasible", 0)``."""
        sol = self._solve(self.session, h)
        if sol.status == "optimal" and sol.x is not None:
            return "optimal", self.metric * self.poly.twist(sol.x)
        if sol.status == "infeasible":
            return "infeasible", np.zeros_like(h)
        if self.ray_session is None:
            self.ray_session = self._session(self.poly.recession())
        ray = self._solve(self.ray_session, h)
        s = self.metric * self.poly.twist(ray.x) if ray.x is not None else np.zeros_like(h)
        if ray.status != "optimal" or h @ s <= 1e-7 * np.linalg.norm(h):
            raise SolverError("highs", f"unbounded support LP without a recession ray ({ray.status})")
        return "unbounded", s / np.linalg.norm(s)


class RayShooter:
    r"""Ray shooting in $S_{ov}$ by LPs on a HiGHS session.

    ``max t`` over the lifted polytope with the ``k`` extra rows $R z - t d = c$
    ($R z$ = the working coordinates of the twist, ``c`` inside $S_{ov}$,
    $0 \le t \le 1$): $c + t^* d$ is where the segment from ``c`` to ``c + d``
    leaves $S_{ov}$. Only the ``k`` coefficients of the ``t`` column change between
    LPs. The duals ``y`` of those rows give the hyperplane supporting $S_{ov}$ there:
    the Lagrangian of the equalities shows $\max_{s \in S_{ov}} -y^T s = -y^T (c + t^* d)$
    when $t^* < 1$ (HiGHS' sign convention is settled by $-y^T d > 0$).
    """

    def __init__(self, poly: LiftedPolytope, rows: NDArray[np.float64], center: NDArray[np.float64]) -> None:
        m, n = poly.A.shape
        k, nz = rows.shape
        twist = sp.hstack(
            [sp.csc_matrix((k, n - nz)), sp.csc_matrix(rows), sp.csc_matrix(np.ones((k, 1)))], format="csc"
        )
        a = sp.vstack([sp.hstack([poly.A, sp.csc_matrix((m, 1))]), twist], format="csc")
        cost = np.zeros(n + 1)
        cost[-1] = -1.0  # max t
        lp = LinearProgram(
            cost,
            a,
            np.concatenate([poly.row_lower, center]),
            np.concatenate([poly.row_upper, center]),
            np.append(poly.col_lower, 0.0),
            np.append(poly.col_upper, 1.0),
        )
        self.session = HighsSession(lp)
        # Dual simplex with Devex pricing from the previous basis: on Case 2's rays 2.7
        # iterations and 166 us per LP, against 204 us for the primal simplex (4.9 iterations)
        # and 215 us for the dual with steepest-edge weights, whose set-up every run costs.
        self.session.set_option("simplex_strategy", 1)
        self.session.set_option("simplex_dual_edge_weight_strategy", 1)
        self.rows = np.arange(m, m + k)
        self.num_lps = 0
        self._col = n

    def __call__(self, d: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        """``t*`` and the unit outward normal of a hyperplane supporting $S_{ov}$ at ``c + t* d``."""
        # Only the t column changes; rescaled (a long d like a short one), its scaled cost stays.
        self.session.set_column(self._col, self.rows, -np.asarray(d, dtype=float), rescale=True)
        self.num_lps += 1
        sol = self.session.solve(duals=True)
        if sol.status != "optimal" or sol.x is None or sol.row_dual is None:
            raise SolverError("highs", f"ray-shooting LP: {sol.status}")
        y = sol.row_dual[self.rows]
        h = -y if -y @ d > 0 else y
        norm = float(np.sqrt(h @ h))
        return float(sol.x[-1]), h / norm if norm > 0 else h


class DistanceOracle:
    r"""Distance from a point to $S_{ov}$ in the max norm, and a separating hyperplane.

    ``min delta`` over the lifted polytope with the ``2k`` rows
    $v - \delta \le R z \le v + \delta$ (only their bounds change). With multipliers
    $\lambda^\pm \ge 0$ of the upper and lower rows, the dual reads
    $\delta^* = \max_{\|g\|_1 \le 1} g^T v - h_{S}(g)$ at $g = \lambda^- - \lambda^+$:
    the hyperplane $g^T u \le h_S(g)$ separates ``v`` by at least $\delta^*$
    (Euclidean distance, as $\|g\|_2 \le 1$).
    """

    def __init__(self, poly: LiftedPolytope, rows: NDArray[np.float64]) -> None:
        m, n = poly.A.shape
        k, nz = rows.shape
        pad, r = sp.csc_matrix((k, n - nz)), sp.csc_matrix(rows)
        one = sp.csc_matrix(np.ones((k, 1)))
        band = sp.vstack([sp.hstack([pad, r, -one]), sp.hstack([pad, r, one])], format="csc")
        a = sp.vstack([sp.hstack([poly.A, sp.csc_matrix((m, 1))]), band], format="csc")
        cost = np.zeros(n + 1)
        cost[-1] = 1.0  # min delta
        inf = np.full(k, np.inf)
        lp = LinearProgram(
            cost,
            a,
            np.concatenate([poly.row_lower, -inf, np.zeros(k)]),
            np.concatenate([poly.row_upper, np.zeros(k), inf]),
            np.append(poly.col_lower, 0.0),
            np.append(poly.col_upper, np.inf),
        )
        self.session = HighsSession(lp)
        self.session.set_option("simplex_dual_edge_weight_strategy", 1)  # Devex: see RayShooter
        self.upper, self.lower = np.arange(m, m + k), np.arange(m + k, m + 2 * k)
        self.num_lps = 0

    def __call__(self, v: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        """``delta*`` and the unit normal ``g / |g|`` of the separating hyperplane."""
        inf = np.full(len(v), np.inf)
        self.session.set_row_bounds(self.upper, -inf, v)
        self.session.set_row_bounds(self.lower, v, inf)
        self.num_lps += 1
        sol = self.session.solve(duals=True)
        if sol.status != "optimal" or sol.x is None or sol.row_dual is None:
            raise SolverError("highs", f"distance LP: {sol.status}")
        y = sol.row_dual
        g = np.abs(y[self.lower]) - np.abs(y[self.upper])
        norm = np.linalg.norm(g)
        return float(sol.x[-1]), g / norm if norm > 0 else g
