"""``fetchcarry train bc|dagger|ppo`` refuse the benchmark's evaluation seeds and split scenarios (exit 2)."""

from __future__ import annotations

from pathlib import Path

import pytest

from training.cli import main
from training.data.generate import EVAL_SEED_BASE
from training.evaluation.splits import split_scenarios

TINY_PPO = ["--steps", "16", "--n-steps", "16", "--hidden", "8", "--eval-episodes", "0", "--no-progress"]


@pytest.mark.parametrize(("seed", "envs"), [(EVAL_SEED_BASE, 1), (EVAL_SEED_BASE - 1, 2), (EVAL_SEED_BASE + 5, 1)])
def test_train_ppo_refuses_first_episodes_on_evaluation_seeds(
    seed: int, envs: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["train", "ppo", "--family", "basic", "--seed", str(seed), "--envs", str(envs), "--out", str(tmp_path / "r")]
    assert main([*argv, *TINY_PPO]) == 2
    error = capsys.readouterr().err
    assert "reach the evaluation seeds" in error and "--allow-evaluation-seeds" in error
    assert "Traceback" not in error and not (tmp_path / "r").exists()  # refused before any run folder


def test_train_ppo_below_the_evaluation_seeds_or_on_purpose_trains(tmp_path: Path) -> None:
    last_allowed = ["--seed", str(EVAL_SEED_BASE - 2), "--envs", "2"]
    assert main(["train", "ppo", "--family", "basic", *last_allowed, "--out", str(tmp_path / "a"), *TINY_PPO]) == 0
    on_purpose = ["--seed", str(EVAL_SEED_BASE), "--allow-evaluation-seeds"]
    assert main(["train", "ppo", "--family", "basic", *on_purpose, "--out", str(tmp_path / "b"), *TINY_PPO]) == 0


def _generate(argv: list[str], dataset: str) -> None:
    base = ["generate", "--episodes", "1", "--interface", "phases", "--dataset-id", dataset, "--no-progress"]
    assert main([*base, *argv, "--allow-evaluation-seeds"]) == 0


def test_train_bc_and_dagger_refuse_a_dataset_of_evaluation_seeds(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _generate(["--family", "basic", "--seed", str(EVAL_SEED_BASE)], "fetchcarry/evalseeds-v0")
    bc = ["train", "bc", "--dataset", "fetchcarry/evalseeds-v0", "--epochs", "1", "--no-progress"]
    assert main([*bc, "--out", str(tmp_path / "bc")]) == 2
    assert f"1 episodes of evaluation seeds (from {EVAL_SEED_BASE}" in capsys.readouterr().err
    assert not (tmp_path / "bc").exists()
    dagger = ["train", "dagger", "--family", "basic", "--dataset", "fetchcarry/evalseeds-v0", "--demonstrations",
              "1", "--iterations", "1", "--episodes-per-iteration", "1", "--eval-episodes", "1"]  # fmt: skip
    assert main([*dagger, "--out", str(tmp_path / "dagger")]) == 2
    assert "evaluation seeds" in capsys.readouterr().err
    assert main([*bc, "--out", str(tmp_path / "bc"), "--allow-evaluation-seeds"]) == 0  # research on purpose


def test_train_bc_refuses_a_dataset_recorded_on_a_split_scenario(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scenario = tmp_path / "innocent.json"
    split_scenarios("iid-v0", 1)[0].scenario.save(scenario)  # iid-v1:dev episode 0
    _generate(["--scenario", str(scenario), "--seed", "0"], "fetchcarry/onsplit-v0")
    argv = ["train", "bc", "--dataset", "fetchcarry/onsplit-v0", "--epochs", "1", "--no-progress"]
    assert main([*argv, "--out", str(tmp_path / "bc")]) == 2
    error = capsys.readouterr().err
    assert "iid-v1:dev episode 0" in error and "--allow-evaluation-seeds" in error
    _generate(["--family", "basic", "--seed", "0"], "fetchcarry/fine-v0")  # training seeds: trained on
    assert main(["train", "bc", "--dataset", "fetchcarry/fine-v0", "--epochs", "1", "--no-progress",
                 "--out", str(tmp_path / "fine")]) == 0  # fmt: skip
