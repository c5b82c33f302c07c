"""DAgger and MaskablePPO from pixels: tiny runs in topdown, their run folders, the recorded observation mode."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from fetchcarry_env.errors import InputError
from tests.cli_run import bench, run
from training.envs import make_env
from training.errors import BenchmarkError

TINY = {"obs_mode": "topdown", "topdown_size": 16, "topdown_frame": "world"}  # the env options of the tiny runs


@pytest.fixture(scope="module")
def dagger_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A DAgger run of the cnn on 16 x 16 topdown maps: 2 expert episodes, 1 iteration of 1 learner episode."""
    from training.learners.dagger import train_dagger
    from training.learners.options import BCConfig, DaggerOptions, ImageOptions

    out = tmp_path_factory.mktemp("obs") / "dagger-topdown"
    options = DaggerOptions(demonstrations=2, iterations=1, episodes_per_iteration=1, eval_episodes=1, epochs=2)
    config = BCConfig(encoder="cnn", obs_mode="topdown", hidden=16)
    rows = train_dagger("basic", options, config, out, ImageOptions(topdown_size=16), progress=False)
    assert [row["iteration"] for row in rows] == [0, 1]
    return out


def _act_once(run_dir: Path, env_options: dict) -> None:
    """Load ``run_dir`` for an env of ``env_options`` and take one step: an allowed candidate."""
    from training import load_policy

    env = make_env("phases", family="basic", **env_options)
    try:
        policy = load_policy(run_dir, env)
        observation, _ = env.reset(seed=3)
        action, _ = policy.predict(observation, deterministic=True)
        assert env.get_wrapper_attr("action_masks")()[int(action)]
        env.step(int(action))
    finally:
        env.close()


def test_dagger_from_topdown_labels_pixels_and_saves_a_run_that_loads_and_acts(dagger_run: Path):
    import torch

    from training.learners.runs import CHECKPOINT_FILE, read_config
    from training.resolve import resolve

    saved = read_config(dagger_run)
    assert saved["observation"] == TINY and saved["features"] == 7 * 16 * 16
    assert saved["config"]["obs_mode"] == "topdown" and saved["options"]["images"]["topdown_size"] == 16
    checkpoint = torch.load(dagger_run / CHECKPOINT_FILE, weights_only=True)
    labelled = checkpoint["observations"]
    assert labelled.dtype == torch.uint8 and labelled.shape[1] == 7 * 16 * 16 and len(labelled) >= 2
    assert int(labelled.max()) == 255  # map pixels, not the state vector
    spec = resolve(str(dagger_run))
    assert spec.env_options["obs_mode"] == "topdown" and spec.env_options["topdown_size"] == 16
    _act_once(dagger_run, spec.env_options)


def test_dagger_from_topdown_is_accepted_and_a_cnn_on_the_state_is_not():
    from training.learners.options import BCConfig, DaggerRun, PPOOptions

    DaggerRun(family="basic", config=BCConfig(encoder="cnn", obs_mode="topdown"))
    with pytest.raises(InputError, match="cnn"):
        DaggerRun(family="basic", config=BCConfig(encoder="cnn"))
    with pytest.raises(InputError, match="cnn"):
        PPOOptions(encoder="mlp", obs_mode="topdown")


def test_ppo_from_topdown_trains_with_the_masks_and_its_run_loads(tmp_path: Path):
    from training.learners.options import ImageOptions, PPOOptions
    from training.learners.ppo import train_ppo
    from training.learners.runs import read_config

    options = PPOOptions(steps=256, n_steps=128, batch_size=64, n_epochs=2, encoder="cnn", obs_mode="topdown",
                         hidden=16, checkpoint_every=128)  # fmt: skip
    rows = train_ppo("basic", options, tmp_path / "ppo", ImageOptions(topdown_size=16), progress=False)
    assert [row["steps"] for row in rows] == [128, 256]
    saved = read_config(tmp_path / "ppo")
    assert saved["complete"] and saved["observation"] == TINY and saved["config"]["encoder"] == "cnn"
    _act_once(tmp_path / "ppo", TINY)


def test_maskable_ppo_on_pixels_gets_the_envs_masks():
    """The actions MaskablePPO samples from topdown are the allowed ones, by the masks the env gave it."""
    from dataclasses import replace

    from fetchcarry_env.observation import Capacity
    from training.learners.options import BCConfig, PPOOptions
    from training.learners.ppo import actor_spec, make_model, make_vec_env

    env = make_vec_env("basic", 1, TINY)
    try:
        features = env.observation_space.shape[0]
        assert env.observation_space.dtype == np.uint8 and features == 7 * 16 * 16
        options = PPOOptions(steps=64, n_steps=64, n_epochs=1, encoder="cnn", obs_mode="topdown", hidden=16)
        config = BCConfig(encoder="cnn", obs_mode="topdown", hidden=16)
        capacity = env.get_attr("unwrapped")[0].capacity
        assert isinstance(capacity, Capacity)
        model = make_model(env, replace(options), actor_spec("basic", config, capacity, env.action_space.n, features))
        model.learn(64)
        buffer = model.rollout_buffer
        masks = buffer.action_masks.reshape(64, -1).astype(bool)
        actions = buffer.actions.reshape(64).astype(int)
        assert not masks.all() and masks[np.arange(64), actions].all()
        assert float(buffer.observations.max()) == 255.0  # it learned from pixels
    finally:
        env.close()


def test_the_recorded_obs_mode_round_trips_and_is_checked(dagger_run: Path, tmp_path: Path):
    import shutil

    from fetchcarry_env.observation import Capacity
    from training.learners.options import BCConfig
    from training.learners.runs import RunFolderError, read_config, run_config
    from training.resolve import run_image_options

    saved = read_config(dagger_run)
    assert run_image_options(saved) == TINY
    legacy = {k: v for k, v in saved.items() if k != "observation"}  # a run folder from before it was recorded
    assert run_image_options(legacy) == {"obs_mode": "topdown", "topdown_size": 16}
    state = run_config("bc", {}, BCConfig(), Capacity(), 10, 20, {})
    assert "observation" not in state  # state networks' run folders stay as they were
    image = run_config("bc", {}, BCConfig(encoder="cnn", obs_mode="topdown"), Capacity(), 10, 20, {})
    assert image["observation"] == {"obs_mode": "topdown", "topdown_size": 64, "topdown_frame": "world"}
    for observation in ({"obs_mode": "rgbd", "camera_size": 16}, {**TINY, "topdown_size": 32},
                        {**TINY, "camera_size": 16}, {**TINY, "topdown_frame": "left"}, "topdown"):  # fmt: skip
        broken = tmp_path / f"broken-{len(list(tmp_path.iterdir()))}"
        shutil.copytree(dagger_run, broken)
        (broken / "config.json").write_text(json.dumps({**saved, "observation": observation}))
        with pytest.raises(RunFolderError, match="observation"):
            read_config(broken)


def test_an_other_obs_mode_given_for_an_image_run_is_refused(dagger_run: Path, capsys: pytest.CaptureFixture):
    from training.resolve import PolicySpec, check_obs_mode, resolve

    spec = resolve(str(dagger_run))
    check_obs_mode(spec, None)
    check_obs_mode(spec, "topdown")
    with pytest.raises(BenchmarkError, match="trained on obs_mode 'topdown'"):
        check_obs_mode(spec, "state")
    check_obs_mode(PolicySpec("expert", "env", factory="expert"), "rgbd")  # a named policy acts in any mode
    status, _, err = run(capsys, "rollout", "--family", "basic", "--seed", "3", "--policy", dagger_run,
                         "--obs-mode", "rgbd")  # fmt: skip
    assert status == 2 and "trained on obs_mode 'topdown', not 'rgbd'" in err
    status, out, _ = run(capsys, "rollout", "--family", "basic", "--seed", "3", "--policy", dagger_run, "--json")
    assert status in (0, 1) and json.loads(out)["steps"] >= 1  # its env made in its own mode
    status, _, err = run(capsys, "benchmark", "--policies", dagger_run, "--split", "iid:dev", "--episodes", "1",
                         "--obs-mode", "state", "--out", dagger_run.parent / "bench")  # fmt: skip
    assert status == 2 and "trained on obs_mode 'topdown'" in err


def test_the_learned_study_evaluates_an_image_run_in_its_own_mode(dagger_run: Path, capsys: pytest.CaptureFixture):
    status, out, _ = bench(capsys, "learned", "--family", "basic", "--episodes", "1", dagger_run)
    assert status == 0 and "success" in out and "1 held-out seeds" in out
