"""Each plan, executed action by action in ``FetchCarryPush-v0``, delivers every object.

The planner plans on the env's own lattice; :func:`plan_to_actions` turns the phases
into actions; the env (PyBullet) executes them. No action may be refused, and the
episode must end, on the last action and not before, with every object delivered.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
from expert.planner import plan
from expert.to_actions import plan_to_actions
from expert.validate import validate_plan
from fetchcarry_env.families import get_family
from fetchcarry_env.scenario import Scenario

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"
TIME_LIMIT = 20.0  # seconds per planning call


def family_scenario(name: str, seed: int) -> Scenario:
    return get_family(name).sample(np.random.default_rng(seed))


CASES = {
    "spec example (push aside)": lambda: Scenario.load(EXAMPLE),
    "basic": lambda: family_scenario("basic", 1),
    "push": lambda: family_scenario("push", 2),
    "corridor": lambda: family_scenario("corridor", 3),
    "multi": lambda: family_scenario("multi", 4),
}


PUSH_ASIDE = ("spec example (push aside)", "push")


@pytest.mark.parametrize("case", list(CASES))
def test_the_plan_delivers_every_object_in_the_env(case):
    scenario = CASES[case]()
    env = gym.make("FetchCarryPush-v0", scenario=scenario)
    try:
        env.reset(seed=0)
        lattice = env.unwrapped.lattice
        result = plan(scenario, time_limit=TIME_LIMIT, lattice=lattice)
        assert result.found, (case, result.status)
        assert validate_plan(scenario, result) == []
        if case in PUSH_ASIDE:  # clutter stands on a goal: the plan must push it aside
            assert any(p.action == "push" for p in result.phases)
        actions = plan_to_actions(result, scenario, lattice)
        assert len(actions) == len(result.phases) - 1
        for k, action in enumerate(actions, start=1):
            _, _, terminated, truncated, info = env.step(action.to_array())
            assert info["invalid_action"] is None, (case, k, result.phases[k], info["invalid_action"])
            assert not truncated, (case, k)
            assert terminated == (k == len(actions)), (case, k, info)
        assert info["is_success"], (case, info)
    finally:
        env.close()
