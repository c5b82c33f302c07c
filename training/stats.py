"""Interval estimates for the evaluations: the Wilson score interval, clustered and paired bootstraps, the sign test.

Pure arithmetic (no env, no policy), so that learners measuring their held-out success
and the benchmark's metrics share one definition. The benchmark's episodes are not
independent trials: several training seeds of one method run on the same scenarios and
their failures cluster by scenario, so every interval over pooled seeds resamples
scenarios (clusters), and comparisons of two methods are paired on the same scenarios.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.stats import binomtest, bootstrap

Z_95 = 1.96  # the normal quantile of a two-sided 95 % interval


def wilson(successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """The Wilson score interval of a success rate (95 % with the default ``z``)."""
    if n == 0:
        return (math.nan, math.nan)
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    # min/max with p: at 0 % or 100 % rounding can put an end a hair past p, which the interval contains
    return (min(p, max(0.0, centre - half)), max(p, min(1.0, centre + half)))


BOOTSTRAP_RESAMPLES = 2000  # resamples of every bootstrap interval
BOOTSTRAP_SEED = 0  # the resampling's seed: the same records give the same interval


def cluster_bootstrap(
    sums: Sequence[float], counts: Sequence[float], level: float = 0.95
) -> tuple[float, float, float]:
    """A ratio of sums over clusters and its percentile bootstrap interval, resampling whole clusters.

    Cluster ``i`` (a scenario) holds ``counts[i]`` values (one per training seed that has
    one) summing to ``sums[i]``; the estimate is ``sum(sums) / sum(counts)``, the mean over
    every value, and the interval resamples scenarios with replacement, each with all its
    seeds' values (scipy.stats.bootstrap, paired, percentile method), so that values of
    one scenario are never taken for independent trials. Clusters with a count of 0 are
    left out. ``(estimate, nan, nan)`` with fewer than two clusters; ``(nan, nan, nan)``
    with none. The interval lies within the values' range (a ratio of costs is never
    negative).
    """
    pairs = [(s, c) for s, c in zip(sums, counts, strict=True) if c > 0]
    if not pairs:
        return (math.nan, math.nan, math.nan)
    total, weight = np.array(pairs, dtype=float).T
    estimate = float(total.sum() / weight.sum())
    if len(pairs) < 2:
        return (estimate, math.nan, math.nan)
    means = total / weight
    if np.ptp(means) == 0:
        return (estimate, estimate, estimate)

    def statistic(s: np.ndarray, c: np.ndarray, axis: int = -1) -> np.ndarray:
        return np.sum(s, axis=axis) / np.sum(c, axis=axis)

    result = bootstrap(
        (total, weight),
        statistic,
        paired=True,
        vectorized=True,
        n_resamples=BOOTSTRAP_RESAMPLES,
        confidence_level=level,
        method="percentile",
        rng=np.random.default_rng(BOOTSTRAP_SEED),
    )
    low, high = result.confidence_interval
    return (estimate, min(estimate, float(low)), max(estimate, float(high)))


def success_interval(sums: Sequence[float], counts: Sequence[float], z: float = Z_95) -> tuple[float, float]:
    """The 95 % interval of a success rate over scenarios (``sums[i]`` successes of ``counts[i]`` episodes).

    One episode per scenario (one training seed): the Wilson interval. Several (seeds
    pooled): the clustered bootstrap (:func:`cluster_bootstrap`), widened to hold the
    Wilson interval of the same counts (:func:`at_least_wilson`).
    """
    scenarios = sum(1 for c in counts if c > 0)
    wins, n = float(sum(sums)), float(sum(counts))
    if scenarios == 0:
        return (math.nan, math.nan)
    if n == scenarios:
        return wilson(round(wins), scenarios, z)
    estimate, low, high = cluster_bootstrap(sums, counts)
    return _spread_or_scenarios((low, high), estimate, scenarios, round(wins), round(n), z)


def _spread_or_scenarios(
    interval: tuple[float, float], estimate: float, scenarios: int, wins: int, n: int, z: float
) -> tuple[float, float]:
    """A bootstrap ``interval`` of a pooled rate, widened to hold Wilson's interval of ``wins`` in ``n``; where the
    bootstrap has no spread (every scenario at the same rate, all solved say), Wilson's interval at the number of
    scenarios: the effective n of clustered trials at its smallest."""
    low, high = interval
    if math.isnan(low) or low == high:
        return wilson(round(estimate * scenarios), scenarios, z)
    return at_least_wilson(interval, wins, n, z)


def seeded_success_interval(outcomes: np.ndarray, z: float = Z_95) -> tuple[float, float]:
    """The 95 % interval of a success rate from a (training seeds x scenarios) table of outcomes (nan: not run).

    One training seed: :func:`success_interval` over its scenarios. Several: the two-stage
    bootstrap (:func:`seeds_then_scenarios`), widened to hold the Wilson interval of the
    same counts, so that a rate measured on few seeds that disagree gets the width their
    disagreement asks for, and never less than its counts alone would.
    """
    ran = ~np.isnan(outcomes)
    if outcomes.shape[0] == 1:
        row = outcomes[0][ran[0]]
        return success_interval(list(row), [1.0] * len(row), z)
    estimate, low, high = seeds_then_scenarios(outcomes)
    scenarios = int(ran.any(axis=0).sum())
    wins, n = round(float(np.nansum(outcomes))), int(ran.sum())
    return _spread_or_scenarios((low, high), estimate, scenarios, wins, n, z)


def at_least_wilson(interval: tuple[float, float], successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """``interval`` widened to hold the Wilson interval of ``successes`` in ``n`` (a nan end is Wilson's)."""
    w_low, w_high = wilson(successes, n, z)
    low, high = interval
    return (w_low if math.isnan(low) else min(low, w_low), w_high if math.isnan(high) else max(high, w_high))


def seeds_then_scenarios(values: np.ndarray, level: float = 0.95) -> tuple[float, float, float]:
    """The mean of a (training seeds x scenarios) table and its two-stage percentile bootstrap interval.

    ``values[i, j]`` is training seed ``i``'s value on scenario ``j`` (nan where it did not
    run). Each resample draws the seeds with replacement, then the scenarios with
    replacement (one draw for every seed: a scenario's seeds stay together), and takes
    the mean of the drawn cells that ran: the interval covers what varies between
    training runs as well as between scenarios. ``(estimate, nan, nan)`` with fewer than
    two scenarios.
    """
    ran = ~np.isnan(values)
    estimate = float(np.nanmean(values)) if ran.any() else math.nan
    seeds, scenarios = values.shape
    if scenarios < 2 or not ran.any():
        return (estimate, math.nan, math.nan)
    filled = np.where(ran, values, 0.0)
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    rows = rng.integers(0, seeds, (BOOTSTRAP_RESAMPLES, seeds, 1))
    columns = rng.integers(0, scenarios, (BOOTSTRAP_RESAMPLES, 1, scenarios))
    totals = filled[rows, columns].sum(axis=(1, 2))
    counts = ran[rows, columns].sum(axis=(1, 2))
    means = totals[counts > 0] / counts[counts > 0]
    tail = (1.0 - level) / 2.0
    low, high = np.quantile(means, [tail, 1.0 - tail])
    return (estimate, min(estimate, float(low)), max(estimate, float(high)))


def paired_bootstrap(differences: Sequence[float], level: float = 0.95) -> tuple[float, float, float]:
    """The mean of per-scenario ``differences`` (A minus B on the same scenario) and its bootstrap interval."""
    values = [float(d) for d in differences]
    return cluster_bootstrap(values, [1.0] * len(values), level)


def sign_test(wins: int, losses: int) -> float:
    """Two-sided sign-test p-value of ``wins`` against ``losses`` (ties left out); 1 with neither."""
    trials = wins + losses
    return 1.0 if trials == 0 else float(binomtest(wins, trials, 0.5).pvalue)
