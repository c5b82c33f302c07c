"""Methods and their training seeds in the records, and the paired comparison of two methods.

A *method* is what a table ranks: a policy label, with its training seeds pooled. A
record's method and seed are its ``baseline`` and ``training_seed`` fields when it has
them (``fetchcarry reproduce``'s records), else its policy label read as ``NAME-sSEED``
(``bc-mlp-s2`` is method ``bc-mlp``, seed 2; ``expert`` is method ``expert``, no seed):
:func:`training.evaluation.results.method_of`, by which a results file also holds each
episode (split, seed, method and training seed) once.

:func:`compare` pairs two methods on the scenarios both ran (same split, seed and
digest): per scenario, each method's success rate over its seeds and its mean cost over
the seeds that succeeded; the paired bootstrap (:func:`training.stats.paired_bootstrap`)
of the success difference over the common scenarios, and of the cost difference over
the scenarios both solved; and the sign of the success difference over training seeds
(seed ``i`` of A against seed ``i`` of B; against a single run, one pair: A's seeds
averaged, so that one run is counted once) with its two-sided sign-test p-value.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from training.errors import BenchmarkError
from training.evaluation.results import SEED_SUFFIX, method_of
from training.stats import paired_bootstrap, sign_test

__all__ = [
    "SEED_SUFFIX",
    "Comparison",
    "compare",
    "compare_methods",
    "grouped",
    "method_of",
    "methods_by_split",
    "pooled",
]


def pooled(records: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """``records`` with ``policy`` set to the method (seeds pooled) and ``training_seed`` to the seed."""
    out = []
    for record in records:
        method, seed = method_of(record)
        out.append({**record, "policy": method, "training_seed": seed})
    return out


def methods_by_split(records: Sequence[dict[str, Any]]) -> dict[str, dict[str, list[dict[str, Any]]]]:
    """split -> method -> its :func:`pooled` records, in the order they first appear: one pass over ``records``."""
    return grouped(pooled(records))


def grouped(pooled_records: Sequence[dict[str, Any]]) -> dict[str, dict[str, list[dict[str, Any]]]]:
    """split -> method -> records of ``pooled_records`` (already :func:`pooled`), in the order they first appear."""
    table: dict[str, dict[str, list[dict[str, Any]]]] = {}
    for record in pooled_records:
        table.setdefault(record["split"], {}).setdefault(record["policy"], []).append(record)
    return table


@dataclass(frozen=True)
class Comparison:
    """Method ``a`` against method ``b`` on one split, paired on the same scenarios (A minus B)."""

    a: str
    b: str
    split: str
    scenarios: int  # scenarios both ran
    success_a: float  # mean success over the common scenarios (seeds pooled)
    success_b: float
    success_diff: float  # mean of A's minus B's per-scenario success rate
    success_low: float  # 95 % paired bootstrap interval over scenarios
    success_high: float
    solved_both: int  # scenarios both solved at least once (the cost difference's)
    cost_diff: float  # metres: mean of A's minus B's per-scenario mean cost of successes
    cost_low: float
    cost_high: float
    seeds: int  # seed pairs compared
    seed_wins: int  # pairs where A's success rate is higher
    seed_losses: int
    sign_p: float  # two-sided sign test over the seed pairs (ties left out)

    def line(self) -> str:
        """One line of text: the differences with their intervals and the sign over seeds."""
        cost = (
            "-"
            if math.isnan(self.cost_diff)
            else f"{self.cost_diff:+.3f} m [{self.cost_low:+.3f}, {self.cost_high:+.3f}]"
        )
        return (
            f"{self.a} - {self.b} on {self.split} ({self.scenarios} scenarios): success "
            f"{100 * self.success_diff:+.1f} pts [{100 * self.success_low:+.1f}, {100 * self.success_high:+.1f}] "
            f"({self.success_a:.1%} vs {self.success_b:.1%}); cost {cost} on {self.solved_both} solved by both; "
            f"seeds {self.seed_wins} up, {self.seed_losses} down of {self.seeds} (sign test p = {self.sign_p:.3g})"
        )


def _per_scenario(records: list[dict[str, Any]]) -> dict[tuple[int, Any], list[dict[str, Any]]]:
    out: dict[tuple[int, Any], list[dict[str, Any]]] = {}
    for r in records:
        out.setdefault((r["seed"], r.get("digest")), []).append(r)
    return out


def _rate(group: list[dict[str, Any]]) -> float:
    return sum(r["success"] for r in group) / len(group)


def _cost(group: list[dict[str, Any]]) -> float | None:
    costs = [r["cost"] for r in group if r["success"]]
    return sum(costs) / len(costs) if costs else None


def compare(records: Sequence[dict[str, Any]], a: str, b: str, split: str) -> Comparison:
    """Method ``a`` against ``b`` on ``split``; :class:`BenchmarkError` if either is missing or none is shared."""
    return compare_methods(methods_by_split(records).get(split, {}), a, b, split)


def compare_methods(methods: dict[str, list[dict[str, Any]]], a: str, b: str, split: str) -> Comparison:
    """:func:`compare` on one split's records grouped by method (:func:`methods_by_split`), in time linear in them."""
    mine = {m: methods.get(m, []) for m in (a, b)}
    for method, group in mine.items():
        if not group:
            known = ", ".join(methods) or "none"
            raise BenchmarkError(f"no records of {method!r} on {split}; methods there: {known}")
    per_a, per_b = _per_scenario(mine[a]), _per_scenario(mine[b])
    common = [key for key in per_a if key in per_b]
    if not common:
        raise BenchmarkError(f"{a} and {b} share no scenario on {split} (same seed and digest)")
    success = [_rate(per_a[k]) - _rate(per_b[k]) for k in common]
    costs = [(_cost(per_a[k]), _cost(per_b[k])) for k in common]
    cost_diffs = [x - y for x, y in costs if x is not None and y is not None]
    s_mean, s_low, s_high = paired_bootstrap(success)
    c_mean, c_low, c_high = paired_bootstrap(cost_diffs) if cost_diffs else (math.nan,) * 3
    wins, losses, pairs = _seed_signs(mine[a], mine[b], set(common))
    return Comparison(
        a=a,
        b=b,
        split=split,
        scenarios=len(common),
        success_a=sum(_rate(per_a[k]) for k in common) / len(common),
        success_b=sum(_rate(per_b[k]) for k in common) / len(common),
        success_diff=s_mean,
        success_low=s_low,
        success_high=s_high,
        solved_both=len(cost_diffs),
        cost_diff=c_mean,
        cost_low=c_low,
        cost_high=c_high,
        seeds=pairs,
        seed_wins=wins,
        seed_losses=losses,
        sign_p=sign_test(wins, losses),
    )


def _seed_signs(a: list[dict[str, Any]], b: list[dict[str, Any]], common: set) -> tuple[int, int, int]:
    """``(wins, losses, pairs)`` of A's per-seed success rate against B's on the common scenarios."""

    def rates(group: list[dict[str, Any]]) -> list[float]:
        by_seed: dict[Any, list[dict[str, Any]]] = {}
        for r in group:
            if (r["seed"], r.get("digest")) in common:
                by_seed.setdefault(r["training_seed"], []).append(r)
        return [_rate(by_seed[s]) for s in sorted(by_seed, key=lambda s: (s is None, s or 0))]

    ra, rb = rates(a), rates(b)
    if min(len(ra), len(rb)) == 1:  # a single run is one observation: one pair, the other side's seeds averaged
        ra, rb = [sum(ra) / len(ra)], [sum(rb) / len(rb)]
    pairs = list(zip(ra, rb, strict=False))
    return sum(x > y for x, y in pairs), sum(x < y for x, y in pairs), len(pairs)
