"""The ladder study: its training family (objects-1-4), its goals read from a benchmark's records, its run tools."""

from __future__ import annotations

import json
from collections import Counter

import numpy as np
import pytest

from benchmarks.studies import ladder
from fetchcarry_env.families import get_family
from fetchcarry_env.worlds.ladder import draw_ladder
from fetchcarry_env.worlds.objects import draw_objects
from training.evaluation.splits import SPLITS
from training.stats import wilson


def test_the_training_family_draws_one_to_four_objects_at_capacity_four_and_repeats():
    family = get_family("objects-1-4")
    assert family.capacity.objects == 4
    counts = Counter(len(family.sample(np.random.default_rng(seed)).objects) for seed in range(80))
    assert set(counts) == {1, 2, 3, 4}
    assert min(counts.values()) >= 10  # uniform: about 20 each
    first = family.sample(np.random.default_rng(7)).to_dict()
    assert family.sample(np.random.default_rng(7)).to_dict() == first


def test_a_ladder_draw_is_the_objects_k_draw_after_k():
    rng, again = np.random.default_rng(3), np.random.default_rng(3)
    scenario = draw_ladder(rng)
    k = int(again.integers(1, 5))
    assert draw_objects(again, k).to_dict() == scenario.to_dict()


def _record(policy: str, k: int, seed: int, success: bool) -> dict:
    return {"policy": policy, "source": f"objects-{k}", "seed": seed, "success": success}


def test_the_goals_are_met_or_missed_with_their_interval_from_a_benchmarks_records():
    records = [_record("bc", 6, s, s < 8) for s in range(10)]  # 80 %: met
    records += [_record("bc", 8, s, s < 5) for s in range(10)]  # 50 %: missed
    records += [_record("greedy", 6, s, True) for s in range(4)]  # no objects-8 episode: left out
    low, high = wilson(8, 10)
    assert ladder.goals(records) == [
        f"bc: at least 80% on objects-6: met (80% [{low:.0%}, {high:.0%}], 10 episodes)",
        f"bc: at least 60% on objects-8: missed (50% [{wilson(5, 10)[0]:.0%}, {wilson(5, 10)[1]:.0%}], 10 episodes)",
        "greedy: at least 80% on objects-6: met (100% [51%, 100%], 4 episodes)",
    ]


def test_the_objects_splits_are_the_ladders_curve_from_one_object_on():
    sources = [source.name for source in SPLITS["objects-v2:test"].sources]
    assert sources[:8] == [f"objects-{k}" for k in range(1, 9)]


@pytest.mark.parametrize("rule", [False, True])
def test_skip_delivered_leaves_out_the_picks_of_a_delivered_object(rule: bool):
    import torch

    from fetchcarry_env.observation import Capacity, observation_layout, observation_size
    from fetchcarry_env.phases import PhaseLayout
    from training.learners.bc import BCConfig, BCPolicy

    capacity = Capacity()
    layout, slots = PhaseLayout.for_postures(capacity=capacity), observation_layout(capacity)
    flat = np.zeros(observation_size(capacity), np.float32)
    flat[slots["object_0"]] = [1, 0.0, 0.0, 0.8, 1.0, 1.0, 0.8, 0.035, 0.2, 0, 0]  # still to deliver
    flat[slots["object_1"]] = [1, 1.0, 1.0, 0.8, 1.0, 1.0, 0.8, 0.035, 0.2, 0, 1]  # delivered
    again, other = layout.index("pick", 1, 0, 0, 0), layout.index("pick", 0, 2, 1, 0)
    scores = torch.full((layout.size,), -10.0)
    scores[[again, other]] = torch.tensor([3.0, 1.0])

    class Fixed(torch.nn.Module):
        def forward(self, rows: torch.Tensor) -> torch.Tensor:
            return scores.expand(len(rows), -1)

    policy = BCPolicy(Fixed(), BCConfig(avoid_repeats=False, skip_delivered=rule), capacity)
    mask = np.zeros(layout.size, bool)
    mask[[again, other]] = True
    assert int(policy.predict(flat, action_masks=mask)[0]) == (other if rule else again)
    mask[other] = False  # nothing else allowed: the delivered object's pick after all
    assert int(policy.predict(flat, action_masks=mask)[0]) == again


def test_variant_copies_a_run_with_other_acting_rules_or_a_dagger_runs_last_iteration(tmp_path):
    import torch

    from training.learners.runs import save_checkpoint

    run = tmp_path / "bc"
    run.mkdir()
    config = {"kind": "bc", "config": {"avoid_returns": False}, "data": {}, "complete": True}
    (run / "config.json").write_text(json.dumps(config))
    (run / "model.pt").write_bytes(b"weights")
    copy = ladder.variant(run, tmp_path / "copy", {"skip_delivered": True, "avoid_returns": True})
    assert json.loads((copy / "config.json").read_text())["config"] == {"avoid_returns": True, "skip_delivered": True}
    assert (copy / "model.pt").read_bytes() == b"weights"
    with pytest.raises(ValueError, match="not acting options"):
        ladder.variant(run, tmp_path / "other", {"hidden": True})
    with pytest.raises(ValueError, match="exists"):
        ladder.variant(run, copy, {"skip_delivered": True})
    dagger = tmp_path / "dagger"
    dagger.mkdir()
    (dagger / "config.json").write_text(json.dumps({**config, "kind": "dagger", "complete": False}))
    with pytest.raises(ValueError, match="not finished"):
        ladder.variant(dagger, tmp_path / "none", {})
    rows = [{"iteration": 0, "expert_labels": 5}, {"iteration": 1, "expert_labels": 9}]
    save_checkpoint(dagger, {"network": {"w": torch.ones(2)}, "metrics": rows, "episodes": 12})
    snapshot = ladder.variant(dagger, tmp_path / "snapshot", {"skip_delivered": True})
    saved = json.loads((snapshot / "config.json").read_text())
    assert saved["complete"] and saved["data"] == {"expert_labels": 9, "episodes": 12, "stopped_after_iteration": 1}
    assert torch.equal(torch.load(snapshot / "model.pt")["w"], torch.ones(2))


def test_trace_gives_one_word_per_phase_with_the_hand_and_the_deliveries():
    line = ladder.trace("random-phases", 1, 100_000)
    seed, outcome, phases, *words = line.split()
    assert (seed, outcome in ("success", "failure")) == ("100000", True)
    assert len(words) == int(phases) >= 1
    assert all(word[:4] in ("pick", "plac", "push", "appr", "wayp", "edge") and "[d" in word for word in words)
    if outcome == "success":
        assert words[-1].startswith("plac0(h0)[d0|")  # the last phase places the one object, not delivered before
