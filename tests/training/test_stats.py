"""The intervals: over seeds then scenarios when seeds are pooled, never narrower than Wilson's, paired for
comparisons, never negative ratios."""

from __future__ import annotations

import math

import numpy as np
import pytest

from training.stats import (
    cluster_bootstrap,
    paired_bootstrap,
    seeded_success_interval,
    sign_test,
    success_interval,
    wilson,
)


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


def test_seeds_that_disagree_widen_the_interval_over_seeds_then_scenarios() -> None:
    # the audit's case: three seeds on 300 scenarios at 0.3 %, 24 % and 0 %, published as 8.1 % [6.4, 9.8]
    outcomes = np.zeros((3, 300))
    outcomes[0, :1] = 1.0
    outcomes[1, ::4] = 1.0  # 75 of 300
    low, high = seeded_success_interval(outcomes)
    assert low == 0.0 and high > 0.2  # the seeds' spread, not only the scenarios'
    *_, pooled_high = cluster_bootstrap(list(outcomes.sum(axis=0)), [3.0] * 300)
    assert pooled_high < 0.15  # what holding the networks fixed gave
    assert seeded_success_interval(outcomes) == (low, high)  # deterministic


def test_a_pooled_interval_is_never_narrower_than_wilsons_of_the_same_counts() -> None:
    outcomes = np.zeros((3, 20))
    outcomes[0, 0] = 1.0  # 1 success in 60 episodes
    low, high = seeded_success_interval(outcomes)
    w_low, w_high = wilson(1, 60)
    assert low <= w_low and high >= w_high
    missing = outcomes.copy()
    missing[2, 10:] = np.nan  # a seed that did not run half the scenarios: 50 episodes
    low, high = seeded_success_interval(missing)
    assert low <= wilson(1, 50)[0] and high >= wilson(1, 50)[1]
    assert seeded_success_interval(outcomes[:1]) == wilson(1, 20)  # one seed: Wilson over its scenarios
