"""A new observation mode is one module and one entry: a throwaway one through the env, a dataset, BC, the benchmark."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import throwaway_mode
from cli_run import run
from gymnasium.utils.env_checker import check_env

from fetchcarry_env.observations import modes
from fetchcarry_env.observations.modes import ObservationMode, register_mode, unregister_mode
from training.data.datasets import load
from training.evaluation.results import read_results


@pytest.fixture
def occupancy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[ObservationMode]:
    """The throwaway mode, registered for one test (its datasets in a folder of their own)."""
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    mode = register_mode(throwaway_mode.OCCUPANCY)
    yield mode
    unregister_mode(mode.name)


def test_the_env_draws_a_registered_mode_and_refuses_its_bad_options(occupancy) -> None:
    env = gym.make("FetchCarryPush-v0", family="basic", obs_mode="occupancy", occupancy_size=12)
    check_env(env.unwrapped, skip_render_check=True)
    observation, _ = env.reset(seed=3)
    grid = observation["occupancy"]
    assert grid.shape == (1, 12, 12) and np.count_nonzero(grid == 255) == 1 and np.any(grid == 128)
    with pytest.raises(ValueError, match="occupancy_size must be at least 8"):
        gym.make("FetchCarryPush-v0", obs_mode="occupancy", occupancy_size=4)
    with pytest.raises(ValueError, match="takes no option"):
        gym.make("FetchCarryPush-v0", obs_mode="occupancy", camera_size=32)


def test_a_registered_mode_renders_trains_a_cnn_and_benchmarks(occupancy, capsys, tmp_path: Path) -> None:
    source, rendered, run_dir = "fetchcarry/occ-src-v0", "fetchcarry/occ-v0", tmp_path / "occ-bc"
    steps = [
        ("generate", "--family", "basic", "--policy", "expert", "--interface", "phases", "--episodes", 2,
         "--dataset-id", source, "--no-progress"),
        ("dataset", "render", source, "--obs-mode", "occupancy", "--occupancy-size", 16, "--out", rendered,
         "--no-progress"),
        ("train", "bc", "--dataset", rendered, "--encoder", "cnn", "--obs-mode", "occupancy", "--epochs", 2,
         "--out", run_dir, "--no-progress"),
        ("benchmark", "--policies", run_dir, "--split", "iid", "--episodes", 2, "--no-progress", "--out",
         tmp_path / "bench"),
    ]  # fmt: skip
    for argv in steps:
        status, _, err = run(capsys, *argv)
        assert status == 0, (argv[:2], err)
    assert load(rendered)[0].observations["occupancy"].shape[1:] == (1, 16, 16)
    records = [r for r in read_results(tmp_path / "bench" / "results.json") if r["policy"] == "occ-bc"]
    assert len(records) == 2 and all(r["phases"] >= 1 for r in records)


def test_the_built_in_modes_are_records_of_the_same_table() -> None:
    names = [mode.name for mode in modes()]
    assert names[:3] == ["state", "topdown", "rgbd"] and "occupancy" not in names
