r"""An independent cvxpy transcription of Problem 2 (eq. 31-35), for cross-checks only.

Everything here is written from the paper's equations, in their literal forms, and
shares nothing with [`mjtvm.problem2.assembly`][mjtvm.problem2.assembly] (only the schema's orientation rule
[`tangent_basis()`][mjtvm.model.contacts.tangent_basis] and [`slide_unit()`][mjtvm.model.contacts.slide_unit] are reused):

* contact forces are free d-vectors per F-point with the friction pyramid in H-form
  $V f \le 0$ (eq. 24; with $\mu = 0$ the normal ray) of the coefficient
  $(1 - \delta)\mu$ at the state's ``friction_margin`` $\delta$, $f = n_f n$ at L-points (eq. 22),
  $f = n_f (n - \mu \hat s)$ at S-points (eq. 16-17), none at D-points;
* kinematics eq. (7)-(13) with $G^T \dot r = v + \omega \times (p_C - p_O)$;
* torques eq. (19), balance eq. (20); with a transmission ([`mjtvm.model.transmission`][mjtvm.model.transmission])
  the joint torques are $P^T u + J_{eq}^T \lambda - b \dot q$, the constraints
  $J_{eq} \dot q = 0$ hold and the box bounds each actuator's $(u, P \dot q)$;
* the box of eq. (2) with its four variables per joint and each corner written as a
  convex combination of the vertices of $P$ mirrored into its quadrant;
* joint position limits (``docs/joint-limits.md``): $\dot q_j \le 0$ within the
  tolerance of the upper limit, $\dot q_j \ge 0$ of the lower, and over a travel
  horizon $H \dot q_j \le (hi_j - q_j)\, s\, \alpha$,
  $-H \dot q_j \le (q_j - lo_j)\, s\, \alpha$ with $s$ the largest speed of
  $p_O$ and of the contact points under $\hat r_l$.

The problem is rebuilt for every (k, l): this is the slow baseline of the benchmarks.
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError, SolverError, StateError

try:  # an optional dependency: the cross-checks and the benchmark's baseline need it, a solve does not
    import cvxpy as cp
except ImportError as e:
    raise ParamError("reference", 'cvxpy is not installed: pip install -e ".[reference]" in a clone') from e
from mjtvm.model.contacts import Contact, slide_unit, tangent_basis
from mjtvm.model.state import GraspState

__all__ = ["pyramid_halfspaces", "reference_alpha", "reference_tvmmp"]

_STATUS = {cp.OPTIMAL: "optimal", cp.INFEASIBLE: "infeasible", cp.UNBOUNDED: "unbounded"}
#: Tighter than Clarabel's defaults (1e-8), so that alphas agree to ~1e-9 with a simplex solver.
_CLARABEL_TOL = {"tol_gap_abs": 1e-9, "tol_gap_rel": 1e-9, "tol_feas": 1e-9}
#: Tighter than HiGHS' defaults (1e-7): at Case 2's weight limit (2.9452894958 x its REFS)
#: the defaults balanced up to 2.9452897995 (1.03e-7 beyond), with 1e-10 the limit is exact.
_HIGHS_TOL = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}
_CORNERS = ((1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0))  # (s1, s2) of eq. (2)


def pyramid_halfspaces(contact: Contact, friction_edges: int, mu: float | None = None) -> NDArray[np.float64]:
    r"""``V`` of eq. (24): the inscribed friction pyramid is $\{f : V f \le 0\}$.

    Edges $e_k = n + \mu (\cos\theta_k t_1 + \sin\theta_k t_2)$,
    $\theta_k = 2\pi k / n_{fric}$ (in the plane $n \pm \mu t$); each row is the
    normal of the facet through two consecutive edges ($e_k \times e_{k+1}$; in the plane
    the perpendicular of each edge), signed so that $n$ (interior) gives a negative value.

    Parameters
    ----------
    contact
        An F contact with ``mu > 0``.
    friction_edges
        $n_{fric}$ (space only).
    mu
        The coefficient of the pyramid (default the contact's ``mu``).

    Returns
    -------
    ndarray
        ``(n_fric, 3)`` in space, ``(2, 2)`` in the plane.
    """
    n = contact.normal
    mu = float(contact.mu if mu is None else mu)  # type: ignore[arg-type]
    basis = tangent_basis(n, contact.tangent)
    if contact.dim == 2:
        edges = [n + mu * basis[0], n - mu * basis[0]]
        rows = [np.array([-e[1], e[0]]) for e in edges]
    else:
        th = 2.0 * np.pi * np.arange(friction_edges) / friction_edges
        edges = [n + mu * (np.cos(t) * basis[0] + np.sin(t) * basis[1]) for t in th]
        rows = [np.cross(edges[k], edges[(k + 1) % len(edges)]) for k in range(len(edges))]
    return np.array([-v if v @ n > 0 else v for v in rows])


def _g_transpose(position: NDArray[np.float64], p_o: NDArray[np.float64]) -> NDArray[np.float64]:
    r"""``(d, D)`` $G_{ij}^T$: $G^T \dot r = v + \omega \times (p_C - p_O)$ (eq. 6)."""
    r = position - p_o
    if r.shape[0] == 2:  # [vx - w r_y, vy + w r_x]
        return np.array([[1.0, 0.0, -r[1]], [0.0, 1.0, r[0]]])
    skew = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])  # [r x]
    return np.hstack([np.eye(3), -skew])  # omega x r = -[r x] omega


def _box_constraints(
    state: GraspState, tau: cp.Expression, qd: cp.Expression, loss: cp.Expression | float = 0.0
) -> list[cp.Constraint]:
    r"""Eq. (2)-(3) literally: box variables and four corners in the mirrored copies of P
    (per operation range: a joint, or an actuator of a transmission). ``loss`` (>= 0, per
    range) widens the torque's box on both sides: the motor gives ``|tau| + loss``."""
    m = len(state.operation_ranges)
    t_max, t_min, q_max, q_min = (cp.Variable(m) for _ in range(4))
    cons = [t_max >= 0, t_min <= 0, q_max >= 0, q_min <= 0]
    cons += [t_min <= tau - loss, tau + loss <= t_max, q_min <= qd, qd <= q_max]
    n_v = max(len(r.vertices) for r in state.operation_ranges)
    # Pad each vertex list with copies of its first vertex: the hull is unchanged.
    verts = np.array(
        [
            np.vstack([r.vertices, np.repeat(r.vertices[:1], n_v - len(r.vertices), 0)])
            for r in state.operation_ranges
        ]
    )
    for (s1, s2), (tc, qc) in zip(_CORNERS, ((t_max, q_max), (t_max, q_min), (t_min, q_max), (t_min, q_min))):
        lam = cp.Variable((m, n_v), nonneg=True)
        cons += [cp.sum(lam, axis=1) == 1]
        cons += [tc == cp.sum(cp.multiply(lam, s1 * verts[:, :, 0]), axis=1)]
        cons += [qc == cp.sum(cp.multiply(lam, s2 * verts[:, :, 1]), axis=1)]
    return cons


def _build(state: GraspState, w: NDArray[np.float64], r_hat: NDArray[np.float64]) -> cp.Problem:
    r"""The LP (31) / (35) for one REFS vertex ``w`` and one RVDS vertex ``r_hat``."""
    d, m = state.dim, state.num_joints
    alpha = cp.Variable(nonneg=True)
    qd, tau = cp.Variable(m), cp.Variable(m)
    rdot = alpha * r_hat
    wrench: cp.Expression = cp.Constant(w)  # sum_i G_i f_i + w_k (eq. 20)
    torque: cp.Expression = cp.Constant(state.gravity_torque)  # sum_i J_i^T f_i + g_f (eq. 19)
    cons: list[cp.Constraint] = []
    shared_rho = cp.Variable(nonneg=True) if state.slip == "shared" else None
    for c in state.contacts:
        gt = _g_transpose(c.position, state.object_position)
        rel = c.jacobian @ qd - gt @ rdot  # finger-side minus object-side velocity
        n = c.normal
        if c.type == "D":  # eq. (10): no force, may only separate
            cons.append(n @ rel <= 0)
            continue
        if c.type == "F":
            cons.append(rel == 0)  # eq. (7)
            f = cp.Variable(d)
            # docs/state-format.md: the friction margin delta shrinks the cone to (1 - delta) mu
            mu_f = (1.0 - state.friction_margin) * float(c.mu)  # type: ignore[arg-type]
            if mu_f > 0.0:
                cons.append(pyramid_halfspaces(c, state.friction_edges, mu_f) @ f <= 0)  # eq. (24)
            else:  # the pyramid degenerates to the normal ray
                cons += [tangent_basis(n, c.tangent) @ f == 0, n @ f >= 0]
        else:
            cons.append(n @ rel == 0)  # eq. (8)
            n_f = cp.Variable(nonneg=True)  # eq. (22)
            if c.type == "L":
                f = n_f * n
            else:
                s_hat, mu = slide_unit(c), float(c.mu)  # type: ignore[arg-type]  # S: mu validated
                f = n_f * (n - mu * s_hat)  # eq. (16)-(17)
                t = tangent_basis(n, c.tangent)
                if shared_rho is None:  # eq. (13): T (J qd - G^T rdot) = -rho_i T s_hat
                    cons.append(t @ rel == -cp.Variable(nonneg=True) * (t @ s_hat))
                else:  # eq. (34) read literally: one rho, unnormalised slide directions
                    s_tan = c.slide_direction - (c.slide_direction @ n) * n  # type: ignore[operator]
                    cons.append(t @ rel == -shared_rho * (t @ s_tan))
        wrench = wrench + gt.T @ f
        torque = torque + c.jacobian.T @ f
    cons.append(wrench == 0)
    tr = state.transmission
    if tr is None:
        cons.append(tau == torque)
        cons += _box_constraints(state, tau, qd)
    else:
        u = cp.Variable(len(tr.actuator_names))  # actuator forces
        joint_torque = tr.moment.T @ u
        if tr.constraint_jacobian is not None:
            joint_torque = joint_torque + tr.constraint_jacobian.T @ cp.Variable(tr.num_constraints)
            cons.append(tr.constraint_jacobian @ qd == 0)
        cons.append(joint_torque == torque)
        loss: cp.Expression | float = 0.0
        if tr.joint_damping is not None:
            # Damping is a loss (docs/state-format.md): actuator a overcomes b_j |qd_j| through
            # each joint j it moves, its force at least b_j |qd_j| / |P_aj|; never in the balance.
            loss = cp.Variable(len(tr.actuator_names), nonneg=True)
            for a, j in zip(*np.nonzero(tr.moment), strict=True):
                if tr.joint_damping[j] > 0.0:
                    cons.append(loss[a] >= tr.joint_damping[j] * cp.abs(qd[j]) / abs(tr.moment[a, j]))
        cons += _box_constraints(state, u, tr.moment @ qd, loss)
    cons += _limit_constraints(state, qd, alpha, r_hat)
    return cp.Problem(cp.Maximize(alpha), cons)


def _limit_constraints(
    state: GraspState, qd: cp.Variable, alpha: cp.Variable, r_hat: NDArray[np.float64]
) -> list[cp.Constraint]:
    r"""The joint position limits, written from ``docs/joint-limits.md``: a joint on a limit
    (within the tolerance) does not move toward it; any other limited joint does not reach
    its limit while the object travels the horizon $H$ at $\alpha \hat r_l$."""
    lim = state.joint_limits
    if lim is None:
        return []
    d = state.dim
    points = [state.object_position] + [c.position for c in state.contacts]
    speed = max(
        float(np.linalg.norm(_g_transpose(p, state.object_position) @ r_hat)) for p in points
    )  # the object's travel per unit alpha (at p_O the map is [I, 0])
    assert d in (2, 3)
    cons: list[cp.Constraint] = []
    h = lim.horizon
    for j in range(state.num_joints):
        if not np.isfinite(lim.lower[j]):
            continue
        up, dn = lim.upper[j] - lim.position[j], lim.position[j] - lim.lower[j]
        if up <= lim.tolerance:
            cons.append(qd[j] <= 0)
        elif h > 0:
            cons.append(h * qd[j] <= up * speed * alpha)
        if dn <= lim.tolerance:
            cons.append(qd[j] >= 0)
        elif h > 0:
            cons.append(-h * qd[j] <= dn * speed * alpha)
    return cons


def reference_alpha(
    state: GraspState, k: int, l: int, *, solver: str = "CLARABEL"
) -> tuple[str, float | None]:
    r"""Solve LP (31) / (35) for REFS vertex ``k`` and RVDS vertex ``l`` with cvxpy.

    Parameters
    ----------
    state
        A grasp state with ``rvds``.
    k, l
        Indices of $w_k$ in ``state.refs`` and $\hat r_l$ in ``state.rvds``.
    solver
        A cvxpy solver name (``"CLARABEL"``, ``"HIGHS"``, ...).

    Returns
    -------
    tuple
        ``(status, alpha)``: status ``"optimal"``, ``"infeasible"`` or ``"unbounded"``;
        alpha is ``None`` unless optimal.

    Raises
    ------
    SolverError
        When cvxpy reports any other status (for Clarabel and HiGHS: also with their default
        tolerances, tried after the tight ones of ``_CLARABEL_TOL``, ``_HIGHS_TOL``) or the
        solver fails.
    """
    if state.rvds is None:
        raise StateError("rvds", "Problem 2 needs RVDS vertices (a non-empty list of twists)")
    problem = _build(state, state.refs[k], state.rvds[l])
    tight = {"CLARABEL": _CLARABEL_TOL, "HIGHS": _HIGHS_TOL}.get(solver.upper())
    attempts = [tight, {}] if tight is not None else [{}]
    for options in attempts:  # tight tolerances, then the solver's defaults if they stall
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)  # "Solution may be inaccurate"
                problem.solve(solver=solver, **options)
        except cp.error.SolverError as e:
            raise SolverError(f"cvxpy-{solver}", str(e), (k, l)) from e
        if problem.status in _STATUS:
            break
    status = _STATUS.get(problem.status)
    if status is None:
        raise SolverError(f"cvxpy-{solver}", str(problem.status), (k, l))
    return status, (float(problem.value) if status == "optimal" else None)


def reference_tvmmp(
    state: GraspState, *, solver: str = "CLARABEL"
) -> tuple[NDArray[np.float64], tuple[tuple[str, ...], ...]]:
    r"""Every $\alpha_{kl}$ of Problem 2, one freshly built cvxpy LP per pair.

    Parameters
    ----------
    state
        A grasp state with ``rvds``.
    solver
        A cvxpy solver name.

    Returns
    -------
    tuple
        ``(alpha, status)``: ``(K, R)`` alphas (NaN where not optimal) and ``K`` tuples of
        ``R`` statuses; the origin vertex is ``"skipped"`` (Supplement 3).
    """
    if state.rvds is None:
        raise StateError("rvds", "Problem 2 needs RVDS vertices (a non-empty list of twists)")
    n_k, n_l = len(state.refs), len(state.rvds)
    alpha = np.full((n_k, n_l), np.nan)
    status = [["skipped"] * n_l for _ in range(n_k)]
    for k in range(n_k):
        for l in range(n_l):
            if not np.any(state.rvds[l] != 0.0):
                continue
            status[k][l], a = reference_alpha(state, k, l, solver=solver)
            if a is not None:
                alpha[k, l] = a
    return alpha, tuple(tuple(s) for s in status)
