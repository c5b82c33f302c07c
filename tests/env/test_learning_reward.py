"""LearningReward: the paper's reward kept, potential-based shaping on progress, refusals dearer than moves."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from expert import ExpertPolicy
from fetchcarry_env.phase_env import make_phase_env
from fetchcarry_env.shaping import DEFAULT_STAGE, LearningReward, potential

ENV_ID = "FetchCarryPushPhases-v0"


def expert_run(env: gym.Env, seed: int) -> list[tuple[float, dict]]:
    """The expert's episode through the candidates: ``(reward, info)`` per step."""
    expert = ExpertPolicy(env, interface="env")  # the plan's env actions, mapped here
    observation, _ = env.reset(seed=seed)
    out = []
    for step in range(20):
        action, _ = expert.predict(observation, episode_start=step == 0)
        index = env.get_wrapper_attr("index_of")(action)
        assert index is not None, "pick a seed whose expert actions are all candidates"
        observation, reward, terminated, _truncated, info = env.step(index)
        out.append((reward, info))
        if terminated:
            break
    return out


def test_the_default_reward_and_info_are_the_papers():
    paper = expert_run(gym.make(ENV_ID, family="basic"), seed=4)
    learning = expert_run(gym.make(ENV_ID, family="basic", reward="learning"), seed=4)
    assert [r for r, _ in paper] == [i["paper_reward"] for _, i in learning]
    assert paper[-1][1]["travel_cost"] == learning[-1][1]["travel_cost"]
    assert paper[-1][1]["is_success"]


def test_shaping_telescopes_to_minus_the_start_potential():
    env = gym.make(ENV_ID, family="basic", reward="learning", gamma=1.0)
    env.reset(seed=4)
    start = potential(env.unwrapped.scenario, env.unwrapped.state)
    run = expert_run(env, seed=4)
    assert start < -2 * DEFAULT_STAGE  # a pick and a place to go, and a way to travel
    assert sum(i["shaping"] for _, i in run) == pytest.approx(-start)
    assert potential(env.unwrapped.scenario, env.unwrapped.state) == 0.0
    # Each step of the expert's gets closer to done: the shaping pays for progress.
    assert all(i["shaping"] > 0 for _, i in run)


def test_a_refused_action_costs_more_than_any_move():
    env = LearningReward(make_phase_env(family="basic"))
    env.reset(seed=0)
    longest = env.longest_move_cost()
    assert longest == pytest.approx(14.0, abs=0.01)  # the 7 m x 7 m extent, corner to corner
    mask = env.get_wrapper_attr("action_masks")()
    _obs, reward, *_rest, info = env.step(int(np.flatnonzero(~mask)[0]))
    assert info["invalid_action"] is not None
    assert reward - info["shaping"] < -longest


@pytest.mark.parametrize("options", [{"gamma": 0.0}, {"gamma": 1.5}, {"stage": -1.0}, {"refusal_cost": 1.0}], ids=str)
def test_bad_options_raise(options):
    with pytest.raises(ValueError):
        LearningReward(make_phase_env(family="basic"), **options)
    with pytest.raises(ValueError):
        gym.make(ENV_ID, reward="cheap")
