r"""Contacts of the grasp: F, L, S and D points (paper, section 2.1 and eq. 7-24).

=====  ===========================  ===============================================
type   velocity constraint          force on the object
=====  ===========================  ===============================================
F      J qd - G^T rdot = 0 (eq. 7)  in the friction pyramid inscribed in the cone (eq. 24)
L      n^T (J qd - G^T rdot) = 0    n_f n, n_f >= 0 (eq. 22)
S      normal as L; tangential      n_f (n - mu s), n_f >= 0 (eq. 16-17)
       T (J qd - G^T rdot) = -rho s
D      n^T (J qd - G^T rdot) <= 0   0
=====  ===========================  ===============================================

``n`` is the unit normal pointing *into* the object, ``s`` the unit slide direction
(the object's contact-point velocity relative to the finger's, in the tangent plane).
Forces are parameterised by their generators (edges): every admissible force is
``E @ lam`` with ``lam >= 0`` (Minkowski-Weyl: the same cone as the paper's H-form
``V f <= 0`` of eq. 24).

Tangent bases (3-D). ``t1`` is the optional ``tangent`` of the contact, made
orthogonal to ``n``; by default the world axis least aligned with ``n`` (the lowest
index on a tie), made orthogonal to ``n`` and normalised; ``t2 = n x t1``. The pyramid's
edges are ``n + mu (cos th_k t1 + sin th_k t2)``, ``th_k = 2 pi k / n_edges``. The
default rule is fixed by the world axes, so rotating a whole state moves the pyramid
relative to the cone by up to ``pi / n_edges``: alphas of F contacts are then invariant
only within the pyramid's approximation, exactly when the tangents rotate too. In
the plane the tangent is ``[-n_y, n_x]`` and the "pyramid" is the exact cone
``n +- mu t``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import StateError
from mjtvm.lp.roundoff import drop_cancellation, drop_data_roundoff
from mjtvm.model.bounds import MAX_JOINTS, describe, float_array, number

__all__ = ["CONTACT_TYPES", "Contact", "force_generators", "slide_unit", "tangent_basis"]

CONTACT_TYPES = ("F", "L", "S", "D")
ContactType = Literal["F", "L", "S", "D"]
UNIT_TOL = 1e-6  # accepted deviation of a normal's length from 1


def _vector(value: ArrayLike, field: str, length: int) -> NDArray[np.float64]:
    v = float_array(value, field, ndim=1, what=f"a list of {length} numbers")
    if v.shape != (length,):
        raise StateError(field, f"expected {length} numbers, got {v.shape[0]}", value)
    return v


def _direction_norm(v: NDArray[np.float64]) -> float:
    """Euclidean norm without underflow or overflow (entries of 1e-200 or 1e200 squared)."""
    big = float(np.max(np.abs(v))) if v.size else 0.0
    return 0.0 if big == 0.0 else big * float(np.linalg.norm(v / big))


def _mu_range(value: ArrayLike, ctype: str, mu: float | None) -> tuple[float, float]:
    """A contact's ``mu_range`` checked: two numbers ``0 <= lo <= mu <= hi`` on an F or S contact."""
    if ctype not in ("F", "S"):
        raise StateError("mu_range", f"only F and S contacts have friction; this contact is of type {ctype}")
    v = float_array(value, "mu_range", ndim=1, what="two numbers [mu_lo, mu_hi]")
    if v.shape != (2,):
        raise StateError("mu_range", f"expected two numbers [mu_lo, mu_hi], got {v.shape[0]}", value)
    lo, hi = float(v[0]), float(v[1])
    if not 0.0 <= lo <= float(mu) <= hi:  # type: ignore[arg-type]  # mu: validated for F and S
        raise StateError(
            "mu_range", f"expected 0 <= mu_lo <= mu ({mu!r}) <= mu_hi, got [{lo!r}, {hi!r}]", value
        )
    return (lo, hi)


@dataclass(frozen=True, eq=False)
class Contact:
    r"""One contact point $C_{ij}$ between a finger (or the base) and the object.

    Parameters
    ----------
    name
        Unique name.
    type
        ``"F"``, ``"L"``, ``"S"`` or ``"D"``.
    position
        ``(d,)`` contact point, world frame (m).
    normal
        ``(d,)`` unit normal pointing into the object, world frame.
    jacobian
        ``(d, M)``: velocity of the finger-side contact point = ``jacobian @ qdot``
        (eq. 6); all zeros for a fixed base.
    mu
        Friction coefficient (required for F and S, ignored for L and D).
    tangent
        Optional ``(d,)`` direction in the tangent plane fixing the pyramid's ``t1``.
    slide_direction
        S only, ``(d,)``: direction of the object's contact-point velocity relative to
        the finger's; its normal component is ignored.
    preload
        Minimum normal force (N, default 0): the LP requires $n^T f \ge$ ``preload``
        instead of eq. (22)'s $n_f \ge 0$ (F, L and S; a D-point carries no force).
        A finger held on the object by its velocity loop alone (a zero-force L-point) leaves
        it at the first lag; a preload makes the witness press it on.
    mu_range
        Optional ``(mu_lo, mu_hi)`` with ``mu_lo <= mu <= mu_hi`` (F and S only): the interval
        the true coefficient is known to lie in. The LPs use ``mu``; the result adds the worst
        case over the interval (`mjtvm.model.friction`, ``docs/state-format.md``).
    """

    name: str
    type: ContactType
    position: NDArray[np.float64]
    normal: NDArray[np.float64]
    jacobian: NDArray[np.float64]
    mu: float | None = None
    tangent: NDArray[np.float64] | None = None
    slide_direction: NDArray[np.float64] | None = None
    preload: float = 0.0
    mu_range: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise StateError("name", "expected a non-empty string", self.name)
        if not isinstance(self.type, str) or self.type not in CONTACT_TYPES:
            raise StateError("type", f"expected one of F, L, S, D, got {describe(self.type)}", self.type)
        pos = float_array(self.position, "position", ndim=1, what="2 (planar) or 3 (spatial) numbers")
        d = pos.shape[0]
        if d not in (2, 3):
            raise StateError(
                "position", f"expected 2 (planar) or 3 (spatial) numbers, got {d}", self.position
            )
        object.__setattr__(self, "position", pos)
        normal = _vector(self.normal, "normal", d)
        norm = float(np.linalg.norm(normal))
        if abs(norm - 1.0) > UNIT_TOL:
            raise StateError(
                "normal",
                f"expected a unit vector (norm 1 within {UNIT_TOL:g}), got norm {norm:.6g}",
                self.normal,
            )
        # Its round-off is 0 (roundoff module): MuJoCo's n_y = -1.07e-14 on a fingertip whose
        # r_y is 0 made the moment-x row of the balance -2.8e-16 n_f = 0, which pins n_f.
        normal = drop_data_roundoff(normal / norm)
        normal.setflags(write=False)
        object.__setattr__(self, "normal", normal)
        jac = float_array(
            self.jacobian,
            "jacobian",
            ndim=2,
            max_len=d,
            max_width=MAX_JOINTS,
            what=f"{d} rows (one per coordinate) of M numbers",
        )
        if jac.shape[0] != d or jac.shape[1] == 0:
            raise StateError(
                "jacobian",
                f"expected {d} rows (one per coordinate) of M >= 1 numbers, got shape {jac.shape}",
                self.jacobian,
            )
        object.__setattr__(self, "jacobian", jac)
        if self.type in ("F", "S"):
            if self.mu is None:
                raise StateError("mu", f"required for a {self.type} contact")
        if self.mu is not None:
            if isinstance(self.mu, (float, np.floating)) and np.isnan(self.mu):
                raise StateError("mu", "expected a finite number >= 0, got nan", self.mu)
            mu = number(self.mu, "mu")
            if mu < 0.0:
                raise StateError("mu", f"expected a finite number >= 0, got {mu!r}", self.mu)
            object.__setattr__(self, "mu", mu)
        if self.tangent is not None:
            t = _vector(self.tangent, "tangent", d)
            tn = _direction_norm(t)
            if tn == 0.0 or abs(float((t / tn) @ normal)) > UNIT_TOL:
                raise StateError(
                    "tangent", "expected a non-zero direction orthogonal to the normal", self.tangent
                )
            object.__setattr__(self, "tangent", t)
        if self.type == "S":
            if self.slide_direction is None:
                raise StateError("slide_direction", "required for an S contact (the slide direction)")
            s = _vector(self.slide_direction, "slide_direction", d)
            sn = _direction_norm(s)
            st = s / sn - ((s / sn) @ normal) * normal if sn > 0.0 else s
            if float(np.linalg.norm(st)) <= UNIT_TOL:
                raise StateError(
                    "slide_direction",
                    "has no component in the tangent plane (it must not be parallel to the normal)",
                    self.slide_direction,
                )
            object.__setattr__(self, "slide_direction", s)
        elif self.slide_direction is not None:
            raise StateError("slide_direction", f"only S contacts slide; this contact is of type {self.type}")
        preload = number(self.preload, "preload")
        if preload < 0.0:
            raise StateError("preload", f"expected a finite number >= 0 (N), got {preload!r}", self.preload)
        if preload > 0.0 and self.type == "D":
            raise StateError("preload", "a D contact carries no force: its preload must be 0", self.preload)
        object.__setattr__(self, "preload", preload)
        if self.mu_range is not None:
            object.__setattr__(self, "mu_range", _mu_range(self.mu_range, self.type, self.mu))

    @property
    def dim(self) -> int:
        """d: 2 in the plane, 3 in space."""
        return int(self.position.shape[0])

    @property
    def num_joints(self) -> int:
        """M, the number of columns of the Jacobian."""
        return int(self.jacobian.shape[1])


def tangent_basis(
    normal: NDArray[np.float64], tangent: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    r"""Orthonormal tangent basis $T$ (``(d-1, d)``, the paper's $T_{ij}$).

    Rows ``t1`` (and ``t2 = n x t1`` in space); see the module docstring for the rule.
    """
    n = np.asarray(normal, dtype=float)
    if n.shape[0] == 2:
        return np.array([[-n[1], n[0]]])
    if tangent is None:
        axis = int(np.argmin(np.abs(n)))  # argmin takes the lowest index on a tie
        t1 = np.zeros(3)
        t1[axis] = 1.0
    else:
        t1 = np.asarray(tangent, dtype=float)
        t1 = t1 / _direction_norm(t1)  # validated non-zero; pre-scaled so a tiny or huge tangent is safe
    # The round-off of the differences is 0 (roundoff module): a tangent written with
    # 1.7e-18 in a component that is exactly 0 puts that round-off into the LPs' twist column.
    t1 = drop_cancellation(t1 - (t1 @ n) * n, np.abs(t1) + abs(t1 @ n) * np.abs(n))
    t1 /= np.linalg.norm(t1)
    # n x t1 written out: np.cross costs 10 us per call (Problem 2 assembles per state).
    (n0, n1, n2), (a0, a1, a2) = n.tolist(), t1.tolist()
    t2 = np.array([n1 * a2 - n2 * a1, n2 * a0 - n0 * a2, n0 * a1 - n1 * a0])
    mag = np.array([abs(n1 * a2) + abs(n2 * a1), abs(n2 * a0) + abs(n0 * a2), abs(n0 * a1) + abs(n1 * a0)])
    return np.array([t1, drop_cancellation(t2, mag)])


def slide_unit(contact: Contact) -> NDArray[np.float64]:
    """Unit tangential slide direction of an S contact (normal component removed, its
    round-off 0 as in [`tangent_basis()`][mjtvm.model.contacts.tangent_basis])."""
    if contact.slide_direction is None:
        raise StateError("slide_direction", f"contact {contact.name!r} has none")
    s = contact.slide_direction / _direction_norm(contact.slide_direction)  # validated non-zero
    n = contact.normal
    s = drop_cancellation(s - (s @ n) * n, np.abs(s) + abs(s @ n) * np.abs(n))
    return s / np.linalg.norm(s)


@lru_cache(maxsize=8)
def _edge_angles(friction_edges: int) -> tuple[NDArray[np.float64], ...]:
    """``cos``, ``sin`` of the pyramid's ``friction_edges`` edge angles and their magnitudes
    (read only: every contact of every state with that count shares them)."""
    theta = 2.0 * np.pi * np.arange(friction_edges) / friction_edges
    cos, sin = np.cos(theta), np.sin(theta)
    # cos(pi/2) = 6e-17 is an exact 0: left in, such round-off enters the LPs beside O(1)
    # entries, where no scaling can tell it from data (|cos|, |sin| are 0 or >= sin(2 pi/256)).
    cos[np.abs(cos) < 1e-12] = 0.0
    sin[np.abs(sin) < 1e-12] = 0.0
    out = (cos, sin, np.abs(cos), np.abs(sin))
    for a in out:
        a.setflags(write=False)
    return out


def force_generators(contact: Contact, friction_edges: int = 16) -> NDArray[np.float64]:
    r"""``(d, g)`` generators of the admissible contact forces on the object.

    F: the pyramid edges inscribed in the Coulomb cone (eq. 24), ``friction_edges``
    of them in space and 2 in the plane; L: ``n`` (eq. 22); S: ``n - mu s``
    (eq. 16-17: kinetic friction opposes the object's slip); D: none (``g = 0``).
    """
    n = contact.normal
    if contact.type == "L":
        return n.reshape(-1, 1).copy()
    if contact.type == "D":
        return np.zeros((contact.dim, 0))
    mu = float(contact.mu)  # type: ignore[arg-type]  # validated for F and S
    if contact.type == "S":
        s = slide_unit(contact)
        return drop_cancellation(n - mu * s, np.abs(n) + mu * np.abs(s)).reshape(-1, 1)
    basis = tangent_basis(n, contact.tangent)
    if contact.dim == 2:
        t = basis[0]
        return np.column_stack([n + mu * t, n - mu * t])
    cos, sin, abs_cos, abs_sin = _edge_angles(friction_edges)
    edges = n[:, None] + mu * (np.outer(basis[0], cos) + np.outer(basis[1], sin))
    mag = np.abs(n)[:, None] + mu * (
        np.outer(np.abs(basis[0]), abs_cos) + np.outer(np.abs(basis[1]), abs_sin)
    )
    return drop_cancellation(np.asarray(edges), mag)
