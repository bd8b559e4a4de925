r"""alpha_sim of one pair (k, l): the largest fraction s of $\alpha_{kl}$ whose witness a MuJoCo
rollout achieves, found by bisection on pass/fail rollouts ([`rollout()`][mjtvm.physics.simulate.rollout]).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import StateError
from mjtvm.model.state import GraspState
from mjtvm.physics.settings import SimSettings
from mjtvm.physics.simulate import rollout
from mjtvm.physics.witness import Drive, WitnessKind, witness_drive
from mjtvm.problem2.tvmmp import tvmmp

_F64 = NDArray[np.float64]

__all__ = ["MONOTONE_GRID", "Bisection", "alpha_sim", "bisect", "monotone_flips"]

MONOTONE_GRID = (0.8, 0.9, 0.95, 1.05, 1.1, 1.2)
"""The speeds about a bisection's threshold that [`monotone_flips()`][mjtvm.physics.bisection.monotone_flips]
tries: below 1, fractions of s* (each should pass); above 1, multiples of s* + tol (each should fail)."""


@dataclass(frozen=True)
class Bisection:
    """Largest passing value found, and whether it sits at a bracket end (censored)."""

    value: float
    below_bracket: bool
    above_bracket: bool
    evaluations: int


def bisect(
    passes: Callable[[float], bool], lo: float = 0.0, hi: float = 2.0, *, tol: float = 0.01
) -> Bisection:
    r"""Largest ``x`` in ``[lo, hi]`` with ``passes(x)``, assuming pass below / fail above a threshold.

    Returns ``lo`` (``below_bracket``) if ``passes(lo)`` is False and ``hi``
    (``above_bracket``) if ``passes(hi)`` is True; otherwise the last passing midpoint,
    within ``tol`` of the threshold.
    """
    if not (lo < hi and tol > 0):
        raise StateError("bracket", f"expected lo < hi and tol > 0, got {lo}, {hi}, {tol}")
    if passes(hi):
        return Bisection(hi, False, True, 1)
    if not passes(lo):
        return Bisection(lo, True, False, 2)
    count = 2
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        count += 1
        lo, hi = (mid, hi) if passes(mid) else (lo, mid)
    return Bisection(lo, False, False, count)


def monotone_flips(
    b: Bisection,
    passes: Callable[[float], bool],
    *,
    grid: tuple[float, ...] = MONOTONE_GRID,
    tol: float = 0.01,
    hi: float = 2.0,
) -> list[str] | None:
    """The speeds of ``grid`` about the threshold s* of ``b`` at which pass/fail is not what a
    threshold says: ``"fails at s = X"`` below s*, ``"passes at s = X"`` above s* + ``tol``
    (empty: monotone there); ``None`` when ``b`` is censored (s* at a bracket end: no threshold
    inside it). Speeds beyond ``hi`` or at 0 are not tried."""
    if b.below_bracket or b.above_bracket:
        return None
    flips = []
    for f in grid:
        s = f * b.value if f < 1.0 else f * (b.value + tol)
        if not 0.0 < s <= hi:
            continue
        ok = passes(s)
        if f < 1.0 and not ok:
            flips.append(f"fails at s = {s:.3g}")
        elif f > 1.0 and ok:
            flips.append(f"passes at s = {s:.3g}")
    return flips


def alpha_sim(
    model: mujoco.MjModel,
    qpos: _F64,
    state: GraspState,
    k: int,
    l: int,
    *,
    result: Any = None,
    settings: SimSettings | None = None,
    witness: WitnessKind = "central",
    bracket: tuple[float, float] = (0.0, 2.0),
    tol: float = 0.01,
    object_body: str = "object",
    drive: Callable[[float], Drive] | None = None,
) -> tuple[float, float, Bisection]:
    r"""alpha_sim of pair (k, l): $s^* \alpha_{kl}$, s* by [`bisect()`][mjtvm.physics.bisection.bisect] on rollouts.

    ``model`` from `sim_model()`; ``result``: the state's
    [`TvmmpResult`][mjtvm.problem2.tvmmp.TvmmpResult] (solved here when omitted). ``drive``:
    the drive at speed factor s (default the witness's,
    [`witness_drive()`][mjtvm.physics.witness.witness_drive]; the squeeze's:
    [`squeezed_drive()`][mjtvm.physics.hold_drive.squeezed_drive]). Returns
    ``(alpha_sim, alpha_kl, bisection)``.

    Raises
    ------
    StateError
        The pair is not optimal in the LP (no witness).
    """
    res = tvmmp(state) if result is None else result
    if res.status[k][l] != "optimal":
        raise StateError("pair", f"pair ({k}, {l}) is {res.status[k][l]}: no witness to simulate")
    alpha, vertex = float(res.alpha[k, l]), res.witnesses[k][l]

    def passes(s: float) -> bool:
        at = (
            witness_drive(state, k, l, alpha, s, witness=witness, vertex=vertex)
            if drive is None
            else drive(s)
        )
        return rollout(model, qpos, at, settings=settings, object_body=object_body).passed

    b = bisect(passes, *bracket, tol=tol)
    return b.value * alpha, alpha, b
