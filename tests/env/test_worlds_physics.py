"""Physics variation and capacity in the env: drawn from the seed, bit for bit; a push lands elsewhere; room to fit."""

from __future__ import annotations

import copy

import gymnasium as gym
import numpy as np
import pytest

import fetchcarry_env  # noqa: F401  (registers the env ids)
from fetchcarry_env.observation import Capacity, CapacityError
from fetchcarry_env.registration import ENV_ID, PHASES_ENV_ID
from fetchcarry_env.scenario import ScenarioError
from fetchcarry_env.worlds.physics import HOME, PhysicsError, PhysicsVariation

STEPS = 12


def _masked_random_episode(env: gym.Env, seed: int) -> list[np.ndarray]:
    """Observations of a masked random episode of the phases env (the policy seeded apart from the env)."""
    rng = np.random.default_rng(1000 + seed)
    observation, _ = env.reset(seed=seed)
    seen = [observation["observation"]]
    for _ in range(STEPS):
        allowed = np.flatnonzero(env.get_wrapper_attr("action_masks")())
        observation, _, terminated, truncated, _ = env.step(int(rng.choice(allowed)))
        seen.append(observation["observation"])
        if terminated or truncated:
            break
    return seen


def test_perturbed_draws_mass_and_friction_from_the_seed_and_replays_bit_for_bit():
    first, second = (gym.make(PHASES_ENV_ID, family="perturbed") for _ in range(2))
    for seed in (0, 5):
        a, b = _masked_random_episode(first, seed), _masked_random_episode(second, seed)
        assert first.unwrapped._item_physics == second.unwrapped._item_physics
        assert len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    masses = {v.mass for v in first.unwrapped._item_physics.values()}
    assert masses and all(HOME.mass[0] <= m <= HOME.mass[1] for m in masses)
    first.reset(seed=1)
    other = dict(first.unwrapped._item_physics)
    first.reset(seed=2)
    assert other != first.unwrapped._item_physics


def test_a_copy_keeps_the_episode_physics():
    env = gym.make(ENV_ID, family="perturbed")
    env.reset(seed=3)
    twin = copy.deepcopy(env)
    assert twin.unwrapped._item_physics == env.unwrapped._item_physics and env.unwrapped._item_physics


def _push_landing(physics: PhysicsVariation | str | None) -> tuple[float, float]:
    """Where the block of the push family's seed 7 lands after the expert's first push, with ``physics``."""
    from expert.policy import ExpertPolicy

    env = gym.make(ENV_ID, family="push", physics=physics)
    observation, _ = env.reset(seed=7)
    expert = ExpertPolicy(env)
    for _ in range(10):
        action, _ = expert.predict(observation)
        observation, _, _, _, info = env.step(action)
        if "push" in info:
            return env.unwrapped.state.clutter[info["push"]["clutter"]]
    raise AssertionError("the expert made no push")


def test_a_slippery_light_block_lands_elsewhere_than_the_default():
    slippery = PhysicsVariation("slippery", mass=(0.4, 0.4), friction=(0.25, 0.25))
    default, varied = _push_landing(None), _push_landing(slippery)
    assert _push_landing("none") == default
    assert np.hypot(*np.subtract(default, varied)) > 0.005, (default, varied)


def test_physics_names_and_the_switch():
    assert gym.make(ENV_ID, family="perturbed", physics="none").unwrapped.physics is None
    assert gym.make(ENV_ID, family="basic", physics="home").unwrapped.physics is HOME
    assert gym.make(ENV_ID, family="basic").unwrapped.physics is None
    with pytest.raises(PhysicsError, match="known: none, home"):
        gym.make(ENV_ID, family="basic", physics="moon")


def test_default_capacity_holds_the_family_or_the_fixed_scenario():
    env = gym.make(ENV_ID, family="objects-8")
    env.reset(seed=0)
    assert env.unwrapped.capacity.objects == 8 and len(env.unwrapped.scenario.objects) == 8
    scenario = env.unwrapped.scenario
    fixed = gym.make(ENV_ID, scenario=scenario)  # refused before: "6 objects (room for 4)"
    assert fixed.unwrapped.capacity == Capacity(objects=8)
    assert gym.make(ENV_ID, family="basic").unwrapped.capacity == Capacity()
    with pytest.raises(ScenarioError, match="room for 5"):
        gym.make(ENV_ID, scenario=scenario, capacity="objects=5")


def test_capacity_as_text_or_mapping_and_bad_values():
    env = gym.make(PHASES_ENV_ID, family="basic", capacity={"objects": 6, "clutter": 10})
    assert env.unwrapped.capacity == Capacity(objects=6, clutter=10)
    assert env.observation_space["observation"].shape[0] > gym.make(ENV_ID).observation_space["observation"].shape[0]
    assert Capacity.parse("objects=8, tables=7") == Capacity(objects=8, tables=7)
    for text in ("objects", "objects=-1", "cups=3", "objects=1e9", "postures=0"):
        with pytest.raises(CapacityError):
            Capacity.parse(text)
