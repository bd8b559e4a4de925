"""The ROC AUC of ``mjtvm rank --verify`` (mjtvm.jobs.rank_auc): hand-computed and closed forms."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from mjtvm.jobs.rank_auc import AUC_COLUMNS, auc_scores, auc_summary, auc_table, bootstrap_ci, roc_auc


def _pairwise(scores: list[float], labels: list[bool]) -> float:
    """The Mann-Whitney statistic by its definition: every (positive, negative) pair."""
    pos = [s for s, y in zip(scores, labels, strict=True) if y]
    neg = [s for s, y in zip(scores, labels, strict=True) if not y]
    wins = sum(1.0 if p > n else 0.5 if p == n else 0.0 for p, n in itertools.product(pos, neg))
    return wins / (len(pos) * len(neg))


def test_the_hand_computed_example() -> None:
    # positives 0.35, 0.8; negatives 0.1, 0.4: of the 4 pairs, 0.35 < 0.4 loses, the others win
    assert roc_auc([0.1, 0.4, 0.35, 0.8], [False, False, True, True]) == 0.75


def test_closed_forms() -> None:
    assert roc_auc([1, 2, 3, 4], [False, False, True, True]) == 1.0  # perfectly separated
    assert roc_auc([4, 3, 2, 1], [False, False, True, True]) == 0.0  # perfectly reversed
    assert roc_auc([5, 5, 5, 5, 5], [True, False, True, False, False]) == 0.5  # all tied
    # one tie between a positive and a negative, the rest separated: (n1 n0 - 1/2) / (n1 n0)
    assert roc_auc([1, 2, 3, 3, 4], [False, False, False, True, True]) == pytest.approx(5.5 / 6)
    assert math.isnan(roc_auc([1, 2], [True, True]))  # one class only


def test_equals_the_pairwise_definition_with_ties_and_missing_values() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        n = int(rng.integers(2, 30))
        s = rng.integers(0, 5, n).astype(float)
        s[rng.random(n) < 0.2] = -math.inf  # missing: lowest, tied with each other
        y = rng.random(n) < 0.5
        if y.all() or not y.any():
            continue
        assert roc_auc(s, y) == pytest.approx(_pairwise(list(s), list(y)))


def test_bootstrap_is_seeded_and_brackets_the_estimate() -> None:
    rng = np.random.default_rng(1)
    s = rng.normal(size=60)
    y = s + rng.normal(size=60) > 0
    low, high = bootstrap_ci(s, y, resamples=500)
    assert (low, high) == bootstrap_ci(s, y, resamples=500)
    assert low < roc_auc(s, y) < high <= 1.0
    assert bootstrap_ci(s, y, resamples=500, seed=2) != (low, high)
    assert all(math.isnan(v) for v in bootstrap_ci([1.0, 2.0], [True, True]))


def test_missing_measure_values_score_lowest_and_missing_outcomes_are_left_out() -> None:
    rows = [
        {
            "tvmmp": 0.2,
            "alpha": [[0.3, 0.2]],
            "force_closure": True,
            "sim_hold": True,
            "sim_speed_success": True,
        },
        {
            "tvmmp": None,
            "alpha": [[None, 0.1]],
            "force_closure": False,
            "sim_hold": False,
            "sim_speed_success": None,
        },
        {
            "tvmmp": 0.1,
            "alpha": [[0.1, 0.4]],
            "epsilon_l1": 0.5,
            "sim_hold": False,
            "sim_speed_success": False,
        },
        {"tvmmp": None, "alpha": None, "sim_hold": None, "sim_speed_success": None},  # a failed grasp
    ]
    assert auc_scores(rows[1])["tvmmp"] == -math.inf and auc_scores(rows[1])["alpha_l0"] == -math.inf
    assert auc_scores(rows[0])["force_closure"] == 1.0
    table = {(r["measure"], r["target"]): r for r in auc_table(rows, resamples=50)}
    assert all(set(r) == set(AUC_COLUMNS) for r in table.values())
    hold = table["tvmmp", "sim_hold"]
    assert (hold["positives"], hold["negatives"], hold["excluded"], hold["missing"]) == (1, 2, 1, 1)
    assert hold["auc"] == 1.0  # 0.2 above 0.1 and above the infeasible grasp
    assert table["alpha_l1", "sim_hold"]["auc"] == 0.5  # 0.2 above 0.1, below 0.4
    assert table["epsilon_l1", "sim_hold"]["auc"] == 0.25  # missing (lowest) for the positive
    assert table["tvmmp", "sim_speed_success"]["excluded"] == 2
    assert "AUC vs sim_hold (1 succeed, 2 fail, 1 not simulated): tvmmp 1.000" in auc_summary(
        list(table.values())
    )
