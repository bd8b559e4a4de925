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

A ratio alpha_sim / alpha_kl outside [`CAUSE_LOW`][mjtvm.physics.verdict.CAUSE_LOW],
[`CAUSE_HIGH`][mjtvm.physics.verdict.CAUSE_HIGH] carries its cause (`ratio_cause()`, the
``cause`` column): below, what the simulation met that the quasi-static LP does not count
(``rotor inertia``, ``slip``, ``contact lost``, ``limit reached``, ``speed edge``,
``twist error``, or ``not monotone`` where the rollout just above s* passes; ``fails at
rest`` when s* = 0); above, ``margin``: the rollout's failure tests allow what the LP's exact
limits do not (a motor up to 1 % past its range's speed, the twist within 10 % and 10 deg, a
slip within its tolerance, the friction cone outside the LP's pyramid), with the failure
that ends it.
"""

from __future__ import annotations

from mjtvm.physics.bisection import Bisection
from mjtvm.physics.simulate import RolloutResult

__all__ = ["CAUSE_HIGH", "CAUSE_LOW", "failure_words", "ratio_cause", "verdict"]

#: A ratio alpha_sim / alpha_kl below this carries its cause (issue 35's bounds: 0.9 and 1.05).
CAUSE_LOW = 0.9
#: A ratio above this carries its cause.
CAUSE_HIGH = 1.05


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


def ratio_cause(
    ratio: float,
    words: str,
    *,
    censored: str = "",
    limit_reached: bool = False,
    inertia_max: float = 0.0,
    inertia_joint: str = "",
    ratio_dyn: float | None = None,
) -> str:
    """Why alpha_sim / alpha_kl is outside [CAUSE_LOW, CAUSE_HIGH] (module docstring); ``""``
    inside it or when it is not a number.

    Parameters
    ----------
    ratio
        alpha_sim / alpha_kl.
    words
        The pair's `verdict()`: the failure of the rollout just above alpha_sim.
    censored
        ``"below"`` (fails at rest), ``"above"`` (passes at the bracket's top) or ``""``.
    limit_reached
        The check's rollout ran a joint onto its limit.
    inertia_max, inertia_joint
        N m: the largest inertial and Coriolis torque along the motion at alpha_kl, and its
        joint ([`inertial_demand()`][mjtvm.physics.inertia.inertial_demand]).
    ratio_dyn
        alpha_sim / alpha_dyn, where the dynamic alpha was computed.
    """
    if not (ratio == ratio) or CAUSE_LOW <= ratio <= CAUSE_HIGH:  # nan, or within the bounds
        return ""
    if censored == "above":
        return "margin: nothing fails up to s = 2, the bracket's top"
    if censored == "below":  # s* = 0: no speed to explain, the rollout fails at rest
        return words if words.startswith("fails at rest") else f"fails at rest: {words}"
    if ratio > CAUSE_HIGH:
        return f"margin: the rollout's tolerances pass what the LP's exact limits bound; then {words}"
    if limit_reached:
        return f"limit reached; {words}"
    if "torque limit" in words:
        dyn = ""
        if ratio_dyn is not None and ratio_dyn == ratio_dyn:
            dyn = f", alpha_sim / alpha_dyn {ratio_dyn:.3g}"
        return (
            f"rotor inertia: {inertia_max:.3g} N m of inertial torque at {inertia_joint}, which the "
            f"quasi-static LP leaves out{dyn}; {words}"
        )
    for kind in ("slip", "contact lost", "speed edge", "twist error"):
        if kind in words:
            return f"{kind}: {words}"
    if "not monotone" in words:  # the rollout above s* passed: no failure to name
        return "not monotone: the rollout at s* + 0.01 passes, the bisection's failing midpoint lies below it"
    return words
