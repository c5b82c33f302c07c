"""The fixed references: every published split pinned scenario by scenario, read by the metrics, the same on Ray."""

from __future__ import annotations

import importlib.util

import pytest

from training.evaluation import references
from training.evaluation.metrics import fill_expert_costs, summarise
from training.evaluation.references import (
    compute_references,
    digest_mismatches,
    part_references,
    reference_for,
    references_digest,
)
from training.evaluation.splits import EvalScenario, get_split, published_splits, split_scenarios
from training.resolve import EXPERT

SHORT_PARTS = {"objects-v1:dev", "objects-v1:test", "apartment-v1:dev", "apartment-v1:test"}
"""Parts with fewer episodes than the protocol's 300 (test) and 100 (dev): their references were slow to compute."""


@pytest.mark.parametrize("split", [s.name for s in published_splits()])
def test_every_scenario_of_a_published_split_has_its_digest(split: str) -> None:
    records = part_references(split)
    assert len(records) == get_split(split).episodes  # the part's default: every episode has its reference
    assert len(records) >= (300 if split.endswith(":test") else 100) or split in SHORT_PARTS
    assert [r["index"] for r in records] == list(range(len(records)))
    assert list(digest_mismatches(split)) == []  # every scenario sampled again, not the first three


def test_a_changed_sampler_is_caught_on_a_late_scenario(monkeypatch: pytest.MonkeyPatch) -> None:
    original = split_scenarios

    def changed(split: object, episodes: int | None = None) -> list[EvalScenario]:
        items = original(split, episodes)
        other = original("iid-v1:dev", 1)[0].scenario  # another scenario at episode 250
        items[250] = EvalScenario(250, items[250].split, items[250].source, items[250].seed, other)
        return items

    monkeypatch.setattr(references, "split_scenarios", changed)
    assert [line.split(":")[1].split()[0] for line in digest_mismatches("iid-v1:test")] == ["test"]
    item = split_scenarios("iid-v1:test", 251)[250]
    with pytest.raises(references.ReferenceError, match="sampler changed"):
        reference_for(
            EvalScenario(250, item.split, item.source, item.seed, split_scenarios("iid-v1:dev", 1)[0].scenario)
        )


def _record(policy: str, item: EvalScenario, success: bool, cost: float) -> dict:
    ref = part_references(item.split)[item.index]
    return {
        "policy": policy,
        "scenario": item.scenario.name,
        "split": item.split,
        "source": item.source,
        "seed": item.seed,
        "digest": ref["digest"],
        "success": success,
        "delivered": 1,
        "objects": 1,
        "cost": cost,
        "expert_cost": None,
        "return": 10 - cost,
        "phases": 4,
        "pushes": 0,
        "invalid_actions": 0,
        "contacts": 0,
        "decision_ms": 1.0,
        "mask_ms": 0.0,
    }


def test_cost_ratio_reads_the_reference_not_the_expert_run() -> None:
    items = split_scenarios("iid-v1:test", 3)
    fixed = [part_references("iid-v1:test")[k]["cost"] for k in range(3)]
    # the expert of this run hit a time limit on scenario 1 (under load): it does not move the learner's figures
    records = [
        _record(EXPERT, items[0], True, fixed[0]),
        _record(EXPERT, items[1], False, 0.0),
        _record(EXPERT, items[2], True, fixed[2]),
    ]
    records += [_record("learner", item, True, 1.5 * cost) for item, cost in zip(items, fixed, strict=True)]
    fill_expert_costs(records)
    assert [r["expert_cost"] for r in records[3:]] == fixed
    assert {r["references"] for r in records} == {references_digest(part_references("iid-v1:test"))}
    rows = {row.policy: row for row in summarise(records)}
    assert rows["learner"].cost_ratio == pytest.approx(1.5)
    assert rows["learner"].spl == pytest.approx(1 / 1.5)
    assert rows["learner"].reference == "fixed"
    assert rows[EXPERT].disagreements == 1
    assert rows["learner"].cost_ratio_low > 0


def test_cost_ratio_interval_is_never_negative_nor_of_zero_width_at_one() -> None:
    items = split_scenarios("iid-v1:test", 2)
    fixed = [part_references("iid-v1:test")[k]["cost"] for k in range(2)]
    records = [_record("a", items[0], True, 3 * fixed[0]), _record("a", items[1], False, 1.0)]
    row = summarise(records)[0]
    assert row.cost_ratio == pytest.approx(3) and row.cost_ratio_low != row.cost_ratio_low  # nan: no interval at n=1
    records = [_record("b", items[0], True, 3 * fixed[0]), _record("b", items[1], True, 0.2 * fixed[1])]
    row = summarise(records)[0]
    assert 0 < row.cost_ratio_low <= row.cost_ratio <= row.cost_ratio_high


def _stable(content: dict) -> dict:
    return {
        part: [{k: v for k, v in r.items() if k != "planning_s"} for r in records]
        for part, records in content["parts"].items()
    }


@pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="Ray is not installed")
def test_references_on_ray_are_the_pools_records() -> None:
    episodes = {"dev": 2, "test": 2}
    local = compute_references("push-required-v1", episodes=episodes)
    on_ray = compute_references("push-required-v1", episodes=episodes, workers=2, backend="ray")
    assert _stable(local) == _stable(on_ray)
    shipped = {part: part_references(f"push-required-v1:{part}")[:2] for part in episodes}
    assert _stable(local) == _stable({"parts": shipped})  # and the shipped file's, made once
