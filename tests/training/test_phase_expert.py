"""The MILP expert acts in the env it was given: on ``FetchCarryPushPhases-v0`` it answers candidate indices.

``ExpertPolicy(env)`` on the phases env converts each of its plan's env actions to the
allowed candidate that stands for it (a move none stands for: the nearest allowed move),
the conversion :class:`~training.policies.phase_expert.PhaseExpert` (``expert-phases``)
is made of; ``interface="env"`` keeps the planner's own env actions (the labellers').
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import fetchcarry_env  # noqa: F401  (registers the env ids)
from expert.policy import DEFAULT_TIME_LIMIT, ExpertPolicy
from training.policies.phase_expert import PhaseExpert
from training.resolve import FACTORIES, build, resolve
from training.rollout import run_episode

PHASES = "FetchCarryPushPhases-v0"
SEED = 0  # a basic scenario the expert delivers


def test_the_expert_runs_a_whole_episode_in_the_phases_env_it_was_given() -> None:
    """A plain Gymnasium loop: every answer is an action of the env's ``Discrete`` space, and it delivers."""
    env = gym.make(PHASES, family="basic")
    policy = ExpertPolicy(env)
    observation, _ = env.reset(seed=SEED)
    terminated = truncated = False
    while not (terminated or truncated):
        action, _ = policy.predict(observation)
        assert env.action_space.contains(action)
        observation, _reward, terminated, truncated, info = env.step(action)
    assert terminated and info["is_success"]
    env.close()


def test_the_phase_expert_is_the_expert_on_the_phases_env() -> None:
    """``PhaseExpert`` (``expert-phases``) takes the same actions as ``ExpertPolicy`` on the same env."""
    env = gym.make(PHASES, family="basic")
    phase = run_episode(env, PhaseExpert(env), SEED, record_masks=True)
    plain = run_episode(env, ExpertPolicy(env), SEED, record_masks=True)
    env.close()
    assert phase.figures.success and np.array_equal(phase.actions, plain.actions)
    assert np.array_equal(phase.infos["projected"], plain.infos["projected"])


def test_the_phase_expert_plans_with_the_experts_time_limit_by_default() -> None:
    env = gym.make(PHASES, family="basic")
    assert PhaseExpert(env).time_limit == ExpertPolicy(env).time_limit == DEFAULT_TIME_LIMIT
    assert FACTORIES["expert-phases"].options["time_limit"] == DEFAULT_TIME_LIMIT
    assert build(resolve("expert-phases"), env).time_limit == DEFAULT_TIME_LIMIT


def test_interface_env_keeps_the_planners_own_env_actions_on_the_phases_env() -> None:
    env = gym.make(PHASES, family="basic")
    observation, _ = env.reset(seed=SEED)
    action, _ = ExpertPolicy(env, interface="env").predict(observation)
    assert np.shape(action) == (5,) and env.get_wrapper_attr("index_of")(action) is not None


@pytest.mark.parametrize(
    ("make", "interface", "problem"),
    [
        (lambda: gym.make("FetchCarryPush-v0", family="basic"), "phases", "FetchCarryPushPhases-v0"),
        (lambda: gym.vector.SyncVectorEnv([lambda: gym.make(PHASES, family="basic")] * 2), None, 'interface="env"'),
        (lambda: gym.make(PHASES, family="basic"), "candidates", "interface must be"),
    ],
)
def test_an_expert_that_cannot_answer_in_its_interface_is_refused_at_construction(make, interface, problem) -> None:
    with pytest.raises(ValueError, match=problem):
        ExpertPolicy(make(), interface=interface)


def test_the_phase_expert_refuses_a_plain_env() -> None:
    with pytest.raises(ValueError, match="FetchCarryPushPhases-v0"):
        PhaseExpert(gym.make("FetchCarryPush-v0", family="basic"))
