"""The result of Problem 2 (the ``mjtvm.result/1`` document) and its JSON helpers."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from mjtvm.model.friction import FrictionReport
from mjtvm.problem2.assembly import BoxForm

__all__ = [
    "RESULT_SCHEMA",
    "Diagnosis",
    "DiagnosisCause",
    "PairStatus",
    "Timings",
    "TvmmpResult",
    "Witness",
    "finite_floats",
    "finite_or_none",
]

PairStatus = Literal["optimal", "infeasible", "unbounded", "skipped"]
DiagnosisCause = Literal["contacts", "ranges", "balance", "unheld", "limits", "unknown"]
RESULT_SCHEMA = "mjtvm.result/1"


def finite_floats(values: Any) -> Any:
    """Nested lists of floats for JSON with every NaN or infinity as ``None`` (JSON has
    neither; ``json.dumps(..., allow_nan=False)`` holds on every document), signed zeros as
    0.0. An overflow (e.g. ``alpha * r`` for an RVDS entry near 1e308) becomes ``None``."""
    a = np.asarray(values, dtype=float) + 0.0
    if a.ndim == 0:
        return float(a) if np.isfinite(a) else None
    out = a.tolist()
    return out if np.all(np.isfinite(a)) else _none_nan(out)


def _none_nan(x: Any) -> Any:
    if isinstance(x, list):
        return [_none_nan(v) for v in x]
    return x if math.isfinite(x) else None


def finite_or_none(x: float | None) -> float | None:
    """``x`` when finite, else ``None`` (JSON has no NaN or infinity)."""
    return None if x is None or not math.isfinite(x) else float(x)


@dataclass(frozen=True)
class Diagnosis:
    r"""Why a pair's alpha is 0 or a REFS vertex cannot be balanced ([`diagnosis`][mjtvm.problem2.diagnosis]).

    Attributes
    ----------
    pair
        ``(k, l)`` of an alpha 0; ``(k, -1)`` for a REFS vertex that cannot be balanced (every
        pair of that ``k`` infeasible).
    cause
        ``"contacts"``: the kinematics of ``contacts`` alone lock the motion (eq. 11-13);
        ``"ranges"``: the operation ranges of ``joints`` bind (eq. 19-20 with eq. 1);
        ``"balance"``: no contact forces balance the REFS vertex, whatever the torques;
        ``"unheld"``: the transmission leaves joint motions (``joints``) that no actuator
        drives and no equality holds, and the REFS vertex needs torque along them
        ([`unheld_motions()`][mjtvm.problem2.holding.unheld_motions]);
        ``"limits"``: the position limits of ``joints`` bind (`limits`);
        ``"unknown"``: neither found (an alpha at the solver's tolerance).
    contacts, joints
        The names of a minimal set of contacts (``"contacts"``) or joints (``"ranges"``).
    message
        One line in words.
    direction
        For a REFS vertex that cannot be balanced (pair ``(k, -1)``), where its Farkas
        certificate gives one: ``(D,)`` the unit twist ``[v; omega]`` (about the object's
        origin, world frame) along which the net wrench on the object pushes it whatever
        the admissible contact forces: minus the certified multipliers of the balance rows
        (eq. 20), scaled to norm 1; ``()`` otherwise.
    relief
        For cause ``"balance"``: ``(contact, change)`` pairs, each a change of one contact
        alone that makes the REFS vertex balanced (``"mu >= 1.74"``, a larger friction
        coefficient; ``"type F, mu 0.3"``, the contact sticking); ``()`` when none does.
    """

    pair: tuple[int, int]
    cause: DiagnosisCause
    contacts: tuple[str, ...]
    joints: tuple[str, ...]
    message: str
    direction: tuple[float, ...] = ()
    relief: tuple[tuple[str, str], ...] = ()

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "pair": list(self.pair),
            "cause": self.cause,
            "contacts": list(self.contacts),
            "joints": list(self.joints),
            "message": self.message,
        }
        if self.direction:
            out["direction"] = [float(x) for x in self.direction]
        if self.cause == "balance":
            out["relief"] = [{"contact": c, "change": ch} for c, ch in self.relief]
        return out


@dataclass(frozen=True, eq=False)
class Witness:
    r"""A solution attaining $\alpha_{kl}$ (Supplement 1 scales it down to any speed).

    Attributes
    ----------
    alpha
        $\alpha_{kl}$.
    twist
        ``(D,)`` object twist $\alpha \hat r_l$ = [v of p_O (m/s); omega (rad/s)].
    forces
        ``(L, d)`` contact forces on the object (N), world frame.
    torques
        ``(M,)`` joint torques $\tau$ (N m), eq. (19); with a transmission the
        ``(A,)`` actuator forces ``u`` (N or N m), one per operation range.
    speeds
        ``(M,)`` joint speeds $\dot q$ (rad/s).
    slip_speeds
        Slip speeds $\rho$ of the S-points (m/s), one per S-point or one shared.
    box
        ``(M, 4)`` the box of eq. (2): ``[tau_min, tau_max, qd_min, qd_max]`` per joint
        (``(A, 4)`` per actuator with a transmission, its force and speed). With the
        eliminated form it is the smallest valid box
        ``[min(tau - loss, 0), max(tau + loss, 0), min(qd, 0), max(qd, 0)]``, ``loss`` the
        force that overcomes the joints' damping (0 without damping; ``tau + loss`` is what
        the motor gives, [`assembly`][mjtvm.problem2.assembly]).
    actuator_speeds
        ``(A,)`` actuator speeds ``P qd`` (m/s or rad/s) with a transmission, else ``None``
        (the joint speeds are the actuators').
    """

    alpha: float
    twist: NDArray[np.float64]
    forces: NDArray[np.float64]
    torques: NDArray[np.float64]
    speeds: NDArray[np.float64]
    slip_speeds: NDArray[np.float64]
    box: NDArray[np.float64]
    actuator_speeds: NDArray[np.float64] | None = None

    @property
    def range_speeds(self) -> NDArray[np.float64]:
        """The speeds paired with `torques` in the operation ranges."""
        return self.speeds if self.actuator_speeds is None else self.actuator_speeds

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        out = {
            "alpha": finite_or_none(self.alpha),
            "twist": finite_floats(self.twist),
            "forces": finite_floats(self.forces),
            "torques": finite_floats(self.torques),
            "speeds": finite_floats(self.speeds),
            "slip_speeds": finite_floats(self.slip_speeds),
            "box": finite_floats(self.box),
        }
        if self.actuator_speeds is not None:
            out["actuator_speeds"] = finite_floats(self.actuator_speeds)
        return out


@dataclass(frozen=True)
class Timings:
    """Wall-clock seconds spent assembling and solving, and the number of LPs solved."""

    assemble_s: float
    solve_s: float
    total_s: float
    num_lps: int


@dataclass(frozen=True, eq=False)
class TvmmpResult:
    r"""Result of Problem 2 for one state (the ``mjtvm.result/1`` document).

    Attributes
    ----------
    alpha
        ``(K, R)`` $\alpha_{kl}$; NaN where the pair is not ``optimal``.
    status
        ``K`` tuples of ``R`` statuses: ``optimal``, ``infeasible``, ``unbounded`` or ``skipped``.
    tvmmp
        $\min \alpha_{kl}$ over the optimal pairs; ``None`` when a pair is
        infeasible or no pair is optimal.
    feasible
        False when some REFS vertex cannot be balanced at all.
    held
        ``K`` booleans: whether REFS vertex $w_k$ is held at rest, balanced at zero
        joint speed within the ranges' torque at zero speed ([`holding`][mjtvm.problem2.holding]);
        a pair of an unheld ``k`` is infeasible. Empty for a result built without it.
    distribution
        One entry per RVDS vertex: $\min_k \alpha_{kl} \hat r_l$ (Supplement 4), or
        ``None`` where no finite minimum exists; the origin is implied.
    limiting
        The (k, l) attaining the TVMMP, or ``None``; of alphas within a relative 1e-8 of
        the TVMMP (a tie up to the solver's round-off), the first in (k, l) order.
    witnesses
        ``K`` tuples of ``R`` [`Witness`][mjtvm.problem2.result.Witness] (``None`` where not optimal or not requested).
    timings
        [`Timings`][mjtvm.problem2.result.Timings].
    solver, box
        The backend asked for and the operation-range form used.
    settled_by
        ``K`` tuples of ``R``: the backend whose verdict each pair reports (``"highs"`` or
        ``"clarabel"``; ``None`` where skipped). It differs from ``solver`` where HiGHS
        could not settle an LP and Clarabel did, or where Clarabel's infeasible/unbounded
        verdict was overruled by HiGHS and a feasibility re-solve.
    certified
        ``K`` tuples of ``R``: whether each pair's answer is certified on the unscaled LP
        ([`certificate`][mjtvm.lp.certificate]: an optimal alpha by its primal, dual and gap
        checks; an infeasible or unbounded verdict by a second, cold solve); ``None`` where
        skipped. A pair that is not certified has a note saying what failed.
    notes
        ``((k, l), message)`` for every LP on which a backend failed, the backends
        disagreed, or an answer failed its certificate (``l = -1``: the balance-only LP of
        a state without non-zero RVDS vertex).
    diagnosis
        Per alpha 0 and per REFS vertex that cannot be balanced, why
        ([`diagnose()`][mjtvm.problem2.diagnosis.diagnose]); empty unless asked for (``tvmmp(...,
        diagnose=True)``) and some alpha is 0 or some pair infeasible.
    friction
        [`FrictionReport`][mjtvm.model.friction.FrictionReport] when the state has a friction margin or
        friction intervals (the TVMMP at margin 0, the worst case over the intervals), else
        ``None``. ``alpha`` and ``tvmmp`` are at the margin, at the nominal coefficients.
    """

    alpha: NDArray[np.float64]
    status: tuple[tuple[PairStatus, ...], ...]
    tvmmp: float | None
    feasible: bool
    distribution: tuple[NDArray[np.float64] | None, ...]
    limiting: tuple[int, int] | None
    witnesses: tuple[tuple[Witness | None, ...], ...] = field(repr=False)
    timings: Timings
    solver: str
    box: BoxForm
    settled_by: tuple[tuple[str | None, ...], ...] = ()
    certified: tuple[tuple[bool | None, ...], ...] = ()
    notes: tuple[tuple[tuple[int, int], str], ...] = ()
    diagnosis: tuple[Diagnosis, ...] = ()
    held: tuple[bool, ...] = ()
    friction: FrictionReport | None = None

    def uncertified(self) -> list[tuple[int, int]]:
        """The pairs whose answer is not certified (each has a note), in (k, l) order."""
        return [(k, l) for k, row in enumerate(self.certified) for l, c in enumerate(row) if c is False]

    def note(self, pair: tuple[int, int]) -> str | None:
        """The note of ``pair`` (the last, if several), or ``None``."""
        found = [m for p, m in self.notes if p == pair]
        return found[-1] if found else None

    def to_dict(self, *, witnesses: bool = True) -> dict[str, Any]:
        """The ``mjtvm.result/1`` document; extra keys follow the schema's own."""
        out: dict[str, Any] = {
            "schema": RESULT_SCHEMA,
            "tvmmp": finite_or_none(self.tvmmp),
            "feasible": self.feasible,
            "held": list(self.held),
            "alpha": [
                [None if s != "optimal" else finite_or_none(a) for a, s in zip(ar, sr)]
                for ar, sr in zip(self.alpha, self.status)
            ],
            "status": [list(s) for s in self.status],
            "distribution": [None if v is None else finite_floats(v) for v in self.distribution],
            "limiting": None if self.limiting is None else list(self.limiting),
            "solver": self.solver,
            "settled_by": [list(b) for b in self.settled_by],
            "certified": [list(c) for c in self.certified],
            "notes": [{"pair": list(p), "message": m} for p, m in self.notes],
            "box": self.box,
            "timings": {
                "assemble_s": self.timings.assemble_s,
                "solve_s": self.timings.solve_s,
                "total_s": self.timings.total_s,
                "num_lps": self.timings.num_lps,
            },
        }
        if self.diagnosis:
            out["diagnosis"] = [d.to_dict() for d in self.diagnosis]
        if self.friction is not None:
            out["friction"] = self.friction.to_dict()
        if witnesses:
            out["witnesses"] = [[None if w is None else w.to_dict() for w in row] for row in self.witnesses]
        return out
