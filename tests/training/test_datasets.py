"""Minari datasets: round trip, exact replay, resume after an interruption, no silent overwrite, backends."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import h5py
import minari
import numpy as np
import pytest

import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
from fetchcarry_env.errors import InputError
from fetchcarry_env.registration import do_nothing_return
from fetchcarry_env.scenario import Scenario
from training.data.datasets import dataset_exists, dataset_path, episode_metadata, info, replay
from training.data.generate import ClockDecidedError, EpisodeSource, GenerationConfig, generate, run_indexed_episode
from training.data.staging import Staging
from training.rollout import INFO_KEYS, is_timing

DATASET_ID = "fetchcarry/push-test-v0"
EPISODES = 3
SOURCE = EpisodeSource(family="push", seed=20)


def _generate(dataset_id: str = DATASET_ID, episodes: int = EPISODES, **options):
    return generate(GenerationConfig(dataset_id, episodes, SOURCE), progress=False, **options)


@pytest.fixture(scope="module")
def datasets_root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One generated dataset shared by the read-only tests of this module."""
    root = tmp_path_factory.mktemp("minari")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(root))
        _generate()
    return root


@pytest.fixture
def generated(datasets_root: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(datasets_root))
    return DATASET_ID


def test_round_trip_through_minari(generated: str) -> None:
    dataset = minari.load_dataset(generated)
    assert dataset.total_episodes == EPISODES
    env = dataset.recover_environment()
    for k, episode in enumerate(dataset.iterate_episodes()):
        metadata = episode_metadata(dataset, k)
        assert metadata["seed"] == SOURCE.seed + k
        assert metadata["success"] and metadata["outcome"] == "delivered" and metadata["failure"] is None
        # The stored scenario is the one the env draws from the seed, and a valid scenario file.
        observation, _ = env.reset(seed=metadata["seed"])
        assert Scenario.from_dict(metadata["scenario"]) == env.unwrapped.scenario
        assert set(episode.infos) == {key for key in INFO_KEYS if not is_timing(key)}  # no wall-clock time
        assert not any(is_timing(key) for key in metadata)
        assert len(episode.infos["planned"]) == len(episode.actions) + 1 and episode.infos["planned"][1]
        assert np.isfinite(episode.infos["objective"][1]) and np.isnan(episode.infos["objective"][2:]).all()
        # The recorded actions, replayed, give the recorded observations and final state, exactly.
        for key in observation:
            assert np.array_equal(observation[key], episode.observations[key][0])
        for t, action in enumerate(episode.actions):
            observation, reward, terminated, _, _ = env.step(action)
            for key in observation:
                assert np.array_equal(observation[key], episode.observations[key][t + 1])
            assert reward == pytest.approx(episode.rewards[t])
        assert terminated and env.unwrapped.state.holding is None
    env.close()


def test_an_expert_dataset_carries_the_scores_0_and_100_for_minaris_normalised_score(generated: str) -> None:
    dataset = minari.load_dataset(generated)
    returns = np.array([episode.rewards.sum() for episode in dataset.iterate_episodes()])
    floors = [do_nothing_return(len(episode_metadata(dataset, k)["scenario"]["objects"])) for k in range(EPISODES)]
    assert dataset.storage.metadata["ref_max_score"] == pytest.approx(returns.mean())  # the expert: 100
    assert dataset.storage.metadata["ref_min_score"] == pytest.approx(np.mean(floors))  # doing nothing: 0
    assert minari.get_normalized_score(dataset, returns).mean() == pytest.approx(1.0)
    assert minari.get_normalized_score(dataset, np.array(floors)).mean() == pytest.approx(0.0)


def test_replay_reports_an_exact_reproduction(generated: str) -> None:
    report = replay(generated, 1)
    assert report.reproduced and report.same_scenario and report.same_final_state
    assert report.max_observation_error == 0.0 and report.first_divergence is None


def test_info_summarises_outcomes_and_the_planner(generated: str) -> None:
    summary = info(generated)
    assert summary["episodes"] == EPISODES and summary["family"] == "push"
    assert summary["seeds"] == [SOURCE.seed, SOURCE.seed + EPISODES - 1]
    assert summary["success_rate"] == 1.0 and summary["outcomes"] == {"delivered": EPISODES}
    assert summary["plans"] >= EPISODES and summary["generation"]["policy"] == "expert"


def test_the_same_command_writes_the_same_dataset_byte_for_byte(tmp_path: Path, monkeypatch) -> None:
    """Two runs, one with two workers: the same files, bit for bit (the planner's seconds were stored before,
    and a tie between optimal plans was broken by each process's string hashing)."""
    source = EpisodeSource(family="push", seed=0)
    files = []
    for run, workers in (("first", 1), ("second", 2)):
        monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / run))
        generate(GenerationConfig(DATASET_ID, 3, source), progress=False, workers=workers)
        folder = dataset_path(DATASET_ID)
        files.append({p.relative_to(folder): p.read_bytes() for p in folder.rglob("*") if p.is_file()})
    assert files[0].keys() == files[1].keys() and Path("data/main_data.hdf5") in files[0]
    assert all(files[0][name] == files[1][name] for name in files[0])


def test_a_plan_the_safety_stop_decided_is_refused_and_the_finished_episodes_kept(tmp_path, monkeypatch) -> None:
    """Episode 1's planning call says the wall clock stopped it: generate refuses, names it, keeps episode 0."""
    from expert import policy as policy_module

    real = policy_module.planner.plan
    env = SOURCE.build_env()
    env.reset(seed=SOURCE.seed + 1)
    second_table = env.unwrapped.scenario.tables[0].rect.center  # the observed scenario has no name: a table
    env.close()

    def plan(scenario, **kwargs):
        result = real(scenario, **kwargs)
        if math.dist(scenario.tables[0].rect.center, second_table) < 1e-3:
            result.stats.update(clock_stopped=True, stopped_by="clock")
        return result

    monkeypatch.setattr(policy_module.planner, "plan", plan)
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    with pytest.raises(ClockDecidedError, match=r"episode 1 \(seed 21\).*--time-limit"):
        _generate(episodes=2)
    assert not dataset_exists(DATASET_ID) and Staging(DATASET_ID).staged() == {0}


def test_an_interrupted_run_resumes_and_loses_no_episode() -> None:
    def interrupt_after_the_first(index: int, _record) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _generate(on_episode=interrupt_after_the_first)
    assert not dataset_exists(DATASET_ID)
    assert Staging(DATASET_ID).staged() == {0}

    report = _generate()
    assert (report.resumed, report.generated) == (1, EPISODES - 1)
    assert not Staging(DATASET_ID).exists()
    dataset = minari.load_dataset(DATASET_ID)
    assert dataset.total_episodes == EPISODES
    for k, episode in enumerate(dataset.iterate_episodes()):
        assert np.array_equal(episode.actions, run_indexed_episode(SOURCE, k).actions)


def test_an_existing_dataset_is_never_overwritten_silently() -> None:
    _generate(episodes=1)
    before = (dataset_path(DATASET_ID) / "data" / "main_data.hdf5").stat().st_mtime_ns
    with pytest.raises(InputError, match="already exists"):
        _generate(episodes=2)
    assert (dataset_path(DATASET_ID) / "data" / "main_data.hdf5").stat().st_mtime_ns == before
    assert minari.load_dataset(DATASET_ID).total_episodes == 1
    report = _generate(episodes=2, overwrite=True)
    assert report.generated == 2 and minari.load_dataset(DATASET_ID).total_episodes == 2


def test_a_partial_run_with_other_options_is_not_mixed_in() -> None:
    Staging(DATASET_ID).start(GenerationConfig(DATASET_ID, 1, EpisodeSource(family="push", seed=99)).manifest())
    with pytest.raises(InputError, match="seed"):
        _generate()


def test_bad_ids_and_episodes_are_usage_errors(generated: str) -> None:
    with pytest.raises(InputError, match="not a Minari id"):
        info("no slashes or version")
    with pytest.raises(InputError, match="no dataset"):
        info("fetchcarry/missing-v0")
    with pytest.raises(InputError, match="out of range"):
        replay(generated, EPISODES)


def test_two_workers_make_the_same_dataset_as_one() -> None:
    _generate("fetchcarry/one-v0", workers=1)
    _generate("fetchcarry/two-v0", workers=2)
    one, two = minari.load_dataset("fetchcarry/one-v0"), minari.load_dataset("fetchcarry/two-v0")
    for a, b in zip(one.iterate_episodes(), two.iterate_episodes(), strict=True):
        assert np.array_equal(a.actions, b.actions) and np.array_equal(a.rewards, b.rewards)
        assert np.array_equal(a.observations["observation"], b.observations["observation"])


def test_ray_backend_makes_the_same_dataset_on_a_local_instance() -> None:
    ray = pytest.importorskip("ray")
    _generate("fetchcarry/local-v0", episodes=2)
    try:
        report = _generate("fetchcarry/ray-v0", episodes=2, workers=2, backend="ray")
    finally:
        if ray.is_initialized():
            ray.shutdown()
    assert report.backend == "ray" and report.generated == 2
    local, remote = minari.load_dataset("fetchcarry/local-v0"), minari.load_dataset("fetchcarry/ray-v0")
    for a, b in zip(local.iterate_episodes(), remote.iterate_episodes(), strict=True):
        assert np.array_equal(a.actions, b.actions)
        assert np.array_equal(a.observations["observation"], b.observations["observation"])


def test_a_tampered_episode_does_not_replay(tmp_path: Path, generated: str, monkeypatch) -> None:
    """A copy of the dataset with one recorded reward changed: the replay notices."""

    copy_root = tmp_path / "copy"
    shutil.copytree(dataset_path(generated).parent.parent, copy_root)
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(copy_root))
    with h5py.File(dataset_path(generated) / "data" / "main_data.hdf5", "r+") as file:
        file["episode_1"]["rewards"][0] += 1.0
    report = replay(generated, 1)
    assert not report.reproduced and not report.same_rewards
    assert json.loads(json.dumps(report.to_dict()))["episode"] == 1


def test_the_env_spec_recovers_a_fixed_scenario(spec_example: Scenario) -> None:
    source = EpisodeSource(scenario=spec_example.to_dict())
    generate(GenerationConfig("fetchcarry/fixed-v0", 1, source), progress=False)
    env = minari.load_dataset("fetchcarry/fixed-v0").recover_environment()
    env.reset(seed=0)
    assert env.unwrapped.scenario == spec_example
