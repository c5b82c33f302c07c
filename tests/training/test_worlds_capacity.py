"""``--capacity`` on ``fetchcarry train ppo``, ``train dagger`` and ``benchmark``: the learner records it."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

from fetchcarry_env.observation import Capacity, observation_size
from training.cli import main
from training.envs import make_env
from training.errors import BenchmarkError
from training.evaluation.runner import with_capacity
from training.learners import runs
from training.learners.dagger import train_dagger
from training.learners.options import BCConfig, DaggerOptions, PPOOptions
from training.learners.ppo import train_ppo
from training.resolve import resolve

SIX = "objects=6,clutter=8,tables=6,obstacles=12,postures=4"
TINY_PPO = {"steps": 32, "n_steps": 32, "batch_size": 16, "n_epochs": 1, "hidden": 16, "checkpoint_every": 32}


@pytest.fixture(scope="module")
def ppo_runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A flat (mlp) and a set-encoder PPO run on ``basic`` trained with six object slots, and a flat one without."""
    torch.set_num_threads(1)
    root = tmp_path_factory.mktemp("ppo")
    train_ppo("basic", PPOOptions(**TINY_PPO, capacity="objects=6"), root / "mlp6", progress=False)
    train_ppo("basic", PPOOptions(**TINY_PPO, encoder="set", capacity="objects=6"), root / "set6", progress=False)
    train_ppo("basic", PPOOptions(**TINY_PPO), root / "mlp", progress=False)
    return {"mlp6": root / "mlp6", "set6": root / "set6", "mlp": root / "mlp"}


def test_ppo_records_the_capacity_it_was_trained_with(ppo_runs: dict[str, Path]) -> None:
    config = runs.read_config(ppo_runs["mlp6"])
    assert config["capacity"] == {"objects": 6, "clutter": 8, "tables": 6, "obstacles": 12, "postures": 4}
    assert config["features"] == observation_size(Capacity(objects=6)) != observation_size(Capacity())
    assert config["options"]["capacity"] == SIX
    policy = runs.load_policy(ppo_runs["mlp6"], make_env("phases", family="basic", capacity=SIX))
    assert policy.capacity == Capacity(objects=6)


def test_without_capacity_the_run_folder_is_as_before(ppo_runs: dict[str, Path]) -> None:
    config = runs.read_config(ppo_runs["mlp"])
    assert "capacity" not in config["options"]  # the family's: config.json as before the option existed
    assert config["capacity"] == {"objects": 4, "clutter": 8, "tables": 6, "obstacles": 12, "postures": 4}


def test_train_ppo_takes_capacity_on_the_command_line(tmp_path: Path) -> None:
    args = ["train", "ppo", "--family", "basic", "--steps", "32", "--n-steps", "32", "--hidden", "16",
            "--capacity", "clutter=10", "--out", str(tmp_path / "run"), "--no-progress"]  # fmt: skip
    assert main(args) == 0
    assert runs.read_config(tmp_path / "run")["capacity"]["clutter"] == 10


@pytest.mark.parametrize(
    "command",
    [
        ["train", "ppo", "--family", "basic"],
        ["train", "dagger", "--family", "basic"],
        ["benchmark", "--policies", "expert", "--split", "iid"],
    ],
)
@pytest.mark.parametrize("capacity", ["objets=6", "objects=-1", "objects=100000"])
def test_a_bad_capacity_is_bad_input(command: list[str], capacity: str, tmp_path: Path, capsys) -> None:
    with pytest.raises(SystemExit) as stopped:
        main([*command, "--capacity", capacity, "--out", str(tmp_path / "out")])
    assert stopped.value.code == 2
    assert "capacity" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_dagger_records_the_capacity_and_labels_at_it(tmp_path: Path) -> None:
    torch.set_num_threads(1)
    options = DaggerOptions(demonstrations=2, iterations=1, episodes_per_iteration=1, eval_episodes=1, epochs=1,
                            capacity="objects=5")  # fmt: skip
    rows = train_dagger("objects-1", options, BCConfig(hidden=16), tmp_path / "run", progress=False)
    assert [row["iteration"] for row in rows] == [0, 1]
    config = runs.read_config(tmp_path / "run")
    assert config["capacity"]["objects"] == 5 and config["options"]["capacity"].startswith("objects=5,")
    checkpoint = runs.load_checkpoint(tmp_path / "run")
    assert checkpoint["observations"].shape[1] == observation_size(Capacity(objects=5)) == config["features"]


def test_benchmark_capacity_goes_to_every_policy_a_flat_network_only_at_its_own(ppo_runs: dict[str, Path]) -> None:
    eight = {"objects": 8, "clutter": 8, "tables": 6, "obstacles": 12, "postures": 4}
    specs = with_capacity([resolve("expert"), resolve("random-phases"), resolve(str(ppo_runs["set6"]))], "objects=8")
    assert [s.env_options["capacity"] for s in specs] == [eight] * 3  # the set encoder acts at any capacity
    with pytest.raises(BenchmarkError, match=r"mlp6 was trained with the capacity objects=6.*--capacity objects=6"):
        with_capacity([resolve(str(ppo_runs["mlp6"]))], "objects=8")
    (same,) = with_capacity([resolve(str(ppo_runs["mlp6"]))], "objects=6")
    assert same.env_options["capacity"]["objects"] == 6
    unchanged = [resolve("expert")]
    assert with_capacity(unchanged, None) is unchanged


@pytest.mark.parametrize(
    "command",
    [
        ["train", "ppo", "--family", "objects-8", "--capacity", "objects=6"],
        ["train", "dagger", "--family", "objects-2", "--learner-families", "objects-6", "--capacity", "objects=5"],
    ],
)
def test_a_capacity_smaller_than_the_family_needs_is_refused_before_the_run_folder(
    command: list[str], tmp_path: Path, capsys
) -> None:
    assert main([*command, "--out", str(tmp_path / "run")]) == 2
    assert "does not hold family objects-" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
