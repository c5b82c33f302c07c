"""Figures across splits, as Agarwal et al. (2021, "Deep RL at the edge of the statistical precipice") define them.

A method's results across splits are a matrix of scores, one row per run (a training
seed) and one column per task (a split), e.g. success rates. From it:

- :func:`iqm`, the interquartile mean: the mean of the middle half of every score
  (``scipy.stats.trim_mean`` cutting a quarter at each end), robust to a few outlying
  runs or splits where the mean is not;
- :func:`performance_profile`: for each threshold ``tau``, the share of scores above it;
- :func:`probability_of_improvement`: per task, the chance that a run of one method
  scores above a run of the other (ties count half: the Mann-Whitney U statistic over the
  pairs), averaged over tasks;
- :func:`stratified_bootstrap`: a percentile interval of any of them, resampling runs
  with replacement within each task (and each method apart).

These are the figures of the ``rliable`` package, which does not import where pandas 3 is
installed (its ``arch`` dependency); ``tests/training/test_aggregate.py`` checks them
against rliable 1.2.0's own numbers on fixed matrices.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.stats import trim_mean

BOOTSTRAP_REPS = 2_000  # repetitions of a stratified bootstrap
BOOTSTRAP_SEED = 0  # its generator's seed: the same interval on every run


def iqm(scores: np.ndarray) -> float:
    """The interquartile mean of every score of a (runs, tasks) matrix."""
    return float(trim_mean(np.asarray(scores, dtype=float), proportiontocut=0.25, axis=None))


def performance_profile(scores: np.ndarray, taus: Sequence[float]) -> np.ndarray:
    """Per threshold of ``taus``, the share of the (runs, tasks) ``scores`` strictly above it."""
    values = np.asarray(scores, dtype=float).reshape(-1)
    return (values[None, :] > np.asarray(taus, dtype=float)[:, None]).mean(axis=1)


def probability_of_improvement(x: np.ndarray, y: np.ndarray) -> float:
    """P(X > Y): per task (column), the share of pairs of a run of ``x`` and a run of ``y`` where ``x`` scores more,
    ties counted half; averaged over the tasks. ``x`` and ``y`` are (runs, tasks) with the same tasks."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.shape[1] != y.shape[1]:
        raise ValueError(f"x and y must have the same tasks (columns), got {x.shape[1]} and {y.shape[1]}")
    above = (x[:, None, :] > y[None, :, :]).mean(axis=(0, 1))
    tied = (x[:, None, :] == y[None, :, :]).mean(axis=(0, 1))
    return float(np.mean(above + 0.5 * tied))


def stratified_bootstrap(
    statistic: Callable[..., float],
    matrices: Sequence[np.ndarray],
    reps: int = BOOTSTRAP_REPS,
    level: float = 0.95,
    seed: int = BOOTSTRAP_SEED,
) -> tuple[float, float]:
    """A percentile interval of ``statistic(*matrices)``: each (runs, tasks) matrix resampled, runs with replacement
    within each task, independently of the others. A matrix of one run gives no spread of its own."""
    rng = np.random.default_rng(seed)
    arrays = [np.asarray(m, dtype=float) for m in matrices]
    values = np.empty(reps)
    for rep in range(reps):
        resampled = [m[rng.integers(0, m.shape[0], size=m.shape), np.arange(m.shape[1])] for m in arrays]
        values[rep] = statistic(*resampled)
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(values, [tail, 100 - tail])
    return float(low), float(high)
