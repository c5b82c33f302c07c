"""A valid world far from the origin behaves as the same world near it: the expert succeeds, observations fit.

Rule 6 lets a world sit anywhere within 100 m of the origin and stand up to 100 m
tall. There float32 spacing is up to 7.6e-6 m (15 times the 1e-6 m tolerances of the
rules), and a held object rides 5 cm above its table's top.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from expert.policy import ExpertPolicy
from fetchcarry_env.env import FetchCarryPushEnv
from fetchcarry_env.observation import COORD_LIMIT, LIFT_HEIGHT, Capacity, WorldState, encode, observation_space
from fetchcarry_env.scenario import Scenario

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"
BASE = Scenario.load(EXAMPLE)  # area (-1, -1)-(6, 6), tables 0.7 m high, a 0.2 m bottle, a push
MAX_STEPS = 20  # the example takes 5 env steps (its plan's 6 phases, the start included)


def shifted(scenario: Scenario, dx: float, dy: float, table_height: float | None = None) -> Scenario:
    """``scenario`` moved by ``(dx, dy)`` metres, its tables ``table_height`` metres high if given."""
    return Scenario.from_dict(_shifted_data(scenario, dx, dy, table_height))


def _shifted_data(scenario: Scenario, dx: float, dy: float, table_height: float | None = None) -> dict[str, Any]:
    data: dict[str, Any] = json.loads(json.dumps(scenario.to_dict()))

    def move(point: list[float]) -> list[float]:
        return [point[0] + dx, point[1] + dy]

    data["area"] = {"min": move(data["area"]["min"]), "max": move(data["area"]["max"])}
    data["robot"]["start"] = move(data["robot"]["start"])
    for key in ("tables", "obstacles", "clutter"):
        for item in data[key]:
            item["min"], item["max"] = move(item["min"]), move(item["max"])
            if key == "tables" and table_height is not None:
                item["height"] = table_height
    for item in data["objects"]:
        item["start"], item["goal"] = move(item["start"]), move(item["goal"])
    return data


def _corners() -> dict[str, tuple[float, float, float | None]]:
    """Shifts that put the example's area into each corner of rule 6's square, and the far one up high."""
    low, high = -COORD_LIMIT - BASE.area.min_x, COORD_LIMIT - BASE.area.max_x  # x and y alike: a square area
    top = COORD_LIMIT - max(o.height for o in BASE.objects)  # the bottle's top at exactly 100 m
    return {
        "+66 m": (66.0, 66.0, None),
        "+x +y": (high, high, None),
        "+x -y": (high, low, None),
        "-x +y": (low, high, None),
        "-x -y": (low, low, None),
        "+x +y, 100 m up": (high, high, top),
    }


def _episode(scenario: Scenario) -> tuple[bool, int, list[str]]:
    """The expert's episode in ``scenario``: (success, phases, the observations outside the space)."""
    env = FetchCarryPushEnv(scenario=scenario)
    try:
        policy = ExpertPolicy(env)
        observation, _ = env.reset(seed=0)
        outside = [] if env.observation_space.contains(observation) else ["reset"]
        for step in range(MAX_STEPS):
            action, _ = policy.predict(observation)
            observation, _, terminated, _, info = env.step(action)
            if not env.observation_space.contains(observation):
                outside.append(f"step {step}: {_outside(env, observation)}")
            if terminated:
                return bool(info["is_success"]), step + 1, outside
        return False, MAX_STEPS, outside
    finally:
        env.close()


def _outside(env: FetchCarryPushEnv, observation: dict[str, np.ndarray]) -> str:
    space = env.observation_space
    return ", ".join(
        f"{key} {observation[key][~((observation[key] >= box.low) & (observation[key] <= box.high))]}"
        for key, box in space.spaces.items()
        if not box.contains(observation[key])
    )


def test_the_example_near_the_origin_takes_five_steps():
    assert _episode(BASE) == (True, 5, [])


@pytest.mark.parametrize("corner", list(_corners()))
def test_the_expert_succeeds_in_every_corner_of_the_allowed_area(corner: str):
    dx, dy, height = _corners()[corner]
    scenario = shifted(BASE, dx, dy, height)
    assert _episode(scenario) == (True, 5, [])


def test_a_held_object_on_the_highest_table_fits_the_observation_space():
    """Tables 99.999 m high, a 1 mm object (its top at 100 m): in the hand it stands 100.0495 m up."""
    data = _shifted_data(BASE, 0.0, 0.0, 99.999)
    data["objects"][0]["height"] = data["clutter"][0]["height"] = 0.001
    scenario = Scenario.from_dict(data)
    state = WorldState.initial(scenario)
    x, y, z = state.objects["bottle"]
    held = WorldState(state.base, state.heading, "bottle", {"bottle": (x, y, z + LIFT_HEIGHT)}, state.clutter)
    observation = encode(scenario, held, Capacity())
    assert observation["achieved_goal"][2] == pytest.approx(100.0495, abs=1e-4)
    assert observation_space(Capacity()).contains(observation)
