"""The benchmark's figures, per policy and split, from the episode records.

Every figure compares a policy with the MILP expert *on the same scenarios*:

- success rate, with a 95 % Wilson score interval (:func:`wilson`);
- objects delivered per episode;
- cost ratio: the policy's travel cost over the expert's on the same scenario, averaged
  over the episodes both solved (a 95 % interval of that mean, normal approximation);
- SPL-style cost-weighted success, averaged over episodes the expert solved:
  ``success * expert_cost / max(cost, expert_cost)`` (:func:`spl`; Anderson et al.'s
  SPL with path length replaced by the paper's travel cost);
- phases and pushes per episode, next to the expert's on the same scenarios;
- invalid actions and contacts per episode;
- time per decision, next to the planner's (the expert's time per decision), and the
  time of the action masks the policy is given, apart;
- the normalised score ``100 * (R - R_random) / (R_expert - R_random)``, ``R`` the mean
  episode return (the paper's reward summed) over the split.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from training.resolve import EXPERT, RANDOM
from training.stats import Z_95, wilson


def spl(success: bool, cost: float, expert_cost: float) -> float:
    """Success weighted by the expert's cost over ``max(cost, expert_cost)`` (1 for a success at the expert's cost)."""
    if not success:
        return 0.0
    longest = max(cost, expert_cost)
    return 1.0 if longest <= 0 else expert_cost / longest


def mean_interval(values: list[float]) -> tuple[float, float, float]:
    """The mean of ``values`` and its 95 % interval (normal approximation; nan for fewer than two values)."""
    if not values:
        return (math.nan, math.nan, math.nan)
    mean = float(np.mean(values))
    if len(values) < 2:
        return (mean, math.nan, math.nan)
    half = Z_95 * float(np.std(values, ddof=1)) / math.sqrt(len(values))
    return (mean, mean - half, mean + half)


@dataclass(frozen=True)
class Row:
    """One policy on one split (means are per episode)."""

    policy: str
    split: str
    episodes: int
    success: float
    success_low: float  # 95 % Wilson interval
    success_high: float
    delivered: float  # objects delivered per episode
    objects: float  # objects per episode
    cost_ratio: float  # mean cost / expert cost over episodes both solved
    cost_ratio_low: float
    cost_ratio_high: float
    spl: float  # cost-weighted success, over episodes the expert solved
    phases: float
    expert_phases: float  # the expert's on the same scenarios
    pushes: float
    expert_pushes: float
    invalid_actions: float
    contacts: float
    decision_ms: float  # mean time of the policy's predict per decision
    mask_ms: float  # mean time of the env's action masks per decision
    planner_ms: float  # the expert's time per decision on the same scenarios
    score: float  # 100 (R - R_random) / (R_expert - R_random); nan if the expert and random tie


def fill_expert_costs(records: list[dict[str, Any]]) -> None:
    """Set every record's ``expert_cost`` to the expert's cost on the same scenario (``None`` if it failed)."""
    costs = {(r["split"], r["seed"]): r["cost"] if r["success"] else None for r in records if r["policy"] == EXPERT}
    for record in records:
        record["expert_cost"] = costs.get((record["split"], record["seed"]))


def _mean(values: Iterable[float]) -> float:
    values = list(values)
    return float(np.mean(values)) if values else math.nan


def summarise(records: list[dict[str, Any]]) -> list[Row]:
    """One :class:`Row` per policy and split, in the order they first appear in ``records``."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for record in records:
        groups.setdefault((record["policy"], record["split"]), []).append(record)
    return [_row(policy, split, group, groups) for (policy, split), group in groups.items()]


def _row(policy: str, split: str, group: list[dict], groups: dict[tuple[str, str], list[dict]]) -> Row:
    expert = {r["seed"]: r for r in groups.get((EXPERT, split), [])}
    random = groups.get((RANDOM, split), [])
    wins = sum(r["success"] for r in group)
    low, high = wilson(wins, len(group), Z_95)
    ratios = [r["cost"] / r["expert_cost"] for r in group if r["success"] and (r["expert_cost"] or 0) > 0]
    ratio, ratio_low, ratio_high = mean_interval(ratios)
    weighted = [spl(r["success"], r["cost"], r["expert_cost"]) for r in group if r["expert_cost"] is not None]
    same = [expert[r["seed"]] for r in group if r["seed"] in expert]
    r_policy, r_expert, r_random = (_mean(r["return"] for r in g) for g in (group, same, random))
    span = r_expert - r_random
    return Row(
        policy=policy,
        split=split,
        episodes=len(group),
        success=wins / len(group),
        success_low=low,
        success_high=high,
        delivered=_mean(r["delivered"] for r in group),
        objects=_mean(r["objects"] for r in group),
        cost_ratio=ratio,
        cost_ratio_low=ratio_low,
        cost_ratio_high=ratio_high,
        spl=_mean(weighted),
        phases=_mean(r["phases"] for r in group),
        expert_phases=_mean(r["phases"] for r in same),
        pushes=_mean(r["pushes"] for r in group),
        expert_pushes=_mean(r["pushes"] for r in same),
        invalid_actions=_mean(r["invalid_actions"] for r in group),
        contacts=_mean(r["contacts"] for r in group),
        decision_ms=_mean(r["decision_ms"] for r in group),
        mask_ms=_mean(r.get("mask_ms", 0.0) for r in group),
        planner_ms=_mean(r["decision_ms"] for r in same),
        score=100.0 * (r_policy - r_random) / span if abs(span) > 1e-12 else math.nan,
    )
