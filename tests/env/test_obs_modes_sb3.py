"""stable-baselines3's MultiInputPolicy (a NatureCNN per image) and sb3-contrib's MaskablePPO, unchanged, on images."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

PHASES = "FetchCarryPushPhases-v0"


@pytest.mark.parametrize(("mode", "options"), [("topdown", {}), ("rgbd", {"camera_size": 36})])
def test_maskable_ppo_with_multi_input_policy_trains_and_acts_on_images(mode, options):
    import torch
    from sb3_contrib import MaskablePPO
    from stable_baselines3.common.torch_layers import NatureCNN

    torch.set_num_threads(1)
    env = gym.make(PHASES, family="basic", obs_mode=mode, **options)
    model = MaskablePPO("MultiInputPolicy", env, n_steps=16, batch_size=8, n_epochs=1, seed=0, device="cpu")
    extractors = model.policy.features_extractor.extractors
    images = [key for key, module in extractors.items() if isinstance(module, NatureCNN)]
    assert sorted(images) == sorted(k for k in env.observation_space.spaces if k.endswith(("topdown", "rgbd")))
    model.learn(total_timesteps=32)
    observation, _ = env.reset(seed=1)
    mask = env.get_wrapper_attr("action_masks")()
    action, _ = model.predict(observation, action_masks=mask, deterministic=True)
    assert mask[int(action)]  # a masked policy picks an allowed candidate
    env.close()


def test_ppo_with_multi_input_policy_runs_on_the_topdown_map():
    import torch
    from stable_baselines3 import PPO

    torch.set_num_threads(1)
    env = gym.make(PHASES, family="push", obs_mode="topdown")
    model = PPO("MultiInputPolicy", env, n_steps=16, batch_size=8, n_epochs=1, seed=0, device="cpu")
    model.learn(total_timesteps=16)
    action, _ = model.predict(env.reset(seed=0)[0])
    assert 0 <= int(np.asarray(action)) < env.action_space.n
    env.close()
