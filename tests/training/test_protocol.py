"""The protocol's guards: dev and test parts, and no training data on evaluation seeds or split scenarios."""

from __future__ import annotations

from pathlib import Path

import pytest

from training.cli import main
from training.data.generate import EVAL_SEED_BASE, EvaluationSeedError, check_training_seeds
from training.evaluation.protocol import refuse_split_scenario
from training.evaluation.splits import SPLIT_BLOCK, SPLITS, get_split, split_scenarios

V2 = ("iid-v2", "more-objects-v2", "push-required-v2", "layouts-v3", "perturbed-v2", "objects-v2", "apartment-v2")
"""Version 2 of every split (layouts: 3), under the task cost."""
PERTURBED_FACTORS = ("perturbed-layout-v2", "perturbed-distractors-v2", "perturbed-physics-v2")


def test_perturbed_v2s_factors_alone_draw_its_scenarios_without_the_other_two() -> None:
    mix = split_scenarios("perturbed-v2:test", 40)
    for version in PERTURBED_FACTORS:
        alone = split_scenarios(f"{version}:test", 40)
        assert [i.seed for i in alone] == [i.seed for i in mix]
        same = [
            a.scenario.name.split("-")[-1] == m.scenario.name.split("-")[-1] for a, m in zip(alone, mix, strict=True)
        ]
        assert sum(same) >= 36  # a draw either family's checks refuse is drawn again, and the two part ways


def test_dev_and_test_parts_have_disjoint_seeds_and_test_is_the_default() -> None:
    assert get_split("iid").name == "iid-v2:test" and get_split("iid-v2").name == "iid-v2:test"
    assert get_split("iid:dev").name == "iid-v2:dev" and get_split("iid-v1").name == "iid-v1:test"
    assert get_split("iid-v0").name == "iid-v0"
    for base in ("iid", "more-objects", "layouts", "push-required"):
        dev, test = get_split(f"{base}-v1:dev"), get_split(f"{base}-v1:test")
        dev_seeds = {dev.seed(k) for k in range(dev.episodes)}
        test_seeds = {test.seed(k) for k in range(test.episodes)}
        assert not dev_seeds & test_seeds and test.episodes >= 300
        assert min(dev_seeds | test_seeds) >= EVAL_SEED_BASE
        assert max(test_seeds) < EVAL_SEED_BASE + get_split(f"{base}-v0").offset + SPLIT_BLOCK  # its own block
    # v1's dev part is v0's scenarios (where recipes were tuned); its test part never met them
    assert [i.scenario for i in split_scenarios("iid-v1:dev", 5)] == [i.scenario for i in split_scenarios("iid-v0", 5)]


@pytest.mark.parametrize("version", V2)
def test_a_v2_split_has_a_block_of_fresh_seeds_no_earlier_split_draws_from(version: str) -> None:
    dev, test = get_split(f"{version}:dev"), get_split(f"{version}:test")
    block = dev.offset // SPLIT_BLOCK
    assert dev.offset == block * SPLIT_BLOCK and test.offset == dev.offset + SPLIT_BLOCK // 2
    assert 8 <= block <= 14  # blocks 0 to 7 hold every split of versions 0 and 1
    sharing = [split.version for split in SPLITS.values() if split.offset // SPLIT_BLOCK == block]
    factors = PERTURBED_FACTORS if version == "perturbed-v2" else ()  # its one-factor splits, paired on purpose
    assert sharing == [name for name in (version, *factors) for _ in ("dev", "test")]
    dev_seeds = {dev.seed(k) for k in range(dev.episodes)}
    test_seeds = {test.seed(k) for k in range(test.episodes)}
    assert not dev_seeds & test_seeds
    assert min(dev_seeds) == EVAL_SEED_BASE + block * SPLIT_BLOCK
    assert max(test_seeds) < EVAL_SEED_BASE + (block + 1) * SPLIT_BLOCK
    assert get_split(f"{dev.base_name}:dev") == dev and get_split(dev.base_name) == test  # the newest version


def test_training_seeds_reaching_evaluation_seeds_are_refused() -> None:
    check_training_seeds(EVAL_SEED_BASE - 10, 10)
    with pytest.raises(EvaluationSeedError, match="allow-evaluation-seeds"):
        check_training_seeds(EVAL_SEED_BASE - 10, 11)
    check_training_seeds(EVAL_SEED_BASE, 5, allow_evaluation_seeds=True)


@pytest.mark.parametrize("seed", [str(EVAL_SEED_BASE), str(EVAL_SEED_BASE - 1)])
def test_generate_refuses_evaluation_seeds(seed: str, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["generate", "--family", "basic", "--seed", seed, "--episodes", "2", "--dataset-id", "fetchcarry/t-v0"]
    assert main([*argv, "--no-progress"]) == 2
    assert "--allow-evaluation-seeds" in capsys.readouterr().err


def test_generate_refuses_a_split_scenario_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    item = split_scenarios("more-objects:test", 8)[7]
    path = tmp_path / "looks-innocent.json"
    item.scenario.save(path)
    argv = ["generate", "--scenario", str(path), "--episodes", "1", "--dataset-id", "fetchcarry/t-v0", "--no-progress"]
    assert main(argv) == 2
    assert "more-objects-v2:test episode 7" in capsys.readouterr().err
    refuse_split_scenario(item.scenario, allow=True)  # on purpose: allowed
    renamed = split_scenarios("iid-v0", 1)[0].scenario.to_dict() | {"name": "renamed"}  # iid-v1:dev episode 0
    with pytest.raises(EvaluationSeedError, match="iid-v1:dev episode 0"):
        refuse_split_scenario(renamed)
