r"""The friction margin and the friction interval (``docs/state-format.md``, "Friction margin").

**Margin.** A state's ``friction_margin`` $\delta \in [0, 1)$ makes every LP use
$(1 - \delta)\mu$ for each F contact's pyramid (eq. 24): the witness forces then keep
$|f_t| \le (1 - \delta)\mu f_n$, a relative distance $\delta$ from the cone
that the contact really has (a simplex witness of Problem 2 puts F forces on the pyramid's
edges, a rollout of it is the first to slip there). The margin is applied to the contacts'
``mu`` before any assembly ([`margin_contacts()`][mjtvm.model.friction.margin_contacts], called by
`assemble()`); the cvxpy transcription
`oracles.reference` (the cvxpy transcription, outside the package) applies it on its own.

S contacts keep ``mu``: kinetic friction is $\mu n_f$ exactly (eq. 16-17), there is
no cone to keep away from, and a smaller coefficient may raise alpha as well as lower it;
the uncertainty of an S coefficient is the interval's.

**Interval.** A contact's ``mu_range`` $[\mu_{lo}, \mu_{hi}]$ holds its true
coefficient. The worst TVMMP over the box of intervals (each contact's coefficient on its
own) is attained at a corner with every F coefficient at $\mu_{lo}$ and every S
coefficient at $\mu_{lo}$ or $\mu_{hi}$: [`interval_corners()`][mjtvm.model.friction.interval_corners], all
$2^S$ of them, then the least TVMMP. Proof (``docs/state-format.md``):

* F: the pyramid of $\mu$ is the cone over a polygon scaled by $\mu$, so a
  larger $\mu$ only adds feasible points: alpha is non-decreasing in it.
* S: with the other coefficients fixed, let $x_1, x_2$ be feasible at
  $\mu_1 < \mu_2$ with alpha $\ge a$. The S force is
  $n_f n - t s$ with $t = \mu n_f$, and every other row is linear in
  $(x, n_f, t)$; so $\theta x_1 + (1-\theta) x_2$ is feasible, with alpha
  $\ge a$, at $\mu(\theta) = (\theta \mu_1 n_1 + (1-\theta)\mu_2 n_2) /
  (\theta n_1 + (1-\theta) n_2)$, which runs continuously from $\mu_2$ to
  $\mu_1$ (if $n_1 = 0$, $x_1$ is feasible at every $\mu$).
  The set $\{\mu : \alpha(\mu) \ge a\}$ is an interval: alpha is quasi-concave in
  each S coefficient, so is the TVMMP (a minimum of quasi-concave functions), and its
  minimum over an interval is at an end; over a box, by induction, at a corner.

The corners' minimum is the exact worst case for independent coefficients; for one
coefficient shared by every contact (the diagonal of the box) it is a lower bound, exact
with at most one S contact per interval.

**Cones.** MuJoCo's elliptic cone is the Coulomb cone of the geom's friction: the LP's
pyramid is inscribed in it at $\mu$. Its pyramidal cone (condim 3) has the four edges
$n \pm \mu t_1, n \pm \mu t_2$: the cross-section is a square with vertices at
$\pm\mu$ on the tangent axes, whose inscribed circle has radius $\mu/\sqrt 2$
(``docs/dynamics.md``): a pyramid inscribed at $\mu/\sqrt 2$ lies in it whatever the
orientation of MuJoCo's tangent frame (`cone_margin()`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from itertools import product
from typing import Any

from mjtvm.errors import ParamError
from mjtvm.model.contacts import Contact
from mjtvm.model.state import GraspState

__all__ = [
    "CONE_SCALE",
    "MAX_INTERVAL_S",
    "FrictionReport",
    "cone_margin",
    "interval_corners",
    "margin_contacts",
    "nominal_state",
]

#: The coefficient of the largest Coulomb cone inside each of MuJoCo's cones, per unit of the
#: geom's friction: elliptic 1 (it is the Coulomb cone), pyramidal 1 / sqrt(2) (module docstring).
CONE_SCALE = {"elliptic": 1.0, "pyramidal": 1.0 / math.sqrt(2.0)}
#: At most this many S contacts with an interval: the worst case solves 2^S states.
MAX_INTERVAL_S = 8


def cone_margin(cone: str, margin: float = 0.0) -> float:
    r"""The state's ``friction_margin`` for a user margin $\delta$ on MuJoCo's ``cone``:
    $1 - (1 - \delta) c$ with $c$ = [`CONE_SCALE`][mjtvm.model.friction.CONE_SCALE] (elliptic: $\delta$;
    pyramidal: $1 - (1 - \delta)/\sqrt 2$, 0.2929 at $\delta = 0$)."""
    if cone not in CONE_SCALE:
        raise ParamError("cone", f"expected 'elliptic' or 'pyramidal', got {cone!r}", cone)
    if not 0.0 <= margin < 1.0:
        raise ParamError("friction_margin", f"expected a number in [0, 1), got {margin!r}", margin)
    scale = CONE_SCALE[cone]
    return margin if scale == 1.0 else 1.0 - (1.0 - margin) * scale  # elliptic: delta exactly


def margin_contacts(state: GraspState) -> tuple[Contact, ...]:
    r"""The state's contacts with every F coefficient at $(1 - \delta)\mu$ (the state's
    ``friction_margin``); the contacts themselves when the margin is 0."""
    delta = state.friction_margin
    if delta == 0.0:
        return state.contacts
    keep = 1.0 - delta
    return tuple(
        replace(c, mu=keep * float(c.mu), mu_range=None) if c.type == "F" else c  # type: ignore[arg-type]
        for c in state.contacts
    )


def nominal_state(state: GraspState) -> GraspState:
    """``state`` at margin 0 and without intervals: the nominal coefficients."""
    contacts = tuple(c if c.mu_range is None else replace(c, mu_range=None) for c in state.contacts)
    return state.with_(contacts=contacts, friction_margin=0.0)


def interval_corners(state: GraspState) -> list[GraspState]:
    r"""The states at the corners of the friction intervals that hold the worst TVMMP (module
    docstring): every F contact with an interval at its $\mu_{lo}$, every S contact with
    one at $\mu_{lo}$ or $\mu_{hi}$ ($2^S$ states; margin kept, intervals
    dropped). Empty when no contact has an interval.

    Raises
    ------
    ParamError
        More than [`MAX_INTERVAL_S`][mjtvm.model.friction.MAX_INTERVAL_S] S contacts with an interval.
    """
    ranged = [i for i, c in enumerate(state.contacts) if c.mu_range is not None]
    if not ranged:
        return []
    sliding = [i for i in ranged if state.contacts[i].type == "S" and _width(state.contacts[i]) > 0.0]
    if len(sliding) > MAX_INTERVAL_S:
        raise ParamError(
            "mu_range",
            f"expected at most {MAX_INTERVAL_S} S contacts with an interval (the worst case solves "
            f"2^S states), got {len(sliding)}",
        )
    out = []
    for ends in product((0, 1), repeat=len(sliding)):
        end = dict(zip(sliding, ends))
        contacts = []
        for i, c in enumerate(state.contacts):
            if c.mu_range is None:
                contacts.append(c)
            else:
                contacts.append(replace(c, mu=c.mu_range[end.get(i, 0)], mu_range=None))
        out.append(state.with_(contacts=tuple(contacts)))
    return out


def _width(c: Contact) -> float:
    return 0.0 if c.mu_range is None else c.mu_range[1] - c.mu_range[0]


@dataclass(frozen=True)
class FrictionReport:
    r"""What a result says about its friction (the ``friction`` object of ``mjtvm.result/1``).

    Attributes
    ----------
    margin
        The state's ``friction_margin`` $\delta$ (F contacts at $(1-\delta)\mu$).
    nominal_tvmmp
        The TVMMP at margin 0 (the nominal coefficients), ``None`` when infeasible; ``None``
        too when not computed (margin 0: it is the result's own).
    worst_tvmmp
        The least TVMMP over the friction intervals (module docstring), at the margin;
        ``None`` without intervals or when a corner is infeasible.
    worst_feasible
        False when some corner cannot balance a REFS vertex (then ``worst_tvmmp`` is ``None``).
    worst_mu
        Contact name -> coefficient (before the margin) at the worst corner.
    corners
        The number of corner states solved.
    certified
        Whether every LP of every corner (and of the nominal solve) is certified.
    """

    margin: float
    nominal_tvmmp: float | None = None
    worst_tvmmp: float | None = None
    worst_feasible: bool = True
    worst_mu: tuple[tuple[str, float], ...] = ()
    corners: int = 0
    certified: bool = True

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"margin": self.margin, "nominal_tvmmp": self.nominal_tvmmp}
        if self.corners:
            out["interval"] = {
                "worst_tvmmp": self.worst_tvmmp,
                "feasible": self.worst_feasible,
                "worst_mu": dict(self.worst_mu),
                "corners": self.corners,
            }
        out["certified"] = self.certified
        return out
