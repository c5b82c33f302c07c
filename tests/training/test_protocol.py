"""The protocol's guards: dev and test parts, and no training data on evaluation seeds or split scenarios."""

from __future__ import annotations

from pathlib import Path

import pytest

from training.cli import main
from training.data.generate import EVAL_SEED_BASE, EvaluationSeedError, check_training_seeds
from training.evaluation.protocol import refuse_split_scenario
from training.evaluation.splits import SPLIT_BLOCK, get_split, split_scenarios


def test_dev_and_test_parts_have_disjoint_seeds_and_test_is_the_default() -> None:
    assert get_split("iid").name == "iid-v1:test" and get_split("iid-v1").name == "iid-v1:test"
    assert get_split("iid:dev").name == "iid-v1:dev" and get_split("iid-v0").name == "iid-v0"
    for base in ("iid", "more-objects", "layouts", "push-required"):
        dev, test = get_split(f"{base}-v1:dev"), get_split(f"{base}-v1:test")
        dev_seeds = {dev.seed(k) for k in range(dev.episodes)}
        test_seeds = {test.seed(k) for k in range(test.episodes)}
        assert not dev_seeds & test_seeds and test.episodes >= 300
        assert min(dev_seeds | test_seeds) >= EVAL_SEED_BASE
        assert max(test_seeds) < EVAL_SEED_BASE + get_split(f"{base}-v0").offset + SPLIT_BLOCK  # its own block
    # the dev part is v0's scenarios (where recipes were tuned); the test part never met them
    assert [i.scenario for i in split_scenarios("iid:dev", 5)] == [i.scenario for i in split_scenarios("iid-v0", 5)]


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
    assert "more-objects-v1:test episode 7" in capsys.readouterr().err
    refuse_split_scenario(item.scenario, allow=True)  # on purpose: allowed
    renamed = split_scenarios("iid-v0", 1)[0].scenario.to_dict() | {"name": "renamed"}  # iid-v1:dev episode 0
    with pytest.raises(EvaluationSeedError, match="iid-v1:dev episode 0"):
        refuse_split_scenario(renamed)
