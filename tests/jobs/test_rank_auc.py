"""The ROC AUC of ``mjtvm rank --verify`` (mjtvm.jobs.rank_auc): hand-computed and closed forms."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from mjtvm.errors import ParamError
from mjtvm.jobs import rank_auc
from mjtvm.jobs.rank_auc import AUC_COLUMNS, auc_scores, auc_summary, auc_table, bootstrap_ci, roc_auc


def _pairwise(scores: list[float], labels: list[bool]) -> float:
    """The Mann-Whitney statistic by its definition: every (positive, negative) pair."""
    pos = [s for s, y in zip(scores, labels, strict=True) if y]
    neg = [s for s, y in zip(scores, labels, strict=True) if not y]
    wins = sum(1.0 if p > n else 0.5 if p == n else 0.0 for p, n in itertools.product(pos, neg))
    return wins / (len(pos) * len(neg))


def _reference_auc(scores: np.ndarray, labels: np.ndarray, weights: np.ndarray) -> float:
    """The AUC as computed before the resamples were vectorized: one resample at a time."""
    u, inv = np.unique(scores, return_inverse=True)
    pos = np.bincount(inv, weights * labels, minlength=len(u))
    neg = np.bincount(inv, weights * ~labels, minlength=len(u))
    n1, n0 = pos.sum(), neg.sum()
    if n1 == 0 or n0 == 0:
        return math.nan
    below = np.cumsum(neg) - neg
    return float((pos * (below + 0.5 * neg)).sum() / (n1 * n0))


def _reference_bootstrap(scores: np.ndarray, labels: np.ndarray, resamples: int, seed: int = 0) -> np.ndarray:
    """Every resample's AUC as drawn before: one ``rng.integers(0, n, n)`` per resample."""
    rng = np.random.default_rng(seed)
    n = len(scores)
    return np.array(
        [
            _reference_auc(scores, labels, np.bincount(rng.integers(0, n, n), minlength=n).astype(float))
            for _ in range(resamples)
        ]
    )


def _reference_ci(scores: np.ndarray, labels: np.ndarray, resamples: int) -> tuple[float, float]:
    values = _reference_bootstrap(scores, labels, resamples)
    values = values[~np.isnan(values)]
    low, high = np.percentile(values, [2.5, 97.5])
    return float(low), float(high)


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


def test_hand_computed_ties_and_multiplicities() -> None:
    s = np.array([1.0, 2.0, 2.0, 3.0])
    y = np.array([False, False, True, True])
    # pairs (positive, negative): 2>1, 2=2 (1/2), 3>1, 3>2: 3.5 / 4
    assert roc_auc(s, y) == 0.875
    counts = np.array([[1, 1, 1, 1], [2, 0, 1, 1], [0, 3, 1, 2], [1, 1, 0, 0]], dtype=np.int32)
    aucs = rank_auc._aucs(s, y, counts)
    # [2,0,1,1]: both positives above the two copies of 1: 4/4. [0,3,1,2]: the 2 ties the three
    # negatives 2 (3 halves), the two 3s beat them (6 wins): 7.5/9. [1,1,0,0]: no positive
    assert list(aucs[:3]) == [0.875, 1.0, 7.5 / 9] and math.isnan(aucs[3])


@pytest.mark.parametrize("n", [1, 2, 13, 200, 50020])
def test_resample_counts_are_the_per_resample_draws(n: int) -> None:
    # n = 50020 (2^32 mod n = 50016, near n): numpy's bounded draw rejects and redraws a few
    # times (11) in these 20 resamples, so the shared stream is checked through rejections too
    resamples = 20 if n > 1000 else 300
    rng = np.random.default_rng(5)
    old = np.stack([np.bincount(rng.integers(0, n, n), minlength=n) for _ in range(resamples)])
    rng = np.random.default_rng(5)
    first = rank_auc._resample_counts(rng, n, resamples // 3)
    rest = rank_auc._resample_counts(rng, n, resamples - resamples // 3)
    assert np.array_equal(np.vstack([first, rest]), old)


def test_every_resampled_auc_and_interval_equals_the_one_resample_at_a_time_path() -> None:
    rng = np.random.default_rng(11)
    for case in range(12):
        n = int(rng.integers(2, 90))
        s = rng.integers(0, 6, n).astype(float) if case % 2 else rng.normal(size=n)
        s[rng.random(n) < 0.2] = -math.inf
        if case == 5:
            s[rng.random(n) < 0.3] = math.nan  # not a score rank_auc makes, but ordered the same
        y = rng.random(n) < 0.4
        if y.all() or not y.any():
            continue
        resamples = 400
        old = _reference_bootstrap(s, y, resamples)
        new = rank_auc._aucs(s, y, rank_auc._resample_counts(np.random.default_rng(0), n, resamples))
        np.testing.assert_array_equal(np.isnan(new), np.isnan(old))
        np.testing.assert_allclose(new, old, rtol=0.0, atol=1e-12, equal_nan=True)
        assert roc_auc(s, y) == pytest.approx(_reference_auc(s, y, np.ones(n)), abs=1e-12)
        low, high = bootstrap_ci(s, y, resamples=resamples)
        ref = _reference_ci(s, y, resamples)
        assert abs(low - ref[0]) <= 1e-12 and abs(high - ref[1]) <= 1e-12


def test_the_table_equals_one_measure_at_a_time_across_blocks(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(4)
    rows = [
        {
            "tvmmp": None if rng.random() < 0.2 else round(float(rng.random()), 1),
            "alpha": [[float(v) for v in rng.random(3)] for _ in range(2)],
            "force_closure": bool(rng.random() < 0.6),
            "sim_hold": None if rng.random() < 0.1 else bool(rng.random() < 0.5),
            "sim_speed_success": None if rng.random() < 0.3 else bool(rng.random() < 0.5),
        }
        for _ in range(40)
    ]
    whole = auc_table(rows, resamples=300)
    monkeypatch.setattr(rank_auc, "_BLOCK", 7 * 40)  # about 7 resamples a block
    blocks = auc_table(rows, resamples=300)
    assert whole == blocks
    for r in whole:
        known = [row for row in rows if row[r["target"]] is not None]
        s = np.array([auc_scores(row)[r["measure"]] for row in known])
        y = np.array([bool(row[r["target"]]) for row in known])
        assert r["auc"] == pytest.approx(_pairwise(list(s), list(y)), abs=1e-12)
        low, high = _reference_ci(s, y, 300)
        assert abs(r["ci_low"] - low) <= 1e-12 and abs(r["ci_high"] - high) <= 1e-12


def test_bootstrap_is_seeded_and_brackets_the_estimate() -> None:
    rng = np.random.default_rng(1)
    s = rng.normal(size=60)
    y = s + rng.normal(size=60) > 0
    low, high = bootstrap_ci(s, y, resamples=500)
    assert (low, high) == bootstrap_ci(s, y, resamples=500)
    assert low < roc_auc(s, y) < high <= 1.0
    assert bootstrap_ci(s, y, resamples=500, seed=2) != (low, high)
    assert all(math.isnan(v) for v in bootstrap_ci([1.0, 2.0], [True, True]))
    with pytest.raises(ParamError, match="one score and one label a grasp"):
        bootstrap_ci([1.0, 2.0, 3.0], [True, False])


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
