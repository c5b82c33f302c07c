"""BC from pixels: the cnn encoder, demonstrations from a rendered dataset, its run folder in a topdown env."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from fetchcarry_env.errors import InputError
from training.data.generate import generate
from training.data.render import render_dataset
from training.data.sources import EpisodeSource, GenerationConfig

SOURCE, TOPDOWN = "fetchcarry/vision-bc-v0", "fetchcarry/vision-bc-topdown-v0"


@pytest.fixture(autouse=True)
def minari_root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    root = tmp_path / "minari"
    root.mkdir()
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(root))
    return root


def test_network_input_and_the_cnn_scores_only_the_candidates_asked_for():
    import torch

    from training.learners.encoders import ImageScorer, image_shape, network_input

    env = gym.make("FetchCarryPushPhases-v0", family="basic", obs_mode="rgbd", camera_size=16)
    observation, _ = env.reset(seed=0)
    row = network_input(observation, "rgbd")
    assert row.dtype == np.uint8 and row.shape == (8 * 16 * 16,)
    assert np.array_equal(row[: 4 * 256], observation["head_rgbd"].reshape(-1))  # head first, then overhead
    batch = network_input({k: v[None].repeat(3, axis=0) for k, v in observation.items()}, "rgbd")
    assert batch.shape == (3, 8 * 16 * 16) and np.array_equal(batch[2], row)
    with pytest.raises(KeyError, match="topdown"):
        network_input(observation, "topdown")
    assert image_shape("topdown", 7 * 64 * 64) == (7, 64, 64)
    with pytest.raises(ValueError):
        image_shape("topdown", 7 * 64 * 63)
    torch.manual_seed(0)
    network = ImageScorer((7, 64, 64), candidates=50, hidden=32).eval()
    flat = torch.randint(0, 256, (2, 7 * 64 * 64), dtype=torch.uint8).float()
    candidates = torch.tensor([3, 17, 49])
    assert torch.allclose(network.candidate_scores(flat, candidates), network(flat)[:, candidates], atol=1e-6)


def test_bc_cnn_trains_on_a_rendered_dataset_and_acts_in_a_topdown_env(tmp_path):
    from training import load_policy
    from training.learners.imitation import train_bc_run
    from training.learners.options import BCConfig

    generate(GenerationConfig(SOURCE, 3, EpisodeSource(family="basic", interface="phases")), progress=False)
    config = BCConfig(encoder="cnn", obs_mode="topdown", hidden=32, epochs=80, batch_size=8)
    with pytest.raises(InputError, match="dataset render"):
        train_bc_run(SOURCE, config, tmp_path / "none", progress=False)
    render_dataset(SOURCE, "topdown", TOPDOWN, progress=False)
    train_bc_run(TOPDOWN, config, tmp_path / "bc", progress=False)
    rows = (tmp_path / "bc" / "metrics.csv").read_text().splitlines()
    saved = json.loads((tmp_path / "bc" / "config.json").read_text())
    assert saved["observation"] == {"obs_mode": "topdown", "topdown_size": 64, "topdown_frame": "world"}
    assert float(rows[-1].split(",")[2]) == 1.0  # it fits its few labels
    env = gym.make("FetchCarryPushPhases-v0", family="basic", obs_mode="topdown")
    policy = load_policy(tmp_path / "bc", env)
    observation, _ = env.reset(seed=0)  # a training seed: it does what the expert did
    successes = 0
    for _ in range(10):
        action, _ = policy.predict(observation, deterministic=True)
        assert env.get_wrapper_attr("action_masks")()[int(action)]
        observation, _, terminated, truncated, info = env.step(int(action))
        if terminated or truncated:
            successes += info["is_success"]
            break
    assert successes == 1


def test_configurations_that_cannot_work_are_refused():
    from training.learners.options import BCConfig

    with pytest.raises(InputError, match="cnn"):
        BCConfig(encoder="cnn")  # the state vector is no image
    with pytest.raises(InputError):
        BCConfig(encoder="mlp", obs_mode="topdown")
    with pytest.raises(InputError, match="state vector"):
        BCConfig(encoder="cnn", obs_mode="topdown", avoid_returns=True)
