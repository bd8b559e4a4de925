"""A ratio's cause (mjtvm.physics.verdict.ratio_cause) from the pair's verdict and check columns."""

from __future__ import annotations

import math

import pytest

from mjtvm.jobs.verify_report import cause_kind
from mjtvm.physics.verdict import CAUSE_HIGH, CAUSE_LOW, ratio_cause


@pytest.mark.parametrize("ratio", [CAUSE_LOW, 1.0, CAUSE_HIGH, math.nan])
def test_no_cause_within_the_bounds_or_without_a_ratio(ratio: float) -> None:
    assert ratio_cause(ratio, "torque limit at joint j1") == ""


def test_below_a_torque_limit_is_rotor_inertia_with_its_torque_and_alpha_dyn() -> None:
    cause = ratio_cause(
        0.66, "torque limit at joint j2", inertia_max=0.0123, inertia_joint="j2", ratio_dyn=1.006
    )
    assert cause == (
        "rotor inertia: 0.0123 N m of inertial torque at j2, which the quasi-static LP leaves out, "
        "alpha_sim / alpha_dyn 1.01; torque limit at joint j2"
    )
    assert cause_kind(cause) == "rotor inertia"
    assert "alpha_dyn" not in ratio_cause(0.66, "torque limit at joint j2", inertia_joint="j2")


@pytest.mark.parametrize(
    ("words", "kind"),
    [
        ("slip at contact tip1", "slip"),
        ("contact lost at tip2", "contact lost"),
        ("speed edge at actuator fingers", "speed edge"),
        ("twist error: direction", "twist error"),
    ],
)
def test_below_the_failure_names_the_cause(words: str, kind: str) -> None:
    cause = ratio_cause(0.5, words)
    assert cause == f"{kind}: {words}" and cause_kind(cause) == kind


def test_a_limit_reached_comes_first() -> None:
    cause = ratio_cause(0.8, "slip at contact tip1", limit_reached=True)
    assert cause == "limit reached; slip at contact tip1" and cause_kind(cause) == "limit reached"


def test_above_is_the_margin_of_the_rollout_tests() -> None:
    cause = ratio_cause(1.2, "speed edge at actuator fingers")
    assert cause.startswith("margin: ") and cause.endswith("then speed edge at actuator fingers")
    top = ratio_cause(2.0, "passes at the bracket's top (s = 2)", censored="above")
    assert top == "margin: nothing fails up to s = 2, the bracket's top" and cause_kind(top) == "margin"


def test_a_non_monotone_pair_says_so() -> None:
    cause = ratio_cause(0.88, "passes at s* + 0.01 (pass/fail not monotone in s there)")
    assert cause_kind(cause) == "not monotone"


def test_a_pair_failing_at_rest_is_not_blamed_on_its_speed() -> None:
    cause = ratio_cause(0.0, "fails at rest: torque limit at joint j1", censored="below", inertia_joint="j1")
    assert cause == "fails at rest: torque limit at joint j1" and cause_kind(cause) == "fails at rest"
