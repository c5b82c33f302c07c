"""The intervals: clustered over scenarios when seeds are pooled, paired for comparisons, never negative ratios."""

from __future__ import annotations

import math

import pytest

from training.stats import cluster_bootstrap, paired_bootstrap, sign_test, success_interval, wilson


def test_clustered_failures_widen_the_interval_to_the_scenarios_n() -> None:
    # three seeds on 100 scenarios, the same 5 scenarios failed by every seed: 100 trials, not 300
    sums, counts = [0.0] * 5 + [3.0] * 95, [3.0] * 100
    low, high = success_interval(sums, counts)
    pooled_low, pooled_high = wilson(285, 300)
    assert high - low > 1.3 * (pooled_high - pooled_low)
    assert (low, high) == pytest.approx(wilson(95, 100), abs=0.03)  # about the Wilson interval at n = 100


def test_one_episode_per_scenario_is_the_wilson_interval_and_all_solved_is_not_zero_width() -> None:
    assert success_interval([1.0] * 95 + [0.0] * 5, [1.0] * 100) == wilson(95, 100)
    low, high = success_interval([3.0] * 100, [3.0] * 100)  # every seed solved everything: no bootstrap spread
    assert high == 1.0 and low == pytest.approx(wilson(100, 100)[0])


def test_a_ratio_interval_is_within_the_values_and_deterministic() -> None:
    sums = [0.9, 1.1, 2.5, 1.0, 7.0, 1.2]
    counts = [1.0] * 6
    estimate, low, high = cluster_bootstrap(sums, counts)
    assert 0.9 <= low <= estimate <= high <= 7.0
    assert cluster_bootstrap(sums, counts) == (estimate, low, high)
    assert math.isnan(cluster_bootstrap([3.0], [1.0])[1])  # one scenario: no interval, not one of zero width
    assert math.isnan(cluster_bootstrap([], [])[0])


def test_paired_differences_and_the_sign_test() -> None:
    mean, low, high = paired_bootstrap([0.0] * 90 + [1.0] * 10)
    assert mean == pytest.approx(0.1) and 0 < low < 0.1 < high
    assert sign_test(3, 0) == pytest.approx(0.25)  # 3 of 3 seeds: two-sided p = 0.25, never "significant"
    assert sign_test(0, 0) == 1.0
