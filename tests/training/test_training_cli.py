"""The training commands: rollout, demo, generate, dataset, evaluate-expert, train.

Run in-process through ``training.cli.main``. Exit statuses: 0 success, 1 a negative
answer, 2 bad input with a short message on stderr and never a traceback.
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import pytest
from cli_run import run
from PIL import Image

from fetchcarry_env.scenario import Scenario
from training.cli import main
from training.data.datasets import dataset_path

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"
DATASET_ID = "fetchcarry/cli-v0"


# ---------------------------------------------------------------------------- rollout and demo
def test_rollout_prints_the_figures_as_json(capsys) -> None:
    status, out, _ = run(capsys, "rollout", "--scenario", str(EXAMPLE), "--json")
    figures = json.loads(out)
    assert status == 0 and figures["success"] and figures["outcome"] == "delivered"
    assert figures["delivered"] == figures["objects"] == 1 and figures["plans"] == 1


def test_rollout_writes_a_gif_of_every_state(capsys, tmp_path: Path) -> None:
    gif = tmp_path / "episode.gif"
    status, out, _ = run(capsys, "rollout", "--family", "push", "--seed", "3", "--render", str(gif))
    assert status == 0 and f"picture    {gif}" in out
    steps = int(out.split(" after ")[1].split(" steps")[0])
    with Image.open(gif) as image:
        assert image.n_frames == steps + 1


def test_rollout_without_a_plan_is_a_negative_answer(capsys) -> None:
    status, out, _ = run(capsys, "rollout", "--scenario", str(EXAMPLE), "--time-limit", "0.0001")
    assert status == 1
    assert "outcome    planner_failed (time_limit): 0/1 object(s)" in out and "failure    no plan" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["rollout", "--scenario", "missing.json"], "missing.json"),
        (["rollout", "--family", "nope"], "unknown family 'nope'"),
        (["rollout", "--family", "push", "--render", "out.txt"], "cannot write a picture"),
        (["rollout", "--family", "push", "--render", "no/such/folder/x.png"], "does not exist"),
        (["demo", "--out", "episode.bmp"], "cannot write a picture"),
    ],
)
def test_bad_input_is_a_short_message_and_exit_2(capsys, argv: list[str], message: str) -> None:
    status, out, err = run(capsys, *argv)
    assert status == 2 and message in err and out == ""


def test_demo_writes_the_episode_picture_and_its_figures(capsys, tmp_path: Path) -> None:
    picture = tmp_path / "episode.png"
    status, out, _ = run(capsys, "demo", "--out", str(picture))
    assert status == 0
    assert "outcome    delivered: 1/1 object(s) at the goal" in out and "delivered: delivered" not in out
    with Image.open(picture) as image:
        assert image.size[0] >= 1200 and image.size[1] >= 900  # a map, a close-up and a strip of renders


# ---------------------------------------------------------------------------- datasets
@pytest.fixture
def dataset(capsys) -> str:
    status, out, _ = run(
        capsys, "generate", "--family", "push", "--seed", "5", "--episodes", "2", "--dataset-id", DATASET_ID,
        "--no-progress",
    )  # fmt: skip
    assert status == 0 and "2 episodes (0 resumed, 2 generated: 2 delivered everything)" in out
    return DATASET_ID


def test_generate_refuses_an_existing_id(capsys, dataset: str) -> None:
    status, _, err = run(capsys, "generate", "--family", "push", "--episodes", "2", "--dataset-id", dataset)
    assert status == 2 and "already exists" in err and "--overwrite" in err


def test_dataset_info(capsys, dataset: str) -> None:
    status, out, _ = run(capsys, "dataset", "info", dataset)
    assert status == 0 and "episodes    2" in out and "success rate 100.0%" in out
    status, out, _ = run(capsys, "dataset", "info", dataset, "--json")
    assert status == 0 and json.loads(out)["seeds"] == [5, 6]


def test_dataset_replay_exit_statuses(capsys, dataset: str) -> None:
    status, out, _ = run(capsys, "dataset", "replay", dataset, "--episode", "1")
    assert status == 0 and ": reproduced" in out
    status, _, err = run(capsys, "dataset", "replay", dataset, "--episode", "2")
    assert status == 2 and "out of range" in err
    with h5py.File(dataset_path(dataset) / "data" / "main_data.hdf5", "r+") as file:
        file["episode_0"]["observations"]["observation"][3, 0] += 0.5
    status, out, _ = run(capsys, "dataset", "replay", dataset, "--episode", "0")
    assert status == 1 and "NOT reproduced" in out and "first divergence at state 3" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["dataset", "info", "fetchcarry/absent-v0"], "no dataset 'fetchcarry/absent-v0'"),
        (["dataset", "info", "not an id"], "not a Minari id"),
        (["dataset", "replay", "fetchcarry/absent-v0", "--episode", "0"], "no dataset"),
        (["generate", "--family", "push", "--episodes", "1", "--dataset-id", "bad id"], "not a Minari id"),
    ],
)
def test_dataset_bad_input_is_exit_2(capsys, argv: list[str], message: str) -> None:
    status, _, err = run(capsys, *argv)
    assert status == 2 and message in err


def test_bad_numbers_are_argparse_errors(capsys) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["generate", "--family", "push", "--episodes", "0", "--dataset-id", DATASET_ID])
    assert exit_info.value.code == 2 and "--episodes: expected a positive number, got 0" in capsys.readouterr().err


# ---------------------------------------------------------------------------- evaluation and benchmark
def test_evaluate_expert_writes_every_failure_as_a_replayable_scenario(capsys, tmp_path: Path) -> None:
    """With a time limit too short to plan, every episode fails: each one is written out with its seed."""
    failures = tmp_path / "failures"
    status, out, _ = run(
        capsys, "evaluate-expert", "--families", "basic", "--episodes", "2", "--seed", "4", "--time-limit", "0.0001",
        "--failures-dir", str(failures), "--no-progress",
    )  # fmt: skip
    assert status == 1 and "failed: basic seed 4: planner_failed (time_limit)" in out
    for seed in (4, 5):
        scenario = Scenario.load(failures / f"basic-seed{seed}.json")
        sidecar = json.loads((failures / f"basic-seed{seed}.outcome.json").read_text())
        assert sidecar["seed"] == seed and sidecar["replay"] == f"fetchcarry rollout --family basic --seed {seed}"
        assert sidecar["scenario"] == scenario.name and sidecar["figures"]["failure"] == "no plan (time_limit)"


# ---------------------------------------------------------------------------- fetchcarry train
@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["train", "dagger", "--family", "nope"], "unknown family 'nope'"),
        (["train", "ppo", "--family", "nope"], "unknown family 'nope'"),
        (["train", "dagger", "--family", "basic", "--learner-families", "push,zz"], "expected family names"),
        (["train", "bc", "--dataset", "x/y-v0", "--epochs", "0"], "--epochs: expected a positive number, got 0"),
        (["train", "ppo", "--family", "basic", "--learning-rate", "-1"], "--learning-rate: expected a positive"),
        (["train", "ensemble", "--members", "a"], "at least two run folders"),
    ],
)
def test_bad_training_options_exit_2(capsys, tmp_path: Path, argv: list[str], message: str) -> None:
    status, out, err = run(capsys, *argv, "--out", tmp_path / "run")
    assert status == 2 and message in err and out == ""


def test_train_is_generated_from_the_options_dataclasses(capsys) -> None:
    status, out, _ = run(capsys, "train", "dagger", "--help")
    assert status == 0
    for text in ("--episodes-per-iteration N", "--time-limit S", "--learner-families NAME[,NAME...]",
                 "--workers W", "--backend {process,ray}", "--encoder {mlp,set,cnn}", "--no-progress"):  # fmt: skip
        assert text in out, text
    assert "epochs (per iteration for dagger; default 40)" in out and "(default 10)" in out
    status, out, _ = run(capsys, "train", "ensemble", "--help")
    assert "--no-avoid-returns" in out and "--seed" not in out and "--resume" not in out


def test_ctrl_c_keeps_the_checkpoint_and_a_bug_is_not_bad_input(capsys, tmp_path: Path, monkeypatch) -> None:
    from training.learners import imitation

    def interrupted(**options: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(imitation, "train_bc_run", interrupted)
    status, _, err = run(capsys, "train", "bc", "--dataset", "x/y-v0", "--out", tmp_path / "run")
    assert status == 130 and "the last checkpoint in" in err and "--resume" in err

    def broken(**options: object) -> None:
        raise ValueError("a bug in a library, not the user's input")

    monkeypatch.setattr(imitation, "train_bc_run", broken)
    status, _, err = run(capsys, "train", "bc", "--dataset", "x/y-v0", "--out", tmp_path / "run")
    assert status == 3 and "internal error: ValueError" in err
