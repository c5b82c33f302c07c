"""observation_layout names the slices of the flat observation vector: they cover it and say what encode wrote."""

from __future__ import annotations

import itertools

import gymnasium as gym
import numpy as np
import pytest

from fetchcarry_env.observation import FIELDS, SLOT_GROUPS, Capacity, observation_layout, observation_size


@pytest.mark.parametrize("capacity", [Capacity(), Capacity(objects=2, clutter=1, tables=3, obstacles=0, postures=2)])
def test_slots_cover_the_vector_in_order_without_gaps(capacity):
    layout = observation_layout(capacity)
    singles = [s for name, s in layout.items() if name not in SLOT_GROUPS]
    assert singles[0].start == 0 and singles[-1].stop == observation_size(capacity)
    assert all(a.stop == b.start for a, b in itertools.pairwise(singles))
    for group, slot in SLOT_GROUPS.items():
        count = getattr(capacity, group)
        assert layout[group].stop - layout[group].start == count * len(FIELDS[slot])
    assert layout["robot"].stop - layout["robot"].start == len(FIELDS["robot"])


def test_the_slices_hold_what_the_env_encoded():
    env = gym.make("FetchCarryPush-v0", family="push")
    observation, _ = env.reset(seed=0)
    scenario, state = env.unwrapped.scenario, env.unwrapped.state
    flat = observation["observation"]
    layout = observation_layout(env.unwrapped.capacity)

    def field(name: str, kind: str, feature: str) -> float:
        return float(flat[layout[name]][FIELDS[kind].index(feature)])

    assert field("robot", "robot", "x") == pytest.approx(state.base[0])
    assert field("robot", "robot", f"heading_{state.heading}") == 1.0
    obj = scenario.objects[0]
    assert field("object_0", "object", "goal_x") == pytest.approx(obj.goal[0])
    assert field("object_0", "object", "x") == pytest.approx(state.objects[obj.id][0])
    assert field("object_1", "object", "present") == 0.0
    assert field("clutter_0", "clutter", "max_y") == pytest.approx(scenario.clutter[0].rect.max_y)
    assert field("table_1", "table", "height") == pytest.approx(scenario.tables[1].height)
    rows = flat[layout["tables"]].reshape(env.unwrapped.capacity.tables, len(FIELDS["table"]))
    np.testing.assert_array_equal(rows[:, 0], [1.0] * len(scenario.tables) + [0.0] * (len(rows) - len(scenario.tables)))
    assert field("posture_1", "posture", "forward_high") == pytest.approx(scenario.robot.postures[1].forward[1])
