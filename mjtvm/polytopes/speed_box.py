r"""Problem 1 when no force binds: the TVMS is the image of the joint-speed box, a zonotope.

$S_{ov}$ (eq. 26) couples the twist to the forces only through the joint speeds' box:
joint j may turn at $|\dot q_j| \le$ the speed its operation range allows at its
torque. When one set of forces balances every REFS vertex with every torque in the range
that still allows the joint's full speed $\dot q_{max,j}$ (the vertex of $P_j$
on the speed axis), every joint speed in the box $B = \prod_j [-\dot q_{max,j},
\dot q_{max,j}]$ is feasible with those forces, and none outside it is (down-closure, eq. 1),
so the statics drop out: $S_{ov} = \{\dot r \in V : A_q \dot q = A_r \dot r,\ \dot q \in B\}$.

**The condition** ([`speed_box_projection()`][mjtvm.polytopes.speed_box.speed_box_projection]; all of it, else the LP projection runs):

1. *no contact force is needed*: every REFS vertex is 0 and no contact has a preload, so
   the zero forces balance them, leaving each torque at the gravity torque $g_j$;
2. *no other force helps*: either the gravity torques leave every joint its full speed,
   $(|g_j|, \dot q_{max,j}) \in P_j$ (to 1e-12 relative), or the state has one
   contact, whose force must then be 0 (a point force balances no wrench but 0); the box's
   half-widths are the speeds at $g_j$,
   `max_speed_at()`, as on the LP path;
3. no transmission (its damping puts the speeds in the torque rows), no joint on its
   position limit (its speed is one-sided, `limits`), and only F and L contacts
   (equalities $A_q \dot q = A_r \dot r$, eq. 7 and 9; an S contact's slip and a D
   contact's inequality are not images of the box);
4. the twist space ``V`` is a linear subspace: all of $R^D$ without the RVDS cone, or
   the cone of an RVDS whose every vertex's negative is a vertex too (translations:
   $\pm e_x, \pm e_y, \pm e_z$);
5. the kinematics fix the twist and leave the joints free: $A_r$ is injective on ``V``
   and $\mathrm{range}(A_q) \subseteq A_r V$ (rank decisions at
   `RANK_TOL` relative).

Then $S_{ov} = \{T \dot q : \dot q \in B\}$ with $T = E (A_r E)^+ A_q$ (``E`` an
orthonormal basis of ``V``), a zonotope ([`zonotope()`][mjtvm.polytopes.zonotope.zonotope]). One
fingertip F-contact with the translations as RVDS is the classic velocity polytope
$\{J \dot q : \dot q \in B\}$ of the fingertip's Jacobian (pycapacity's
``velocity_polytope``). Conditions 1-2 are sufficient, not necessary, for forces not to
bind (internal forces that keep the torques small would also do; an LP would decide it).
Where forces cannot bind, $S_{ov}$ has the same vertices on both paths; the LP path
finds them to its 1e-9 tolerance, this one to round-off.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState
from mjtvm.polytopes.lifted import Projection
from mjtvm.polytopes.zonotope import RANK_TOL, zonotope
from mjtvm.problem2.assembly import grasp_map_transpose

__all__ = [
    "FULL_SPEED_TOL",
    "BoxImage",
    "ray_lengths_in",
    "speed_box",
    "speed_box_map",
    "speed_box_projection",
]

FULL_SPEED_TOL = 1e-12  #: a joint keeps its full speed at its gravity torque to this relative slack


def _speeds_at(ranges: tuple[OperationRange, ...], torques: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(M,)`` `max_speed_at()` of each joint's
    torque, the same arithmetic, once per distinct range (a hand's joints often share one)."""
    out = np.empty(len(ranges))
    t = np.abs(torques)
    groups: dict[int, list[int]] = {}
    for j, r in enumerate(ranges):
        groups.setdefault(id(r), []).append(j)
    for joints in groups.values():
        r = ranges[joints[0]]
        hp = r.halfplanes[r.halfplanes[:, 1] > 0.0]
        tj = t[joints]
        best = np.min(
            (hp[:, 2][:, None] - hp[:, 0][:, None] * tj) / hp[:, 1][:, None], axis=0, initial=r.max_speed
        )
        out[joints] = np.where(tj > r.max_torque * (1 + 1e-12), -np.inf, best)
    return out


def ray_lengths_in(proj: Projection, rays: NDArray[np.float64]) -> NDArray[np.float64]:
    """``max alpha`` with ``alpha r`` in $S_{ov}$ for each row ``r`` of ``(R, D)`` ``rays``
    (Problem 2's alphas with one REFS vertex), from the facets of a [`BoxImage`][mjtvm.polytopes.speed_box.BoxImage]'s
    projection: ``nan`` for a zero row, 0 for a ray leaving the linear hull at once, ``inf``
    where no facet stops it (the rule of the LP path's ``tvms._ray_lengths``, all rays at once)."""
    w, basis = proj.metric, proj.basis
    s = rays * w
    size = np.sqrt(np.einsum("ij,ij->i", s, s))
    out = np.full(len(rays), np.inf)
    if proj.facets is not None and basis is not None:
        rate = rays @ proj.facets[0].T
        ratio = np.full(rate.shape, np.inf)
        np.divide(np.maximum(proj.facets[1], 0.0), rate, out=ratio, where=rate > 1e-300)
        out = ratio.min(axis=1, initial=np.inf)
    else:  # a point or a segment: between the vertices (or the origin)
        for i, r in enumerate(s):
            along = proj.vertices * w @ r / max(float(size[i]) ** 2, 1e-300)
            out[i] = max(float(np.max(along, initial=0.0)), 0.0)
    if basis is not None:
        rest = s - (s @ basis.T) @ basis
        off = np.sqrt(np.einsum("ij,ij->i", rest, rest)) > 1e-9 * size
        out[off] = 0.0
    out[size == 0.0] = np.nan
    return out


def speed_box(state: GraspState) -> tuple[NDArray[np.float64] | None, str]:
    """``(M,)`` the joint speeds' half-widths when no contact force binds (conditions 1-3 of the
    module docstring), else ``None`` and why not."""
    if state.transmission is not None:
        return None, "a transmission couples the joints"
    if np.any(state.refs != 0.0):
        return None, "a REFS wrench needs contact forces"
    lim = state.joint_limits
    if lim is not None and np.any(lim.at_upper | lim.at_lower):  # its box is one-sided
        j = int(np.flatnonzero(lim.at_upper | lim.at_lower)[0])
        return None, f"joint {state.joint_names[j]!r} is on its position limit"
    for c in state.contacts:
        if c.preload > 0.0:
            return None, f"contact {c.name!r} has a preload"
        if c.type not in ("F", "L"):
            return None, f"contact {c.name!r} is a {c.type} contact (only F and L kinematics are equalities)"
    ranges = state.operation_ranges
    at_g = _speeds_at(ranges, state.gravity_torque)
    if np.any(at_g < 0.0):
        return None, "a gravity torque exceeds its joint's torque"
    if len(state.contacts) != 1:
        top = np.array([r.max_speed for r in ranges])
        slow = np.flatnonzero(at_g < top * (1.0 - FULL_SPEED_TOL))
        if len(slow):
            return None, f"the gravity torque of joint {state.joint_names[slow[0]]!r} lowers its speed"
    return at_g, ""


def _twist_space(state: GraspState, rvds_cone: bool) -> NDArray[np.float64] | None:
    """``(D, k)`` orthonormal basis of the twist space (condition 4), ``None`` if the RVDS cone
    is not a subspace."""
    big_d = state.twist_dim
    if not rvds_cone or state.rvds is None:
        return np.eye(big_d)
    r = np.asarray(state.rvds, dtype=float)
    nonzero = r != 0.0
    count = nonzero.sum(axis=1)
    r = r[count > 0]
    if not len(r):
        return np.zeros((big_d, 0))
    if (count <= 1).all():  # +-e_i only: a subspace iff each axis has both signs
        axis = nonzero[count > 0].argmax(axis=1)
        signs = np.sign(r[np.arange(len(r)), axis])
        pos, neg = set(axis[signs > 0].tolist()), set(axis[signs < 0].tolist())
        return np.eye(big_d)[:, sorted(pos)] if pos == neg else None
    size = np.linalg.norm(r, axis=1)
    gap = np.linalg.norm(r[:, None, :] + r[None, :, :], axis=2)  # |r_i + r_j|: 0 for a pair
    if not np.all(np.min(gap, axis=1) <= RANK_TOL * size):
        return None
    u, sv, _ = np.linalg.svd(r.T, full_matrices=False)
    return np.asarray(u[:, : int(np.sum(sv > RANK_TOL * sv[0]))])


def speed_box_map(state: GraspState, rvds_cone: bool) -> tuple[NDArray[np.float64] | None, str]:
    r"""``(D, M)`` the map $T = E (A_r E)^+ A_q$ with $S_{ov} = T B$ (conditions 3-5
    of the module docstring; 1-2 are [`speed_box()`][mjtvm.polytopes.speed_box.speed_box]), else ``None`` and why not."""
    e = _twist_space(state, rvds_cone)
    if e is None:
        return None, "the RVDS cone is not a linear subspace"
    aq, ar = [], []
    for c in state.contacts:
        sel = np.eye(state.dim) if c.type == "F" else c.normal.reshape(1, -1)
        aq.append(sel @ c.jacobian)
        ar.append(sel @ grasp_map_transpose(c.position, state.object_position))
    if not aq or not e.shape[1]:
        return None, "no contact kinematics" if e.shape[1] else "the twist space is {0}"
    a_q, b = np.vstack(aq), np.vstack(ar) @ e
    u, sv, vt = np.linalg.svd(b, full_matrices=False)
    if len(sv) < b.shape[1] or sv[-1] <= RANK_TOL * sv[0]:  # A_r not injective on V
        return None, "the contacts leave the object free to move"
    proj = u.T @ a_q
    if np.linalg.norm(a_q - u @ proj) > RANK_TOL * max(float(np.linalg.norm(a_q)), 1e-300):
        return None, "the contact kinematics restrict the joint speeds"
    return e @ (vt.T @ (proj / sv[:, None])), ""


@dataclass(frozen=True, eq=False)
class BoxImage:
    """$S_{ov}$ as the image of the joint-speed box.

    Attributes
    ----------
    projection
        The `Projection` the LP path would return (status
        ``"bounded"``, vertices in twist coordinates, ``basis`` and ``facets`` as there;
        ``method = "zonotope"``, no LP).
    affine_volume
        Its volume inside the affine hull in the scaled coordinates ``weights * rdot``
        (Shephard's sum, [`zonotope`][mjtvm.polytopes.zonotope]).
    """

    projection: Projection
    affine_volume: float


def speed_box_projection(
    state: GraspState, weights: NDArray[np.float64], rvds_cone: bool
) -> tuple[BoxImage | None, str]:
    """$S_{ov}$ of ``state`` as a [`BoxImage`][mjtvm.polytopes.speed_box.BoxImage] in the scaled coordinates
    ``weights * rdot`` when the module docstring's condition holds and the enumeration fits
    `MAX_CANDIDATES`; else ``None`` and why not."""
    t0 = time.perf_counter()
    box, why = speed_box(state)
    if box is None:
        return None, why
    t, why = speed_box_map(state, rvds_cone)
    if t is None:
        return None, why
    try:
        z = zonotope(np.zeros(state.twist_dim), weights[:, None] * t * box)
    except ParamError as e:  # the arrays are finite: only the enumeration's size is refused
        return None, str(e)
    rows = z.normals * weights
    norm = np.sqrt(np.einsum("ij,ij->i", rows, rows))
    facets = (rows / norm[:, None], z.offsets / norm) if z.dimension >= 2 else None
    proj = Projection(
        status="bounded",
        vertices=z.vertices / weights,
        dimension=z.dimension,
        basis=z.basis,
        metric=weights,
        unbounded_direction=None,
        num_lps=0,
        seconds=time.perf_counter() - t0,
        method="zonotope",
        facets=facets,
    )
    return BoxImage(proj, z.affine_volume), ""
