"""Training commands at a tiny budget: phase datasets, BC, DAgger and PPO run folders, resume, loading."""

from __future__ import annotations

import json
import math
from pathlib import Path

import gymnasium as gym
import minari
import numpy as np
import pytest
import torch

import fetchcarry_env  # noqa: F401  (registers the env ids)
import training
from training.cli import main
from training.data.datasets import info, replay
from training.data.generate import EpisodeSource, GenerationConfig, generate
from training.data.staging import Staging
from training.learners import runs
from training.learners.bc import BCConfig
from training.learners.dagger import DaggerOptions, train_dagger
from training.learners.imitation import demonstrations_from_dataset
from training.learners.ppo import PPOOptions, train_ppo
from training.policies.phase_expert import MASK_INFO, PROJECTED_INFO

PHASES_ID = "fetchcarry/basic-phases-test-v0"
SOURCE = EpisodeSource(family="basic", seed=0, interface="phases")
EPISODES = 6  # seeds 0..5 of basic: before projection seeds 0, 2 and 3 ended unexpressible (see the first test)


@pytest.fixture(scope="module")
def phase_root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One phases dataset shared by the tests that read it."""
    root = tmp_path_factory.mktemp("minari")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(root))
        generate(GenerationConfig(PHASES_ID, EPISODES, SOURCE), progress=False)
    return root


@pytest.fixture
def phases_dataset(phase_root: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(phase_root))
    return PHASES_ID


def _weights(folder: Path) -> dict[str, torch.Tensor]:
    return torch.load(folder / runs.WEIGHTS_FILE, weights_only=True)


def _same_weights(a: Path, b: Path) -> bool:
    first, second = _weights(a), _weights(b)
    return first.keys() == second.keys() and all(torch.equal(first[k], second[k]) for k in first)


def _without_seconds(rows: list[dict]) -> str:
    """The rows without their wall-clock seconds, as text (so that NaN equals NaN)."""
    return json.dumps([{k: v for k, v in row.items() if k not in ("seconds", "eval_seconds")} for row in rows])


# ---------------------------------------------------------------------------- datasets in the phases interface
def test_phase_dataset_is_complete_with_projected_moves_and_replays(phases_dataset: str) -> None:
    dataset = minari.load_dataset(phases_dataset)
    size = gym.make("FetchCarryPushPhases-v0", family="basic").action_space.n
    projected = []
    for k, episode in enumerate(dataset.iterate_episodes()):
        mask = episode.infos[MASK_INFO]
        assert mask.shape == (len(episode.actions) + 1, size) and mask.dtype == bool
        assert mask[np.arange(len(episode.actions)), episode.actions].all()  # every action is an allowed candidate
        metadata = dataset.storage.get_episode_metadata([k]).__next__()
        assert metadata["outcome"] == "delivered" and episode.terminations[-1]  # none cut short: complete episodes
        steps = episode.infos[PROJECTED_INFO]
        assert not steps[0] and metadata["projected"] == steps.sum()
        projected.append(int(metadata["projected"]))
        assert replay(phases_dataset, k).reproduced
    assert projected[0] >= 1 and projected[2] >= 1 and projected[3] >= 1  # the seeds that used to be unexpressible
    assert info(phases_dataset)["projected_moves"] == sum(projected)
    demonstrations, _ = demonstrations_from_dataset(phases_dataset)
    assert demonstrations.stats["dropped"] == 0
    assert len(demonstrations) == dataset.total_steps
    assert demonstrations.masks[np.arange(len(demonstrations)), demonstrations.labels].all()


def test_env_interface_manifest_is_unchanged() -> None:
    manifest = GenerationConfig("fetchcarry/x-v0", 1, EpisodeSource(family="basic")).manifest()
    assert "interface" not in manifest  # datasets made before --interface keep matching their staging
    phases = GenerationConfig("fetchcarry/x-v0", 1, SOURCE).manifest()
    assert phases["interface"] == "phases" and phases["inexpressible_moves"] == "nearest move candidate"


def test_phase_generation_resumes_after_an_interruption() -> None:
    config = GenerationConfig("fetchcarry/basic-phases-resume-v0", 3, SOURCE)

    def stop(index: int, record: object) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        generate(config, progress=False, on_episode=stop)
    assert len(Staging(config.dataset_id).staged()) == 1
    report = generate(config, progress=False)
    assert (report.resumed, report.generated) == (1, 2)
    assert replay(config.dataset_id, 0).reproduced


def test_cli_generate_phases_and_train_bc_rejects_an_env_dataset(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["generate", "--family", "basic", "--episodes", "1", "--interface", "phases", "--dataset-id",
                 "fetchcarry/p-v0", "--no-progress"]) == 0  # fmt: skip
    capsys.readouterr()
    assert main(["dataset", "info", "fetchcarry/p-v0"]) == 0
    out = capsys.readouterr().out  # basic seed 0 has one projected move
    assert "projected   1 expert moves recorded as their nearest move candidate (1.00 per episode)" in out
    assert main(["generate", "--family", "basic", "--episodes", "1", "--dataset-id", "fetchcarry/e-v0",
                 "--no-progress"]) == 0  # fmt: skip
    status = main(["train", "bc", "--dataset", "fetchcarry/e-v0", "--epochs", "1", "--out", str(tmp_path / "r")])
    assert status == 2


# ---------------------------------------------------------------------------- bc
def _bc(dataset: str, out: Path, *extra: str) -> int:
    return main(["train", "bc", "--dataset", dataset, "--epochs", "3", "--hidden", "32", "--out", str(out),
                 "--no-progress", *extra])  # fmt: skip


def test_train_bc_is_deterministic_and_resumes_to_the_same_weights(
    phases_dataset: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert _bc(phases_dataset, tmp_path / "a") == 0
    assert _bc(phases_dataset, tmp_path / "b") == 0
    assert _same_weights(tmp_path / "a", tmp_path / "b")
    assert _without_seconds(runs.read_metrics(tmp_path / "a")) == _without_seconds(runs.read_metrics(tmp_path / "b"))
    config = json.loads((tmp_path / "a" / runs.CONFIG_FILE).read_text())
    assert config["kind"] == "bc" and config["interface"] == "phases" and config["complete"]
    assert config["options"]["dataset"] == phases_dataset and config["options"]["epochs"] == 3

    real, calls = runs.write_metrics, []

    def interrupt_second_epoch(folder: Path, rows: list) -> None:
        calls.append(len(rows))
        if len(calls) == 2:
            raise KeyboardInterrupt
        real(folder, rows)

    monkeypatch.setattr(runs, "write_metrics", interrupt_second_epoch)
    assert _bc(phases_dataset, tmp_path / "c") == 130
    monkeypatch.setattr(runs, "write_metrics", real)
    assert (tmp_path / "c" / runs.CHECKPOINT_FILE).exists() and not (tmp_path / "c" / runs.WEIGHTS_FILE).exists()
    assert _bc(phases_dataset, tmp_path / "c") == 2  # a run is there: resume it or choose another folder
    assert _bc(phases_dataset, tmp_path / "c", "--resume") == 0
    assert _same_weights(tmp_path / "a", tmp_path / "c")
    assert len(runs.read_metrics(tmp_path / "c")) == 3
    assert _bc(phases_dataset, tmp_path / "c", "--resume") == 0  # complete: nothing to do


def test_train_bc_on_the_first_episodes_of_a_dataset(phases_dataset: str, tmp_path: Path, capsys) -> None:
    assert _bc(phases_dataset, tmp_path / "all") == 0
    assert _bc(phases_dataset, tmp_path / "two", "--episodes", "2") == 0
    everything, two = (json.loads((tmp_path / n / runs.CONFIG_FILE).read_text()) for n in ("all", "two"))
    assert "episodes" not in everything["options"] and two["options"]["episodes"] == 2
    assert two["data"]["episodes"] == 2 and everything["data"]["episodes"] == EPISODES
    assert 0 < two["data"]["labelled"] < everything["data"]["labelled"]
    capsys.readouterr()
    assert _bc(phases_dataset, tmp_path / "many", "--episodes", str(EPISODES + 1)) == 2
    assert f"has {EPISODES} episodes" in capsys.readouterr().err


def test_rollout_takes_a_run_folder(phases_dataset: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert _bc(phases_dataset, tmp_path / "run") == 0
    capsys.readouterr()
    status = main(["rollout", "--family", "basic", "--seed", "100000", "--policy", str(tmp_path / "run"), "--json"])
    figures = json.loads(capsys.readouterr().out)
    assert status == (0 if figures["success"] else 1) and figures["steps"] >= 1
    picture = tmp_path / "learned.png"  # a picture of the learned episode: its actions are candidate indices
    assert main(["rollout", "--family", "basic", "--seed", "100000", "--policy", str(tmp_path / "run"),
                 "--render", str(picture)]) == status  # fmt: skip
    assert picture.stat().st_size > 10_000
    assert main(["rollout", "--family", "basic", "--policy", str(tmp_path / "missing")]) == 2


# ---------------------------------------------------------------------------- loading run folders
@pytest.mark.parametrize(
    "edit",
    [
        lambda c: {**c, "surprise": 1},
        lambda c: {**c, "kind": "sorcery"},
        lambda c: {k: v for k, v in c.items() if k != "capacity"},
        lambda c: {**c, "config": {**c["config"], "layers": 9}},
        lambda c: {**c, "config": {**c["config"], "hidden": "many"}},
        lambda c: {**c, "candidates": True},
        lambda c: {**c, "interface": "env"},
        lambda c: [c],
    ],
)
def test_bad_config_is_a_value_error_and_exit_2(phases_dataset: str, tmp_path: Path, edit) -> None:
    assert _bc(phases_dataset, tmp_path / "run") == 0
    file = tmp_path / "run" / runs.CONFIG_FILE
    file.write_text(json.dumps(edit(json.loads(file.read_text()))))
    with pytest.raises(ValueError):
        training.load_policy(tmp_path / "run")
    assert main(["rollout", "--family", "basic", "--policy", str(tmp_path / "run")]) == 2


def test_weights_that_do_not_fit_are_a_value_error(phases_dataset: str, tmp_path: Path) -> None:
    assert _bc(phases_dataset, tmp_path / "run") == 0
    torch.save({"nothing": torch.zeros(1)}, tmp_path / "run" / runs.WEIGHTS_FILE)
    with pytest.raises(ValueError):
        training.load_policy(tmp_path / "run")


def _unfinished(phases_dataset: str, folder: Path) -> dict:
    """A finished bc run made unfinished again (no model.pt, not complete): its checkpoint, to edit."""
    assert _bc(phases_dataset, folder) == 0
    config = json.loads((folder / runs.CONFIG_FILE).read_text())
    (folder / runs.CONFIG_FILE).write_text(json.dumps({**config, "complete": False}))
    (folder / runs.WEIGHTS_FILE).unlink()
    return torch.load(folder / runs.CHECKPOINT_FILE, weights_only=True)


@pytest.mark.parametrize("epoch", [10**6, 4, -1, "3", 2.5])
def test_resume_refuses_a_checkpoint_beyond_the_runs_epochs(phases_dataset: str, tmp_path: Path, capsys, epoch):
    checkpoint = _unfinished(phases_dataset, tmp_path / "run")
    torch.save({**checkpoint, "epoch": epoch}, tmp_path / "run" / runs.CHECKPOINT_FILE)
    capsys.readouterr()
    assert _bc(phases_dataset, tmp_path / "run", "--resume") == 2  # before: 0, complete with no training
    assert str(tmp_path / "run" / runs.CHECKPOINT_FILE) in capsys.readouterr().err
    assert not (tmp_path / "run" / runs.WEIGHTS_FILE).exists()


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_resume_and_load_refuse_weights_that_are_not_finite(phases_dataset: str, tmp_path: Path, capsys, bad):
    checkpoint = _unfinished(phases_dataset, tmp_path / "run")
    network = {k: torch.full_like(v, bad) if v.is_floating_point() else v for k, v in checkpoint["network"].items()}
    torch.save({**checkpoint, "network": network}, tmp_path / "run" / runs.CHECKPOINT_FILE)
    capsys.readouterr()
    assert _bc(phases_dataset, tmp_path / "run", "--resume") == 2
    assert "not all finite" in capsys.readouterr().err
    assert _bc(phases_dataset, tmp_path / "done") == 0
    weights = _weights(tmp_path / "done")
    torch.save({k: torch.full_like(v, bad) for k, v in weights.items()}, tmp_path / "done" / runs.WEIGHTS_FILE)
    with pytest.raises(runs.RunFolderError, match="not all finite"):  # before: it loaded and "delivered"
        training.load_policy(tmp_path / "done")


def test_a_failed_ppo_init_leaves_no_run_folder_behind(phases_dataset: str, tmp_path: Path, capsys) -> None:
    assert _bc(phases_dataset, tmp_path / "bc") == 0
    (tmp_path / "bc" / runs.WEIGHTS_FILE).write_bytes(b"not a zip of tensors")
    args = ["train", "ppo", "--family", "basic", "--steps", "32", "--n-steps", "32", "--init", str(tmp_path / "bc"),
            "--out", str(tmp_path / "ppo"), "--no-progress"]  # fmt: skip
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert str(tmp_path / "bc" / runs.WEIGHTS_FILE) in err and "weights_only" not in err
    assert not (tmp_path / "ppo" / runs.CONFIG_FILE).exists()  # before: the retry said "already holds a run"


# ---------------------------------------------------------------------------- dagger
TINY_DAGGER = DaggerOptions(demonstrations=2, iterations=1, episodes_per_iteration=2, eval_episodes=2, epochs=2)
TINY_NET = BCConfig(hidden=16, seed=3)


def test_dagger_is_deterministic_and_counts_labels(tmp_path: Path) -> None:
    first = train_dagger("basic", TINY_DAGGER, TINY_NET, tmp_path / "a", progress=False)
    second = train_dagger("basic", TINY_DAGGER, TINY_NET, tmp_path / "b", progress=False)
    assert _without_seconds(first) == _without_seconds(second)
    assert _same_weights(tmp_path / "a", tmp_path / "b")
    assert [row["iteration"] for row in first] == [0, 1]
    assert 0 < first[0]["expert_labels"] < first[1]["expert_labels"]
    assert all(0.0 <= row["heldout_success"] <= 1.0 for row in first)
    assert math.isnan(first[0]["learner_success"]) and 0.0 <= first[1]["learner_success"] <= 1.0
    policy = training.load_policy(tmp_path / "a")
    env = gym.make("FetchCarryPushPhases-v0", family="basic")
    observation, _ = env.reset(seed=1)
    mask = env.get_wrapper_attr("action_masks")()
    action, _ = policy.predict(observation, action_masks=mask)
    assert mask[int(action)]


def test_dagger_options_are_checked_and_nearest_moves_only_add_labels(tmp_path: Path) -> None:
    with pytest.raises(ValueError):
        DaggerOptions(demonstrations=0)
    plain = train_dagger("basic", TINY_DAGGER, TINY_NET, tmp_path / "a", progress=False)
    nearest = DaggerOptions(**{**TINY_DAGGER.__dict__, "nearest_moves": True})
    rows = train_dagger("basic", nearest, TINY_NET, tmp_path / "b", progress=False)
    assert rows[0]["expert_labels"] == plain[0]["expert_labels"]  # iteration 0: the expert's own episodes
    assert rows[1]["unexpressible"] <= plain[1]["unexpressible"]
    assert rows[1]["expert_labels"] >= plain[1]["expert_labels"]


def test_learner_families_aim_the_learner_episodes_and_leave_iteration_0(tmp_path: Path) -> None:
    from fetchcarry_env.observation import Capacity, observation_layout
    from training.learners.dagger import LabelTask

    task = LabelTask("basic", 0, 10.0, families=("push", "multi-2"))
    assert [task.family_of(k) for k in range(3)] == ["push", "multi-2", "push"]
    assert LabelTask("basic", 0, 10.0).family_of(5) == "basic"
    with pytest.raises(ValueError, match="unknown scenario family"):
        train_dagger("basic", DaggerOptions(learner_families=("nope",)), TINY_NET, tmp_path / "bad", progress=False)

    def clutter_rows(options: DaggerOptions, out: Path) -> tuple[int, int, int]:
        rows = train_dagger("basic", options, TINY_NET, out, progress=False)
        saved = runs.load_checkpoint(out)
        observations = saved["observations"].numpy()
        layout = observation_layout(Capacity(**runs.read_config(out)["capacity"]))
        present = observations[:, layout["clutter"]].reshape(len(observations), -1, 6)[:, :, 0].any(axis=1)
        first = int(rows[0]["expert_labels"])
        return first, int(present[:first].sum()), int(present[first:].sum())

    first, before, after = clutter_rows(TINY_DAGGER, tmp_path / "basic")
    assert before == after == 0  # basic draws no clutter
    aimed = DaggerOptions(**{**TINY_DAGGER.__dict__, "learner_families": ("push",)})
    first_aimed, before, after = clutter_rows(aimed, tmp_path / "push")
    assert first_aimed == first and before == 0  # iteration 0: the run's own family, the same labels
    assert after > 0  # the learner's episodes were drawn from push (clutter on the goal)
    assert runs.read_config(tmp_path / "push")["options"]["learner_families"] == ["push"]
    resumed = train_dagger("basic", aimed, TINY_NET, tmp_path / "push", resume=True, progress=False)
    assert int(resumed[0]["expert_labels"]) == first_aimed  # the complete run, loaded: the same options


def test_learner_families_on_the_command_line(capsys, tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["train", "dagger", "--family", "basic", "--learner-families", "push,nope", "--out", str(tmp_path / "r")])
    assert exit_info.value.code == 2 and "expected family names" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_dagger_can_start_from_a_phases_dataset(phases_dataset: str, tmp_path: Path) -> None:
    from fetchcarry_env.errors import InputError

    options = DaggerOptions(**{**TINY_DAGGER.__dict__, "dataset": phases_dataset, "demonstrations": 3})
    rows = train_dagger("basic", options, TINY_NET, tmp_path / "run", progress=False)
    demonstrations, _ = demonstrations_from_dataset(phases_dataset, 3)
    assert rows[0]["expert_labels"] == len(demonstrations)  # iteration 0: the dataset's labels, no new episode
    assert rows[1]["expert_labels"] > rows[0]["expert_labels"]  # then the learner's states, labelled as before
    saved = runs.load_checkpoint(tmp_path / "run")
    np.testing.assert_array_equal(saved["labels"].numpy()[: len(demonstrations)], demonstrations.labels)
    with pytest.raises(InputError, match="not the first 99"):
        train_dagger("basic", DaggerOptions(**{**options.__dict__, "demonstrations": 99}), TINY_NET,
                     tmp_path / "too-many", progress=False)  # fmt: skip
    assert not (tmp_path / "too-many").exists()


def test_an_episode_without_a_label_gives_empty_arrays(monkeypatch: pytest.MonkeyPatch) -> None:
    # A learner episode whose every state has an expert action no candidate expresses (seen on the
    # training family at DAgger's default budget) labels nothing; the aggregate must still take it.
    from fetchcarry_env.phase_env import PhaseActions
    from training.learners.dagger import LabelTask, label_episode

    monkeypatch.setattr(PhaseActions, "index_of", lambda self, action: None)
    episode = label_episode(LabelTask("basic", 0, 10.0), 0)
    assert episode.unexpressible == episode.steps > 0
    assert episode.observations.shape[0] == episode.masks.shape[0] == episode.labels.shape[0] == 0
    assert episode.observations.shape[1] > 0 and episode.masks.shape[1] > 0


def test_dagger_labels_the_same_on_a_worker_pool(tmp_path: Path) -> None:
    serial = train_dagger("basic", TINY_DAGGER, TINY_NET, tmp_path / "a", progress=False)
    pooled = train_dagger("basic", TINY_DAGGER, TINY_NET, tmp_path / "b", workers=2, progress=False)
    assert _without_seconds(serial) == _without_seconds(pooled)


def test_dagger_resumes_after_an_interruption(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    options = DaggerOptions(demonstrations=2, iterations=2, episodes_per_iteration=1, eval_episodes=1, epochs=2)
    whole = train_dagger("basic", options, TINY_NET, tmp_path / "whole", progress=False)
    real = runs.write_metrics

    def stop_after_first_iteration(folder: Path, rows: list) -> None:
        real(folder, rows)
        if len(rows) == 2:
            raise KeyboardInterrupt

    monkeypatch.setattr(runs, "write_metrics", stop_after_first_iteration)
    with pytest.raises(KeyboardInterrupt):
        train_dagger("basic", options, TINY_NET, tmp_path / "cut", progress=False)
    monkeypatch.setattr(runs, "write_metrics", real)
    resumed = train_dagger("basic", options, TINY_NET, tmp_path / "cut", resume=True, progress=False)
    assert _without_seconds(resumed) == _without_seconds(whole)
    assert _same_weights(tmp_path / "whole", tmp_path / "cut")


# ---------------------------------------------------------------------------- ppo
TINY_PPO = PPOOptions(
    steps=64, n_steps=32, batch_size=16, n_epochs=2, hidden=32, checkpoint_every=32, seed=1, eval_episodes=2
)


def test_ppo_is_deterministic_and_logs_learning_curves(tmp_path: Path) -> None:
    first = train_ppo("basic", TINY_PPO, tmp_path / "a", progress=False)
    second = train_ppo("basic", TINY_PPO, tmp_path / "b", progress=False)
    assert _without_seconds(first) == _without_seconds(second)
    assert _same_weights(tmp_path / "a", tmp_path / "b")
    assert [row["steps"] for row in first] == [32, 64]
    assert {"seconds", "success", "return", "paper_return", "travel_cost", "episodes"} <= set(first[0])
    config = runs.read_config(tmp_path / "a")
    assert config["kind"] == "ppo" and config["options"]["steps"] == 64 and config["complete"]
    assert type(training.load_policy(tmp_path / "a")).__name__ == "BCPolicy"


def test_ppo_starts_from_a_bc_run(phases_dataset: str, tmp_path: Path) -> None:
    assert _bc(phases_dataset, tmp_path / "bc") == 0
    options = PPOOptions(
        steps=32, n_steps=32, batch_size=16, n_epochs=1, learning_rate=1e-12, init=str(tmp_path / "bc"), eval_episodes=2
    )
    train_ppo("basic", options, tmp_path / "ppo", progress=False)
    bc, ppo = _weights(tmp_path / "bc"), _weights(tmp_path / "ppo")
    assert bc.keys() == ppo.keys() and all(torch.allclose(bc[k], ppo[k], atol=1e-6) for k in bc)
    assert runs.read_config(tmp_path / "ppo")["options"]["hidden"] == 32  # the init run's network


def test_ppo_interrupted_by_ctrl_c_resumes_to_completion(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    options = PPOOptions(
        steps=96, n_steps=32, batch_size=16, n_epochs=1, hidden=16, checkpoint_every=32, eval_episodes=2
    )
    args = ["train", "ppo", "--family", "basic", "--steps", "96", "--n-steps", "32", "--hidden", "16",
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
    assert main([*args, "--resume"]) == 0
    rows = runs.read_metrics(tmp_path / "run")
    assert [row["steps"] for row in rows] == [32, 64, 96]
    assert runs.read_config(tmp_path / "run")["complete"] and options.steps == 96
