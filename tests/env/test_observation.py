"""The observation holds the whole geometry: decoding it gives the scenario back."""

from __future__ import annotations

import numpy as np
import pytest

from fetchcarry_env.families import get_family
from fetchcarry_env.observation import Capacity, WorldState, decode, encode, observation_space, with_state


@pytest.mark.parametrize("family", ["push", "corridor", "multi"])
def test_decode_inverts_encode(family):
    capacity = Capacity()
    scenario = get_family(family).sample(np.random.default_rng(1))
    state = WorldState.initial(scenario)
    observation = encode(scenario, state, capacity)
    assert observation_space(capacity).contains(observation)
    rebuilt, rebuilt_state = decode(observation, capacity)
    assert len(rebuilt.objects) == len(scenario.objects)
    for original, copy in zip(scenario.objects, rebuilt.objects, strict=True):
        assert copy.start == pytest.approx(original.start, abs=1e-6)
        assert copy.goal == pytest.approx(original.goal, abs=1e-6)
    for original, copy in zip(
        (*scenario.tables, *scenario.obstacles, *scenario.clutter),
        (*rebuilt.tables, *rebuilt.obstacles, *rebuilt.clutter),
        strict=True,
    ):
        assert copy.rect.min == pytest.approx(original.rect.min, abs=1e-6)
        assert copy.rect.max == pytest.approx(original.rect.max, abs=1e-6)
    assert rebuilt.robot.start == pytest.approx(scenario.robot.start, abs=1e-6)
    assert rebuilt_state.holding is None


def test_held_object_is_lifted_and_not_delivered(spec_example):
    capacity = Capacity()
    state = WorldState.initial(spec_example)
    z = state.objects["bottle"][2]
    holding = WorldState(state.base, state.heading, "bottle", {"bottle": (4.0, 4.0, z + 0.05)}, state.clutter)
    assert holding.delivered(spec_example) == []
    observation = encode(spec_example, holding, capacity)
    _, decoded = decode(observation, capacity)
    assert decoded.holding == "object_0"


def test_capacity_names_what_does_not_fit(spec_example):
    with pytest.raises(ValueError, match="1 objects \\(room for 0\\)"):
        Capacity(objects=0).check(spec_example)


def test_with_state_reposes_the_scenario(spec_example):
    state = WorldState.initial(spec_example)
    moved = WorldState((1.0, 0.5), "-y", None, {"bottle": (4.0, 4.0, 0.8)}, {"block": (4.0, 4.2)})
    reposed = with_state(spec_example, moved)
    assert reposed.robot.start == (1.0, 0.5)
    assert reposed.objects[0].start == (4.0, 4.0)
    assert reposed.clutter[0].rect.center == pytest.approx((4.0, 4.2))
    assert state.delivered(spec_example) == []
