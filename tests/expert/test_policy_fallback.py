"""The expert's fallback: a decoupled plan when a planning call ends without one (its budget or its safety stop)."""

from __future__ import annotations

import gymnasium as gym
import pytest

import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
from expert import ExpertPolicy, planner
from expert import policy as policy_module
from expert.approach import shortcut
from expert.decoupled import fallback_plan
from expert.milp.deadline import Deadline
from expert.plans import Phase, Plan
from expert.validate import validate_plan

MAX_STEPS = 50  # the registration's time limit


def _env(family: str, seed: int) -> tuple[gym.Env, dict]:
    env = gym.make("FetchCarryPush-v0", family=family)
    observation, _ = env.reset(seed=seed)
    return env, observation


def _run(env: gym.Env, expert: ExpertPolicy, observation: dict) -> dict:
    for _ in range(MAX_STEPS):
        action, _ = expert.predict(observation, deterministic=True)
        observation, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return info
    raise AssertionError("the episode did not end")


@pytest.fixture
def first_call_times_out(monkeypatch: pytest.MonkeyPatch) -> list[Plan]:
    """The expert's first whole-problem planning call answers ``time_limit`` (sub-plans run as usual)."""
    real, answers = planner.plan, []

    def plan(scenario, **kwargs):
        if not answers:
            answers.append(Plan(scenario.name, "time_limit", None, (), {"total_s": 10.0}))
            return answers[0]
        return real(scenario, **kwargs)

    monkeypatch.setattr(policy_module.planner, "plan", plan)
    return answers


def test_a_timed_out_first_call_is_answered_by_the_fallback_which_delivers(first_call_times_out) -> None:
    env, observation = _env("objects-3", 0)
    expert = ExpertPolicy(env, fallback_time_limit=60.0)
    info = _run(env, expert, observation)
    assert info["is_success"]
    assert first_call_times_out and expert.stats.decoupled == 1 and expert.stats.failures == 0
    first = expert.stats
    assert first.plans >= 1 and first.fallbacks == 0
    assert expert.last_plan is not None


def test_the_fallback_plan_says_it_is_not_proven_optimal(first_call_times_out) -> None:
    env, observation = _env("objects-3", 0)
    expert = ExpertPolicy(env, fallback_time_limit=60.0)
    expert.predict(observation)
    plan = expert.last_plan
    assert plan.status == "feasible" and "not proven optimal" in plan.stats["optimality"]
    assert plan.stats["planner"]["total_s"] == 10.0  # the timed-out call's stats are kept
    assert expert.last_decision.status == "feasible" and expert.last_decision.failure is None


def test_without_the_fallback_a_timed_out_call_fails_as_before(first_call_times_out) -> None:
    env, observation = _env("objects-3", 0)
    expert = ExpertPolicy(env, fallback_time_limit=0)
    expert.predict(observation)
    assert expert.last_decision.failure == "no plan (time_limit)"
    assert expert.stats.failures == 1 and expert.stats.decoupled == 0


def test_where_the_planner_finds_a_plan_the_expert_acts_on_it_unchanged() -> None:
    env, observation = _env("objects-2", 4)
    expert, without = ExpertPolicy(env), ExpertPolicy(env, fallback_time_limit=0)
    expert.predict(observation)
    without.predict(observation)
    assert expert.stats.decoupled == 0 and expert.last_plan.status == "optimal"
    assert expert.last_plan.phases == without.last_plan.phases
    assert expert.last_plan.objective == without.last_plan.objective


def test_a_negative_fallback_time_limit_is_refused() -> None:
    env, _ = _env("basic", 0)
    with pytest.raises(ValueError, match="fallback_time_limit"):
        ExpertPolicy(env, fallback_time_limit=-1.0)


@pytest.mark.parametrize(("family", "seed"), [("apartment", 1), ("apartment", 8), ("objects-8", 7)])
def test_the_fallback_plan_of_a_hard_world_is_valid(family: str, seed: int) -> None:
    """Worlds whose first planning call found no plan in 10 s (apartment 8 and objects-8 7 not even in 60 s)."""
    env, _ = _env(family, seed)
    scenario, lattice = env.unwrapped.scenario, env.unwrapped.lattice
    sub_plan = planner.SubPlanner(planner.PlannerOptions(), Deadline.after(300.0), lattice)
    order = [o.id for o in scenario.objects]
    plan = fallback_plan(scenario, order, lattice, sub_plan)
    assert plan.status == "feasible" and plan.stats["decoupled"].startswith("fallback")
    assert validate_plan(scenario, plan) == []
    assert len(plan.phases) - 1 <= MAX_STEPS  # its actions fit the registered episode
    assert {p.target for p in plan.phases if p.action == "place"} == set(order)


def test_shortcut_drops_a_move_the_next_slide_makes_but_keeps_one_before_a_push() -> None:
    env, _ = _env("basic", 0)
    scenario = env.unwrapped.scenario
    start = scenario.robot.start
    x, y = start
    heading = scenario.robot.heading
    phases = (
        Phase(start, heading, "start"),
        Phase((x, y), heading, "move"),  # stays: a move to where the base is, then another move
        Phase((x, y), heading, "move"),
    )
    assert len(shortcut(scenario, phases)) == 2
    before_push = (*phases[:2], Phase((x, y), heading, "push", "c"))
    assert shortcut(scenario, before_push) == before_push
