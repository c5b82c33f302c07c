"""Execute a plan file in the physics env, phase by phase, and print one JSON row.

    python -m benchmarks.studies.execute_plan SCENARIO PLAN [...] > rows.jsonl

Arguments come in pairs (a ``fetchcarry-scenario/1`` file and a plan for it). Each plan's
phases become the env's actions (:func:`expert.to_actions.plan_to_actions`) in
``FetchCarryPush-v0`` on that scenario (``reset(seed=0)``); the row gives the steps run,
the first invalid action (None: none), whether the episode ended with every object
delivered, and the number of collisions the env reported.
"""

from __future__ import annotations

import json
import sys

import gymnasium as gym

import fetchcarry_env  # noqa: F401  (registers the env ids)
from expert.plans import Plan
from expert.to_actions import plan_to_actions
from fetchcarry_env.scenario import Scenario


def execute(scenario_path: str, plan_path: str) -> dict:
    """The figures of one plan executed in the env (see the module docstring)."""
    scenario, plan = Scenario.load(scenario_path), Plan.load(plan_path)
    env = gym.make("FetchCarryPush-v0", scenario=scenario)
    try:
        env.reset(seed=0)
        actions = plan_to_actions(plan, scenario, env.unwrapped.lattice)
        invalid, info, steps = None, {}, 0
        for steps, action in enumerate(actions, start=1):
            _, _, terminated, truncated, info = env.step(action.to_array())
            if info.get("invalid_action") is not None:
                invalid = f"step {steps}: {info['invalid_action']}"
                break
            if terminated or truncated:
                break
    finally:
        env.close()
    return {
        "plan": plan_path,
        "phases": len(plan.phases),
        "steps_run": steps,
        "invalid_action": invalid,
        "success": bool(info.get("is_success")),
        "collisions": info.get("collisions"),
    }


def main(argv: list[str]) -> int:
    for scenario_path, plan_path in zip(argv[::2], argv[1::2], strict=True):
        print(json.dumps(execute(scenario_path, plan_path)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
