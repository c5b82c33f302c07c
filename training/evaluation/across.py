"""The leaderboard's view across splits: IQM of success, probability of improvement and the performance profile.

Per method, a matrix of success rates: one row per training seed (a method without seeds
is one row), one column per split, each rate over the scenarios every method ran on that
split (as the per-split tables rank them). From it (:mod:`training.evaluation.aggregate`,
Agarwal et al. 2021):

- the IQM of every (seed, split) rate, with a stratified-bootstrap interval (seeds
  resampled within each split);
- the probability of improvement over a reference method (``greedy`` when it ran, else
  the method with the highest IQM): per split, the chance that a seed of the method has a
  higher rate than a seed of the reference, ties half, averaged over the splits;
- the performance profile at a few thresholds: the share of (seed, split) rates above each.

Only the splits every method ran count, and only methods that ran all of them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from training.evaluation.aggregate import iqm, performance_profile, probability_of_improvement, stratified_bootstrap
from training.evaluation.compare import grouped, pooled
from training.evaluation.leaderboard import scenario_key, shared_scenarios

PROFILE_TAUS = (0.5, 0.75, 0.9)  # success rates the profile is shown at
REFERENCE = "greedy"  # the method others are compared with, when it ran


@dataclass(frozen=True)
class AcrossRow:
    """One method across the splits: runs (seeds), IQM with its interval, mean, P(> reference), profile."""

    method: str
    runs: int
    iqm: float
    iqm_low: float
    iqm_high: float
    mean: float
    improvement: float  # P(method > reference); 0.5 for the reference itself
    improvement_low: float
    improvement_high: float
    profile: tuple[float, ...]  # share of (seed, split) success rates above each of PROFILE_TAUS


@dataclass(frozen=True)
class Across:
    """The rows, ranked by IQM, the splits they span, the reference, and the methods left out (a split missing)."""

    splits: tuple[str, ...]
    reference: str
    rows: tuple[AcrossRow, ...]
    left_out: tuple[str, ...]


def success_matrices(records: Sequence[dict[str, Any]]) -> tuple[tuple[str, ...], dict[str, np.ndarray], list[str]]:
    """The splits every kept method ran, each kept method's (seeds, splits) success rates, and the methods left out.

    A rate is over the scenarios every method of the split ran, as its table ranks them
    (:func:`training.evaluation.leaderboard.shared_scenarios`).
    """
    table = grouped(pooled(records))
    splits = tuple(table)
    methods = list(dict.fromkeys(m for by_method in table.values() for m in by_method))
    kept = [m for m in methods if all(m in table[s] for s in splits)]
    rates: dict[str, dict[Any, list[float]]] = {m: {} for m in kept}
    for column, split in enumerate(splits):
        shared, _ = shared_scenarios(split, table[split])
        for method in kept:
            by_seed: dict[Any, list[bool]] = {}
            for r in table[split][method]:
                if scenario_key(r) in shared:
                    by_seed.setdefault(r["training_seed"], []).append(bool(r["success"]))
            for seed, outcomes in by_seed.items():
                rates[method].setdefault(seed, [np.nan] * len(splits))[column] = float(np.mean(outcomes))
    matrices = {m: np.array([row for row in rates[m].values() if not np.isnan(row).any()]) for m in kept}
    return splits, {m: x for m, x in matrices.items() if x.size}, [m for m in methods if m not in kept]


def across_splits(records: Sequence[dict[str, Any]]) -> Across | None:
    """The view of the module docstring; None with fewer than two splits or no method that ran them all."""
    splits, matrices, left_out = success_matrices(records)
    if len(splits) < 2 or not matrices:
        return None
    reference = REFERENCE if REFERENCE in matrices else max(matrices, key=lambda m: iqm(matrices[m]))
    base = matrices[reference]
    rows = []
    for method, scores in matrices.items():
        improvement = probability_of_improvement(scores, base)
        low, high = stratified_bootstrap(probability_of_improvement, (scores, base))
        iqm_interval = stratified_bootstrap(iqm, (scores,))
        profile = tuple(performance_profile(scores, PROFILE_TAUS).tolist())
        rows.append(
            AcrossRow(
                method, len(scores), iqm(scores), *iqm_interval, float(np.mean(scores)), improvement, low, high, profile
            )
        )
    rows.sort(key=lambda row: (-row.iqm, row.method))
    return Across(splits, reference, tuple(rows), tuple(left_out))


def across_markdown(across: Across) -> list[str]:
    """The section's lines: a table of :class:`AcrossRow` and what its columns mean."""
    taus = " / ".join(f"{tau:.0%}" for tau in PROFILE_TAUS)
    lines = [
        f"## Across splits ({len(across.splits)}: {', '.join(across.splits)})",
        "",
        f"| method | seeds | IQM success [95 % CI] | mean success | P(method > {across.reference}) [95 % CI] | "
        f"profile: share of rates above {taus} |",
        "| --- " * 6 + "|",
    ]
    for row in across.rows:
        profile = " / ".join(f"{share:.2f}" for share in row.profile)
        lines.append(
            f"| {row.method} | {row.runs} | {row.iqm:.1%} [{row.iqm_low:.1%}, {row.iqm_high:.1%}] | {row.mean:.1%} | "
            f"{row.improvement:.2f} [{row.improvement_low:.2f}, {row.improvement_high:.2f}] | {profile} |"
        )
    lines += [
        "",
        "- A method's success rates form one row per training seed and one column per split (each rate on the "
        "scenarios every method ran there). IQM: the mean of the middle half of those rates; its interval a "
        "stratified bootstrap (seeds resampled within each split, 2,000 times): a method of one seed has none. "
        f"P(method > {across.reference}): per split, the chance a seed of the method has a higher rate than a seed "
        f"of {across.reference} (ties half), averaged over the splits. Profile: the share of the method's rates "
        "above each threshold (Agarwal et al. 2021, as the rliable package computes them).",
    ]
    if across.left_out:
        lines.append(f"- Left out (not run on every split): {', '.join(across.left_out)}.")
    return [*lines, ""]
