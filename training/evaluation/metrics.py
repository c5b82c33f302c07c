"""The benchmark's figures, per policy and split, from the episode records.

Every figure compares a policy with the MILP expert *on the same scenarios*. The
expert's result on a scenario is its **reference**: for a published split's part
(``iid-v1:test``) the fixed reference shipped with the split
(:mod:`training.evaluation.references`: computed once with a generous planning limit),
never the expert row of this run, whose wall-clock limit moves with the load; for other
scenarios (a folder, a v0 split) the expert row of this run. The expert row of a
published split still runs, and :attr:`Row.disagreements` counts the scenarios where it
did not reproduce its reference (success, or cost to 1 mm).

Episodes of one scenario (several training seeds of a method, pooled under one label)
are one cluster: intervals resample scenarios (:mod:`training.stats`).

- success rate, with a 95 % interval: Wilson with one episode per scenario; with several
  training seeds, the two-stage bootstrap (seeds, then scenarios), never narrower than
  Wilson's interval of the same counts;
- objects delivered per episode;
- cost ratio: the policy's task cost over the reference's on the same scenario,
  averaged over the episodes both solved where the reference travelled at least
  :data:`MIN_RATIO_COST_M`, with a clustered bootstrap interval (never negative; none
  below two scenarios);
- SPL-style cost-weighted success, averaged over episodes the reference solved:
  ``success * reference_cost / max(cost, reference_cost)`` (:func:`spl`; Anderson et
  al.'s SPL with path length replaced by the task cost);
- phases and pushes per episode, next to the reference's on the same scenarios;
- invalid actions and contacts per episode;
- time per decision: the policy's ``predict``, the env's action masks handed to it, and
  the whole step (policy, mask and the env's step), next to the planner's;
- the score (:func:`score`): 0 for doing nothing, 100 for the reference, linear in the
  episode return in between (the env's reward summed: minus the task cost), and a failed
  episode never above a successful one on the same scenario.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from fetchcarry_env.registration import do_nothing_return
from training.evaluation.references import part_references, references_digest
from training.evaluation.splits import SPLITS
from training.resolve import EXPERT
from training.stats import (  # noqa: F401 (Z_95, wilson re-exported: training.benchmark)
    Z_95,
    cluster_bootstrap,
    seeded_success_interval,
    success_interval,
    wilson,
)

RANDOM_PHASES = "random-phases"  # runs beside the expert in every benchmark: uniform over the allowed candidates
COST_AGREES_M = 1e-3  # task cost (its metres of travel and W1 per waiting phase): the expert row agrees within this
MIN_RATIO_COST_M = 1e-3  # metres: a reference that travelled less has no cost ratio (it would be huge, or infinite)


def scored_return(record: dict[str, Any]) -> float:
    """``record``'s return as the score counts it: at least the do-nothing floor for a success, at most it for a
    failure (:func:`fetchcarry_env.registration.do_nothing_return` of its objects)."""
    floor = do_nothing_return(int(record["objects"]))
    return max(record["return"], floor) if record["success"] else min(record["return"], floor)


def score(pairs: Iterable[tuple[dict[str, Any], dict[str, Any]]]) -> float:
    """The score of episodes and their scenarios' references: ``100 * sum(R - F) / sum(R_ref - F)``.

    ``pairs`` holds each episode with its scenario's reference; only references that
    succeeded count. ``F`` is the scenario's do-nothing return (every object waiting all
    the env's phases), ``R`` the episode's :func:`scored_return` and ``R_ref`` the
    reference's return: a policy that does nothing scores 0 and the reference 100; a
    failed episode counts at most ``F`` and a successful one at least ``F``, so that on a
    scenario no failure scores above a success. Linear in the returns otherwise: with
    ``ref_min_score`` the mean ``F`` and ``ref_max_score`` the mean ``R_ref`` of the same
    scenarios, ``minari.get_normalized_score`` gives the same number (divided by 100).
    nan without a successful reference.
    """
    gained = span = 0.0
    for record, reference in pairs:
        if reference is None or not reference["success"]:
            continue
        floor = do_nothing_return(int(record["objects"]))
        gained += scored_return(record) - floor
        span += reference["return"] - floor
    return 100.0 * gained / span if span > 0 else math.nan


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
    success_low: float  # 95 % interval (Wilson, or the two-stage bootstrap over seeds and scenarios)
    success_high: float
    delivered: float  # objects delivered per episode
    objects: float  # objects per episode
    cost_ratio: float  # mean cost / reference cost over episodes both solved
    cost_ratio_low: float  # 95 % clustered bootstrap interval
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
    score: float  # 0 doing nothing, 100 the reference (:func:`score`); nan without a successful reference
    scenarios: int = 0  # distinct scenarios (episodes / scenarios = episodes per scenario, the seeds pooled)
    step_ms: float = math.nan  # mean wall time of a whole step (policy, mask, env step) per decision
    reference: str = "fixed"  # "fixed" (the split's reference file), "expert run" (this run's expert), or "mixed"
    disagreements: int = 0  # the expert row: scenarios where it did not reproduce the fixed reference


def reference_table(records: list[dict[str, Any]]) -> dict[tuple[str, int], dict[str, Any]]:
    """(split, seed) -> the reference of that scenario: the split's fixed reference, else this run's expert.

    Each reference holds ``success``, ``cost``, ``return``, ``phases``, ``pushes``, ``digest``,
    ``fixed`` (from a reference file) and ``references`` (the part's references digest, or None).
    """
    table: dict[tuple[str, int], dict[str, Any]] = {}
    for split in dict.fromkeys(r["split"] for r in records):
        if split in SPLITS and SPLITS[split].part:
            fixed = part_references(split)
            digest = references_digest(fixed) if fixed else None
            table.update({(split, ref["seed"]): {**ref, "fixed": True, "references": digest} for ref in fixed})
    for r in records:
        if r["policy"] == EXPERT and (r["split"], r["seed"]) not in table:
            keys = ("success", "cost", "return", "phases", "pushes", "digest")
            table[(r["split"], r["seed"])] = {**{k: r.get(k) for k in keys}, "fixed": False, "references": None}
    return table


def reference_of(record: dict[str, Any], table: dict[tuple[str, int], dict[str, Any]]) -> dict[str, Any] | None:
    """The reference of ``record``'s scenario in ``table``, if it is the same scenario (digest)."""
    ref = table.get((record["split"], record["seed"]))
    if ref is None or (record.get("digest") is not None and ref["digest"] not in (None, record["digest"])):
        return None
    return ref


def fill_expert_costs(records: list[dict[str, Any]]) -> None:
    """Set every record's ``expert_cost`` (the reference's cost, ``None`` if it failed) and ``references``.

    ``references`` is the digest of the fixed references the cost came from (None: this
    run's expert): what ``fetchcarry leaderboard`` checks before merging folders.
    """
    table = reference_table(records)
    for record in records:
        ref = reference_of(record, table)
        record["expert_cost"] = ref["cost"] if ref is not None and ref["success"] else None
        record["references"] = ref["references"] if ref is not None else None


def _mean(values: Iterable[float]) -> float:
    values = list(values)
    return float(np.mean(values)) if values else math.nan


def summarise(records: list[dict[str, Any]]) -> list[Row]:
    """One :class:`Row` per policy and split, in the order they first appear in ``records``.

    Records of one policy and scenario (split and seed) are one cluster (training seeds
    pooled under one label).
    """
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for record in records:
        groups.setdefault((record["policy"], record["split"]), []).append(record)
    table = reference_table(records)
    return [_row(policy, split, group, groups, table) for (policy, split), group in groups.items()]


def clusters(group: list[dict[str, Any]], value: Any) -> tuple[list[float], list[float]]:
    """Per scenario of ``group``: the sum of ``value(record)`` over its records (None skipped) and their count."""
    sums: dict[int, float] = {}
    counts: dict[int, float] = {}
    for r in group:
        v = value(r)
        sums.setdefault(r["seed"], 0.0)
        counts.setdefault(r["seed"], 0.0)
        if v is not None:
            sums[r["seed"]] += float(v)
            counts[r["seed"]] += 1.0
    return list(sums.values()), list(counts.values())


def outcome_table(group: list[dict[str, Any]]) -> np.ndarray:
    """Successes as a (training seeds x scenarios) table, 1.0 or 0.0 (nan where a seed did not run a scenario).

    A seed that ran a scenario more than once holds its mean there.
    """
    seeds = {s: i for i, s in enumerate(dict.fromkeys(r.get("training_seed") for r in group))}
    scenarios = {s: j for j, s in enumerate(dict.fromkeys(r["seed"] for r in group))}
    totals = np.zeros((len(seeds), len(scenarios)))
    counts = np.zeros_like(totals)
    for r in group:
        cell = (seeds[r.get("training_seed")], scenarios[r["seed"]])
        totals[cell] += float(r["success"])
        counts[cell] += 1.0
    return np.where(counts > 0, totals / np.maximum(counts, 1.0), np.nan)


def _success_interval(group: list[dict[str, Any]]) -> tuple[float, float]:
    """A method's success interval: over training seeds then scenarios when it has several seeds
    (:func:`training.stats.seeded_success_interval`), else over scenarios; never narrower than Wilson's."""
    if any(r.get("training_seed") is not None for r in group):
        return seeded_success_interval(outcome_table(group))
    return success_interval(*clusters(group, lambda r: float(r["success"])))


def _ratio(r: dict[str, Any], ref: dict[str, Any] | None) -> float | None:
    if ref is None or not (r["success"] and ref["success"] and ref["cost"] >= MIN_RATIO_COST_M):
        return None
    return r["cost"] / ref["cost"]


def _row(
    policy: str,
    split: str,
    group: list[dict],
    groups: dict[tuple[str, str], list[dict]],
    table: dict[tuple[str, int], dict[str, Any]],
) -> Row:
    expert = {r["seed"]: r for r in groups.get((EXPERT, split), [])}
    refs = [reference_of(r, table) for r in group]
    wins = sum(r["success"] for r in group)
    low, high = _success_interval(group)
    ratio, ratio_low, ratio_high = cluster_bootstrap(*clusters(group, lambda r: _ratio(r, reference_of(r, table))))
    weighted = [
        spl(r["success"], r["cost"], ref["cost"])
        for r, ref in zip(group, refs, strict=True)
        if ref is not None and ref["success"]
    ]
    known = [ref for ref in refs if ref is not None]
    kinds = {ref["fixed"] for ref in known}
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
        expert_phases=_mean(x["phases"] for x in known),
        pushes=_mean(r["pushes"] for r in group),
        expert_pushes=_mean(x["pushes"] for x in known),
        invalid_actions=_mean(r["invalid_actions"] for r in group),
        contacts=_mean(r["contacts"] for r in group),
        decision_ms=_mean(r["decision_ms"] for r in group),
        mask_ms=_mean(r.get("mask_ms", 0.0) for r in group),
        planner_ms=_mean(expert[r["seed"]]["decision_ms"] for r in group if r["seed"] in expert),
        score=score(zip(group, refs, strict=True)),
        scenarios=len({r["seed"] for r in group}),
        step_ms=_mean(r["step_ms"] for r in group if "step_ms" in r),
        reference="mixed" if len(kinds) > 1 else "fixed" if kinds == {True} else "expert run",
        disagreements=_disagreements(group, refs) if policy == EXPERT else 0,
    )


def _disagreements(group: list[dict[str, Any]], refs: list[dict[str, Any] | None]) -> int:
    """Scenarios where the expert's record differs from its fixed reference (success, or cost by 0.001)."""
    return sum(
        1
        for r, ref in zip(group, refs, strict=True)
        if ref is not None
        and ref["fixed"]
        and (r["success"] != ref["success"] or abs(r["cost"] - ref["cost"]) > COST_AGREES_M)
    )


def grouped(records: list[dict[str, Any]], key: Callable[[dict[str, Any]], str]) -> list[Row]:
    """One :class:`Row` per policy and group ``key(record)`` (``Row.split`` is the group), references kept.

    Each record keeps its own split's reference (the groups are only how rows are cut).
    """
    table = reference_table(records)
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for record in records:
        groups.setdefault((record["policy"], key(record)), []).append(record)
    return [_row(policy, label, group, groups, table) for (policy, label), group in groups.items()]


def by_objects(records: list[dict[str, Any]]) -> list[Row]:
    """One :class:`Row` per policy and object count (``Row.split`` is the count, as text), in count order.

    The graded families (``objects-1`` .. ``objects-8``) and any split of several object
    counts: success and cost ratio against the number of objects.
    """
    return grouped(sorted(records, key=lambda r: r["objects"]), lambda r: str(r["objects"]))
