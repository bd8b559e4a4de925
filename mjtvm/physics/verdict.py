"""A pair's verdict in words: why alpha_sim is what it is (the ``verdict`` column of ``verify.csv``).

The bisection ([`bisect()`][mjtvm.physics.bisection.bisect]) ends between a passing speed factor
s* and a failing one just above it; the failing rollout's first violation
(`failure`) is what limits alpha_sim:

* ``slip at contact C`` (an F-point's slip beyond its tolerance), ``contact lost at C`` (a
  finger more than 0.5 mm from the object), ``torque limit at joint J`` (``at actuator A`` for
  a hand with a transmission; several names when several saturate at once), ``speed edge at
  joint J`` (``at actuator A``: it ran more than 1 % faster than its operation range's largest
  speed, ``SimSettings.edge_tol``), ``twist error:
  speed`` / ``twist error: direction`` (the object's twist off by more than 10 % / 10 deg, the
  motors' speed-torque line or a lag), ``moves at rest``;
* prefixed ``fails at rest:`` when even s = 0 fails (alpha_sim = 0), and
  ``passes at the bracket's top (s = 2)`` when nothing failed up to twice alpha_kl;
* ``passes at s* + 0.01 (...)`` when the rollout just above s* passes: pass and fail are not
  monotone in s there, and the bisection's failing midpoint lies between the two;
* a state that does not hold at rest gets the hold test's line instead
  ([`message()`][mjtvm.physics.hold.HoldResult.message]).
"""

from __future__ import annotations

from mjtvm.physics.bisection import Bisection
from mjtvm.physics.simulate import RolloutResult

__all__ = ["failure_words", "verdict"]


def failure_words(result: RolloutResult, *, actuators: bool = False) -> str:
    """The rollout's first violation in words (module docstring); ``""`` when it passed.

    ``actuators``: the saturated names are actuators (a hand with a transmission), not joints.
    """
    kind, where = result.failure
    if kind == "slip":
        return f"slip at contact {where}"
    if kind == "contact lost":
        return f"contact lost at {where}"
    if kind == "torque limit":
        return f"torque limit at {'actuator' if actuators else 'joint'} {where}"
    if kind == "speed edge":
        return f"speed edge at {'actuator' if actuators else 'joint'} {where}"
    if kind in ("twist magnitude", "twist direction"):
        return f"twist error: {'speed' if kind == 'twist magnitude' else 'direction'}"
    return kind


def verdict(bisection: Bisection, fail: RolloutResult, *, actuators: bool = False) -> str:
    """The pair's verdict: what the rollout just above alpha_sim ran into (module docstring)."""
    if bisection.above_bracket:
        return "passes at the bracket's top (s = 2)"
    words = (
        failure_words(fail, actuators=actuators) or "passes at s* + 0.01 (pass/fail not monotone in s there)"
    )
    return f"fails at rest: {words}" if bisection.below_bracket else words
