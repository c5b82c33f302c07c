"""``fetchcarry dataset render``: a state dataset replayed exactly into topdown and rgbd observations."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import h5py
import numpy as np
import pytest

from training.cli import main
from training.data.datasets import dataset_path, episode_metadata, load, replay
from training.data.generate import generate
from training.data.render import RenderError, render_dataset
from training.data.sources import EpisodeSource, GenerationConfig

SOURCE = "fetchcarry/vision-basic-v0"


@pytest.fixture(autouse=True)
def minari_root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    root = tmp_path / "minari"
    root.mkdir()
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(root))
    return root


@pytest.fixture
def state_dataset() -> str:
    source = EpisodeSource(family="basic", seed=4, interface="phases")
    generate(GenerationConfig(SOURCE, 2, source), progress=False)
    return SOURCE


def test_render_replays_a_state_dataset_into_topdown_exactly(state_dataset):
    report = render_dataset(state_dataset, "topdown", "fetchcarry/vision-topdown-v0", progress=False)
    assert (report.episodes, report.obs_mode) == (2, "topdown")
    old, new = load(state_dataset), load("fetchcarry/vision-topdown-v0")
    assert new.spec.env_spec.kwargs["obs_mode"] == "topdown"
    env = gym.make("FetchCarryPushPhases-v0", family="basic", obs_mode="topdown")
    for k in range(2):
        a, b = old[k], new[k]
        assert np.array_equal(a.actions, b.actions) and np.array_equal(a.rewards, b.rewards)
        for key in ("observation", "achieved_goal", "desired_goal"):
            assert np.array_equal(a.observations[key], b.observations[key])
        assert b.observations["topdown"].shape == (len(a.actions) + 1, 7, 64, 64)
        live, _ = env.reset(seed=4 + k)  # the images are the env's own, state for state
        assert np.array_equal(live["topdown"], b.observations["topdown"][0])
        last = None
        for action in a.actions:
            last = env.step(action)[0]
        assert np.array_equal(last["topdown"], b.observations["topdown"][-1])
        assert episode_metadata(new, k) == episode_metadata(old, k)  # seed, scenario and the figures
    assert replay("fetchcarry/vision-topdown-v0", 1).reproduced  # the rendered dataset replays too


def test_render_into_rgbd_and_back_to_state(state_dataset):
    render_dataset(
        state_dataset, "rgbd", "fetchcarry/vision-rgbd-v0", image_options={"camera_size": 32}, progress=False
    )
    rgbd = load("fetchcarry/vision-rgbd-v0")[0].observations
    assert rgbd["head_rgbd"].shape[1:] == rgbd["overhead_rgbd"].shape[1:] == (4, 32, 32)
    render_dataset("fetchcarry/vision-rgbd-v0", "state", "fetchcarry/vision-state-v0", progress=False)
    state = load("fetchcarry/vision-state-v0")
    assert set(state[0].observations) == {"observation", "achieved_goal", "desired_goal"}
    assert state.observation_space == load(state_dataset).observation_space


def test_an_episode_that_does_not_replay_is_refused_and_nothing_is_written(state_dataset):
    with h5py.File(dataset_path(state_dataset) / "data" / "main_data.hdf5", "r+") as file:
        file["episode_1/rewards"][0] += 1.0
    with pytest.raises(RenderError, match=r"episode 1 .* step 0 gives reward"):
        render_dataset(state_dataset, "topdown", "fetchcarry/vision-topdown-v0", progress=False)
    assert not dataset_path("fetchcarry/vision-topdown-v0").exists()


def test_render_command_exit_statuses(state_dataset, capsys):
    out = "fetchcarry/vision-topdown-v0"
    assert main(["dataset", "render", state_dataset, "--obs-mode", "topdown", "--out", out, "--no-progress"]) == 0
    assert "rendered into obs_mode topdown" in capsys.readouterr().out
    again = ["dataset", "render", state_dataset, "--obs-mode", "topdown", "--out", out, "--no-progress"]
    assert main(again) == 2  # exists
    assert main([*again, "--overwrite"]) == 0
    assert main(["dataset", "render", state_dataset, "--obs-mode", "rgbd", "--out", state_dataset]) == 2
    assert main(["dataset", "render", "fetchcarry/none-v0", "--obs-mode", "rgbd", "--out", "fetchcarry/x-v0"]) == 2
    bad_size = [
        "dataset",
        "render",
        state_dataset,
        "--obs-mode",
        "topdown",
        "--topdown-size",
        "3",
        "--out",
        "fetchcarry/b-v1",
    ]
    assert main(bad_size) == 2
    assert "topdown_size must be at least 8" in capsys.readouterr().err
