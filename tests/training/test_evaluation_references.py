"""The fixed references: every published split pinned scenario by scenario, read by the metrics, the same on Ray."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest
from cli_run import run

from training.evaluation import references
from training.evaluation.metrics import fill_expert_costs, summarise
from training.evaluation.references import (
    FOLDER,
    ReferenceFileError,
    compute_references,
    digest_mismatches,
    load_references,
    part_references,
    reference_for,
    references_digest,
)
from training.evaluation.splits import EvalScenario, get_split, published_splits, split_scenarios
from training.resolve import EXPERT

SHORT_PARTS = {f"{version}:{part}" for version in ("objects-v1", "apartment-v1") for part in ("dev", "test")}
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
        other = original("iid-v2:dev", 1)[0].scenario  # another scenario at episode 250
        items[250] = EvalScenario(250, items[250].split, items[250].source, items[250].seed, other)
        return items

    monkeypatch.setattr(references, "split_scenarios", changed)
    assert [line.split(":")[1].split()[0] for line in digest_mismatches("iid-v2:test")] == ["test"]
    item = split_scenarios("iid-v2:test", 251)[250]
    with pytest.raises(references.ReferenceFileError, match="sampler changed"):
        reference_for(
            EvalScenario(250, item.split, item.source, item.seed, split_scenarios("iid-v2:dev", 1)[0].scenario)
        )
    assert reference_for(item)[0] == part_references("iid-v2:test")[250]  # the scenario itself is its reference's


def test_a_v1_split_loads_as_legacy_and_is_not_scored_against() -> None:
    """Release 0.2's files stay as published and load; the benchmark refuses to score against them."""
    legacy = load_references("iid-v1")
    assert legacy["format"] == references.LEGACY_FORMAT and len(legacy["parts"]["test"]) == 300
    assert "travel" not in legacy["parts"]["test"][0]
    assert load_references("iid-v2")["format"] == references.FORMAT
    with pytest.raises(ReferenceFileError, match="benchmark iid-v2:test instead"):
        reference_for(split_scenarios("iid-v1:test", 1)[0])


def _record(policy: str, item: EvalScenario, success: bool, cost: float) -> dict:
    """A schema-2 record of ``policy`` on ``item`` of task cost ``cost`` (its return minus it, travel within it)."""
    ref = part_references(item.split)[item.index]
    return {
        "policy": policy,
        "scenario": item.scenario.name,
        "split": item.split,
        "source": item.source,
        "seed": item.seed,
        "digest": ref["digest"],
        "success": success,
        "delivered": int(success),
        "objects": 1,
        "cost": cost,
        "travel": cost / 2,
        "expert_cost": None,
        "return": -cost,
        "phases": 4,
        "pushes": 0,
        "invalid_actions": 0,
        "contacts": 0,
        "decision_ms": 1.0,
        "mask_ms": 0.0,
    }


def test_cost_ratio_reads_the_reference_not_the_expert_run() -> None:
    items = split_scenarios("iid-v2:test", 3)
    fixed = [part_references("iid-v2:test")[k]["cost"] for k in range(3)]
    # the expert of this run hit a time limit on scenario 1 (under load): it does not move the learner's figures
    records = [
        _record(EXPERT, items[0], True, fixed[0]),
        _record(EXPERT, items[1], False, 0.0),
        _record(EXPERT, items[2], True, fixed[2]),
    ]
    records += [_record("learner", item, True, 1.5 * cost) for item, cost in zip(items, fixed, strict=True)]
    fill_expert_costs(records)
    assert [r["expert_cost"] for r in records[3:]] == fixed
    assert {r["references"] for r in records} == {references_digest(part_references("iid-v2:test"))}
    rows = {row.policy: row for row in summarise(records)}
    assert rows["learner"].cost_ratio == pytest.approx(1.5)
    assert rows["learner"].spl == pytest.approx(1 / 1.5)
    assert rows["learner"].reference == "fixed"
    assert rows[EXPERT].disagreements == 1
    assert rows["learner"].cost_ratio_low > 0


def test_cost_ratio_interval_is_never_negative_nor_of_zero_width_at_one() -> None:
    items = split_scenarios("iid-v2:test", 2)
    fixed = [part_references("iid-v2:test")[k]["cost"] for k in range(2)]
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
    local = compute_references("push-required-v2", episodes=episodes)
    on_ray = compute_references("push-required-v2", episodes=episodes, workers=2, backend="ray")
    assert _stable(local) == _stable(on_ray)
    shipped = {part: part_references(f"push-required-v2:{part}")[:2] for part in episodes}
    assert _stable(local) == _stable({"parts": shipped})  # and the shipped file's, made once


@pytest.mark.parametrize(
    ("token", "shown"), [('"10"', "'10'"), ("NaN", "nan"), ("1e400", "inf")], ids=["string", "nan", "1e400"]
)
def test_a_reference_cost_that_is_no_finite_number_is_refused_naming_the_field(
    token: str, shown: str, tmp_path: Path
) -> None:
    """The JSON reader takes ``NaN`` and ``1e400`` as floats (nan, inf): the loader refuses them, and a string."""
    records = [json.dumps(r, sort_keys=True) for r in part_references("iid-v2:test")[:2]]
    records[1] = records[1].replace(f'"cost": {json.loads(records[1])["cost"]!r}', f'"cost": {token}', 1)
    assert f'"cost": {token}' in records[1]
    head = '{"format": "fetchcarry-references/2", "split": "iid-v2", "time_limit_s": 600.0, "parts": '
    (tmp_path / "iid-v2.json").write_text(head + '{"test": [' + ",\n".join(records) + "]}}")
    with pytest.raises(ReferenceFileError, match=rf"part 'test' record 1: cost = {shown} is not a finite number"):
        load_references("iid-v2", tmp_path)
    assert load_references("iid-v2", FOLDER) is not None  # the package's file is read apart from the cache's copy


def test_check_plans_a_proven_reference_again_and_catches_a_changed_cost(monkeypatch: pytest.MonkeyPatch) -> None:
    """A sample is drawn from the proven references by the split's name; planning one again gives its record, and a
    record whose cost, return or status was changed (x10, NaN aside: the loader refuses it) is a disagreement."""
    sample, again = (references.replan_sample("push-required-v2:dev", 3) for _ in range(2))
    assert [item.index for item in sample] == [item.index for item in again]  # drawn alike every time
    assert len(sample) == 3 and all(part_references(item.split)[item.index]["proven"] for item in sample)
    item = sample[0]
    limit = load_references("push-required-v2")["time_limit_s"]
    assert references.replan_mismatches(item, limit) == []
    tampered = [dict(r) for r in part_references(item.split)]
    tampered[item.index].update(cost=10 * tampered[item.index]["cost"], status="feasible")
    monkeypatch.setattr(references, "part_references", lambda split, folder=FOLDER: tampered)
    lines = references.replan_mismatches(item, limit)
    assert [line.split(": ")[1].split()[0] for line in lines] == ["status", "cost"]


def test_an_interrupted_references_run_keeps_what_finished_and_extend_continues_it(
    capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    original, calls = references._reference_task, []

    def interrupted_at_the_second(task: tuple[float, EvalScenario]) -> dict:
        calls.append(task[1].index)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return original(task)

    command = ("references", "--split", "iid-v2", "--dev-episodes", 2, "--test-episodes", 1, "--time-limit", 5)
    monkeypatch.setattr(references, "_reference_task", interrupted_at_the_second)
    status, _, err = run(capsys, *command, "--out", tmp_path, "--no-progress")
    assert status == 130 and "run the same command with --extend" in err
    partial = references.load_references("iid-v2.partial", tmp_path)
    assert [r["index"] for r in partial["parts"]["dev"]] == [0]  # the one episode that finished
    calls.clear()
    monkeypatch.setattr(references, "_reference_task", lambda task: calls.append(task[1].index) or original(task))
    status, _, err = run(capsys, *command, "--out", tmp_path, "--no-progress", "--extend")
    assert status == 0, err
    assert calls == [1, 0]  # dev episode 1 and test episode 0: dev episode 0 was kept
    content = references.load_references("iid-v2", tmp_path)
    assert content["parts"]["dev"][0] == partial["parts"]["dev"][0]
    assert not (tmp_path / "iid-v2.partial.json").exists()
