"""ExpertPolicy in the physics env: labels any state, keeps or replans its plan, checks actions, fails cleanly."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
from expert import ExpertPolicy
from fetchcarry_env.actions import Action, Mode
from fetchcarry_env.scenario import Scenario
from training.policies.random import RandomMaskedPolicy
from training.rollout import run_episode

SCENARIOS = Path(__file__).resolve().parent / "scenarios"
MAX_STEPS = 50  # the registration's time limit


def _finish(env: gym.Env, policy: ExpertPolicy, observation: dict) -> tuple[dict, list[Action]]:
    """Let ``policy`` act until the episode ends; return the last info and the actions taken."""
    taken = []
    for _ in range(MAX_STEPS):
        action, _ = policy.predict(observation, deterministic=True)
        taken.append(Action.from_array(action))
        observation, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return info, taken
    raise AssertionError("the episode did not end")


def test_a_whole_episode_follows_one_plan(spec_example: Scenario) -> None:
    env = gym.make("FetchCarryPush-v0", scenario=spec_example)
    observation, _ = env.reset(seed=0)
    policy = ExpertPolicy(env)
    info, taken = _finish(env, policy, observation)
    assert info["is_success"]
    assert Mode.PUSH in {a.mode for a in taken}  # the spec example's goal is covered by a block
    assert (policy.stats.plans, policy.stats.replans, policy.stats.failures) == (1, 0, 0)
    assert policy.last_plan is not None and len(taken) == len(policy.last_plan.phases) - 1


def test_a_fresh_expert_finishes_from_mid_episode_holding_the_object(spec_example: Scenario) -> None:
    """The expert plans from the observation alone: a state it never saw, with the bottle in the hand."""
    env = gym.make("FetchCarryPush-v0", scenario=spec_example)
    observation, _ = env.reset(seed=0)
    leader = ExpertPolicy(env)
    while env.unwrapped.state.holding is None:
        observation, *_ = env.step(leader.predict(observation)[0])
    assert env.unwrapped.state.holding == "bottle"
    fresh = ExpertPolicy(env)
    info, taken = _finish(env, fresh, observation)
    assert info["is_success"]
    assert taken[-1].mode == Mode.PLACE and Mode.PICK not in {a.mode for a in taken}
    assert fresh.stats.plans == 1


def test_the_expert_finishes_from_a_state_a_random_policy_drove_into() -> None:
    """DAgger's case: whatever a learner did first, the expert labels the state and completes the task."""
    env = gym.make("FetchCarryPush-v0", family="push")
    observation, _ = env.reset(seed=11)
    learner = RandomMaskedPolicy(env, seed=11)
    for _ in range(4):
        observation, *_ = env.step(learner.predict(observation)[0])
    info, _ = _finish(env, ExpertPolicy(env), observation)
    assert info["is_success"]


def test_replans_when_a_pushed_block_is_back_where_it_was(spec_example: Scenario) -> None:
    """After the push the block is put back on the goal behind the expert's back: it notices and pushes again."""
    env = gym.make("FetchCarryPush-v0", scenario=spec_example)
    observation, _ = env.reset(seed=0)
    policy = ExpertPolicy(env)
    while True:
        action, _ = policy.predict(observation)
        observation, *_ = env.step(action)
        if Action.from_array(action).mode == Mode.PUSH:
            break
    observation, _ = env.reset(seed=0)  # the world is back at the start; the policy is not told
    info, taken = _finish(env, policy, observation)
    assert info["is_success"]
    assert policy.stats.replans == 1
    assert sum(a.mode == Mode.PUSH for a in taken) == 1  # it pushed again


def test_replanning_reason_names_the_departure(spec_example: Scenario) -> None:
    env = gym.make("FetchCarryPush-v0", scenario=spec_example)
    observation, _ = env.reset(seed=0)
    policy = ExpertPolicy(env)
    observation, *_ = env.step(policy.predict(observation)[0])
    assert policy.last_decision.reason == "episode_start"
    observation, _ = env.reset(seed=0)  # back at the start: the base is not where the plan put it
    policy.predict(observation)
    assert policy.last_decision.replanned and policy.last_decision.reason.startswith("departed: base")


def test_a_batch_of_observations_gets_the_same_actions_as_one_by_one() -> None:
    """A vector env's dict of arrays: one action per env, each env with its own plan."""
    vector = gym.vector.SyncVectorEnv([lambda: gym.make("FetchCarryPush-v0", family="push") for _ in range(2)])
    observations, _ = vector.reset(seed=[3, 4])
    batch_policy = ExpertPolicy(vector)
    actions, state = batch_policy.predict(observations, episode_start=np.array([True, True]))
    assert actions.shape == (2, 5) and state is None
    for k in range(2):
        single = ExpertPolicy(lattice=batch_policy.lattice, capacity=batch_policy.capacity)
        alone, _ = single.predict({key: value[k] for key, value in observations.items()})
        assert np.array_equal(actions[k], alone)
    observations, *_ = vector.step(actions)
    batch_policy.predict(observations, episode_start=np.array([False, True]))
    first, second = batch_policy.last_decisions
    assert not first.planned and first.reason == "following"
    assert second.planned and not second.replanned  # a new episode, not a replan


def test_a_planner_time_limit_is_a_clear_episode_outcome(spec_example: Scenario) -> None:
    env = gym.make("FetchCarryPush-v0", scenario=spec_example)
    record = run_episode(env, ExpertPolicy(env, time_limit=1e-4), seed=0)
    figures = record.figures
    assert figures.outcome == "planner_failed (time_limit)" and not figures.success
    assert figures.failure == "no plan (time_limit)" and figures.planner_failures == 1
    assert figures.steps == 1 and record.truncations[-1] and figures.invalid_actions == 0
    assert bool(record.infos["fallback"][-1])


def test_the_fallback_is_kept_until_the_state_changes(spec_example: Scenario) -> None:
    env = gym.make("FetchCarryPush-v0", scenario=spec_example)
    observation, _ = env.reset(seed=0)
    policy = ExpertPolicy(env, time_limit=1e-4)
    first, _ = policy.predict(observation)
    second, _ = policy.predict(observation)
    assert np.array_equal(first, second) and policy.stats.plans == 1  # no new planning call for the same state
    assert policy.last_decision.fallback and policy.last_decision.reason == "failed here"


@pytest.mark.parametrize("name", ["pick_ambiguity", "pick_blocked_in_front"])
def test_a_pick_takes_the_planned_object_with_no_repair(name: str) -> None:
    """Scenarios where another object stands within reach of natural pick poses, nearer the middle of the
    posture's ranges (a delivered object; multi-2 seed 34: one 9 cm in front of the target). The planner
    models which object the env takes, so its plan executes as planned: one plan, nothing refused."""
    scenario = Scenario.load(SCENARIOS / f"{name}.json")
    env = gym.make("FetchCarryPush-v0", scenario=scenario)
    policy = ExpertPolicy(env)
    record = run_episode(env, policy, seed=0)
    assert record.figures.success and record.figures.invalid_actions == 0
    assert record.figures.repairs == 0 and not record.infos["repaired"].any()
    assert policy.stats.plans == 1 and policy.stats.stuck == 0
    picks = [k for k, p in enumerate(policy.last_plan.phases) if p.action == "pick"]
    assert len(picks) == len(scenario.objects)


def test_refuses_to_be_made_without_a_lattice() -> None:
    with pytest.raises(ValueError, match="lattice"):
        ExpertPolicy()
    with pytest.raises(ValueError, match="time_limit"):
        ExpertPolicy(gym.make("FetchCarryPush-v0"), time_limit=0.0)


def test_a_base_inside_an_octagon_cannot_move_and_the_expert_says_it_is_stuck(spec_example: Scenario) -> None:
    """A base by a table's corner is clear of it, but inside the octagon the MILP keeps it out of (Eq. 18): the
    planner has no plan from there, and the env, whose move rule is the MILP's, refuses every move from it."""
    from expert import plan

    # 0.226 m from table_src's corner (1.7, 1.7) at 22.5 degrees off the x axis: the disc (0.22 m) is clear,
    # but the octagon's corner cut lies 0.22 / cos(22.5 degrees) = 0.238 m out along that line.
    corner = (1.4912, 1.6135)
    scenario = dataclasses.replace(spec_example, robot=dataclasses.replace(spec_example.robot, start=corner))
    assert plan(scenario).status == "infeasible"
    env = gym.make("FetchCarryPush-v0", scenario=scenario)
    record = run_episode(env, ExpertPolicy(env), seed=0)
    assert not record.figures.success and record.figures.outcome == "expert_stuck"
    env.reset(seed=0)
    away = env.unwrapped.lattice.index((0.5, 0.5))
    assert "'table_src'" in env.step(Action(away, "+x", 0, Mode.MOVE).to_array())[4]["invalid_action"]
