"""MaskablePPO on several envs side by side (``fetchcarry train ppo --envs N``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

from fetchcarry_env.errors import InputError
from training.cli import main
from training.learners import runs
from training.learners.options import PPOOptions
from training.learners.ppo import make_training_env, make_vec_env, train_ppo

TWO_ENVS = PPOOptions(
    steps=64, n_steps=32, batch_size=16, n_epochs=2, hidden=32, checkpoint_every=32, seed=1, envs=2, eval_episodes=2
)


def _rows(rows: list[dict]) -> str:
    return json.dumps([{k: v for k, v in row.items() if k not in ("seconds", "eval_seconds")} for row in rows])


def _weights(folder: Path) -> dict[str, torch.Tensor]:
    return torch.load(folder / runs.WEIGHTS_FILE, weights_only=True)


def test_the_vector_env_is_the_single_envs_from_seed_plus_i_with_their_masks() -> None:
    venv = make_vec_env("basic", 2)
    try:
        venv.seed(7)
        observations = venv.reset()
        masks = venv.env_method("action_masks")
        for i in range(2):
            single = make_training_env("basic")
            observation, _ = single.reset(seed=7 + i)
            assert np.array_equal(observations[i], observation)
            assert np.array_equal(masks[i], single.get_wrapper_attr("action_masks")())
            single.close()
    finally:
        venv.close()


def test_ppo_on_two_envs_is_deterministic_and_its_run_folder_says_so(tmp_path: Path) -> None:
    first = train_ppo("basic", TWO_ENVS, tmp_path / "a", progress=False)
    second = train_ppo("basic", TWO_ENVS, tmp_path / "b", progress=False)
    assert _rows(first) == _rows(second)
    a, b = _weights(tmp_path / "a"), _weights(tmp_path / "b")
    assert a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)
    assert [row["steps"] for row in first] == [32, 64]
    config = runs.read_config(tmp_path / "a")
    assert config["options"]["envs"] == 2 and config["complete"]


def test_ppo_on_two_envs_differs_from_one_env(tmp_path: Path) -> None:
    """Two envs collect other episodes than one (env 1 starts from seed + 1): the option is not ignored."""
    one = PPOOptions(**{**TWO_ENVS.__dict__, "envs": 1})
    train_ppo("basic", one, tmp_path / "one", progress=False)
    train_ppo("basic", TWO_ENVS, tmp_path / "two", progress=False)
    a, b = _weights(tmp_path / "one"), _weights(tmp_path / "two")
    assert not all(torch.equal(a[k], b[k]) for k in a)


def test_ppo_on_two_envs_resumes_after_ctrl_c(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    args = ["train", "ppo", "--family", "basic", "--steps", "96", "--n-steps", "32", "--hidden", "16", "--envs", "2",
            "--checkpoint-every", "32", "--eval-episodes", "2", "--out", str(tmp_path / "run"),
            "--no-progress"]  # fmt: skip
    real, calls = runs.write_metrics, []

    def interrupt_third_rollout(folder: Path, rows: list) -> None:
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        real(folder, rows)

    monkeypatch.setattr(runs, "write_metrics", interrupt_third_rollout)
    assert main(args) == 130
    monkeypatch.setattr(runs, "write_metrics", real)
    assert runs.load_checkpoint(tmp_path / "run")["steps"] == 64
    assert main([*args[:-1], "--envs", "1", "--resume", "--no-progress"]) == 2  # other options than the run's
    assert main([*args, "--resume"]) == 0
    assert [row["steps"] for row in runs.read_metrics(tmp_path / "run")] == [32, 64, 96]
    assert runs.read_config(tmp_path / "run")["complete"]


@pytest.mark.parametrize("envs", [0, 65, 33])
def test_impossible_env_counts_are_bad_input(envs: int) -> None:
    with pytest.raises(InputError, match="envs"):
        PPOOptions(n_steps=32, envs=envs)


def test_a_run_folder_from_before_envs_resumes_with_one_env(tmp_path: Path) -> None:
    """A config.json whose options lack ``envs`` (written before the option existed) is a one-env run."""
    options = PPOOptions(
        steps=64, n_steps=32, batch_size=16, n_epochs=1, hidden=16, checkpoint_every=32, eval_episodes=2
    )
    train_ppo("basic", PPOOptions(**{**options.__dict__, "steps": 32}), tmp_path / "run", progress=False)
    config = runs.read_saved(tmp_path / "run")
    del config["options"]["envs"]
    config["options"]["steps"], config["data"]["steps"], config["complete"] = 64, 64, False
    (tmp_path / "run" / runs.CONFIG_FILE).write_text(json.dumps(config))
    rows = train_ppo("basic", options, tmp_path / "run", resume=True, progress=False)
    assert [row["steps"] for row in rows] == [32, 64]
    with pytest.raises(runs.RunFolderError, match="other options"):
        train_ppo("basic", PPOOptions(**{**options.__dict__, "envs": 2}), tmp_path / "run", resume=True)
