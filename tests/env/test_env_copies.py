"""Reproducibility and isolation: seeds, several envs in one process, vector envs, copies and memory."""

from __future__ import annotations

import copy
import gc
import pickle

import gymnasium as gym
import numpy as np
import psutil
import pytest
from sim_worlds import (
    PUSH_PICK_PLACE_PLAN,
    SPEC_EXAMPLE_PLAN,
    action,
    jam,
    make,
    push_pick_place,
    shove,
    spec_example,
)

from fetchcarry_env.actions import Mode

ENV_ID = "FetchCarryPush-v0"
RANDOM_STEPS = 30  # steps of the masked random policy per episode
WORLDS = {  # scripted episodes with every primitive: (scenario, plan, the step after the push, a step holding)
    "small": (push_pick_place, PUSH_PICK_PLACE_PLAN, 1, 2),
    "spec example": (spec_example, SPEC_EXAMPLE_PLAN, 3, 5),  # an off-centre push: the block turns
}


def masked_random_action(env: gym.Env, rng: np.random.Generator) -> np.ndarray:
    """Each component drawn uniformly among the values the env's mask allows."""
    mask = env.unwrapped.action_masks()
    bounds = np.concatenate([[0], np.cumsum(env.action_space.nvec)])
    return np.array([rng.choice(np.flatnonzero(mask[bounds[k] : bounds[k + 1]])) for k in range(len(bounds) - 1)])


def transition_record(result: tuple) -> tuple:
    """A step's outcome as comparable bytes (bit for bit)."""
    observation, reward, terminated, truncated, info = result
    return (
        *(observation[k].tobytes() for k in sorted(observation)),
        reward,
        terminated,
        truncated,
        info["invalid_action"],
        info["contact"],
    )


def random_episode(env: gym.Env, seed: int) -> list[tuple]:
    observation, _ = env.reset(seed=seed)
    records = [tuple(observation[k].tobytes() for k in sorted(observation))]
    rng = np.random.default_rng(seed)
    for _ in range(RANDOM_STEPS):
        records.append(transition_record(env.step(masked_random_action(env, rng))))
    return records


def scripted_episode(env: gym.Env, steps=PUSH_PICK_PLACE_PLAN) -> list[tuple]:
    """The push, pick and place plan, with the exact pose of every body after each step."""
    env.reset(seed=0)
    records = []
    for step in steps:
        records.append((transition_record(env.step(action(env, *step))), env.unwrapped._sim.poses))
    return records


# ---------------------------------------------------------------------- seeds
def test_the_same_seed_gives_identical_trajectories_across_resets_and_seeds_differ():
    first, second = gym.make(ENV_ID), gym.make(ENV_ID)
    seeds = (3, 4, 3)
    runs = [[random_episode(env, seed) for seed in seeds] for env in (first, second)]
    assert runs[0] == runs[1]
    assert runs[0][0] == runs[0][2]  # seed 3 again after another episode: the same trajectory
    assert runs[0][0][0] != runs[0][1][0]  # seeds differ: different scenarios
    first.close()
    second.close()


@pytest.mark.parametrize("world", list(WORLDS))
def test_physics_replays_bit_for_bit_after_other_episodes(world):
    """Bodies are re-used across resets, yet no episode leaves anything behind that changes the next."""
    scenario, plan, *_ = WORLDS[world]
    reference = scripted_episode(make(scenario()), plan)
    env = make(scenario())
    scripted_episode(env, plan)
    for _ in range(3):
        env.unwrapped._sim.client.stepSimulation()  # the world at rest, stepped: nothing may carry over
    assert scripted_episode(env, plan) == reference
    env.reset(options={"scenario": jam()})  # another layout, pushed, then back
    env.step(action(env, (0.75, 1.5), "+x", 0, Mode.PUSH))
    env.reset(options={"scenario": scenario()})
    assert scripted_episode(env, plan) == reference
    env.close()


# ---------------------------------------------------------------------- isolation
def test_two_envs_in_one_process_stay_independent():
    alone_a = scripted_episode(make(push_pick_place()))
    shove_steps = [((0.75, 1.5), "+x", 0, Mode.PUSH), ((0.5, 0.5), "+x", 0, Mode.MOVE)]
    alone_b = scripted_episode(make(shove()), shove_steps)
    a, b = make(push_pick_place()), make(shove())
    together_a, together_b = [], []
    a.reset(seed=0)
    b.reset(seed=0)
    for step_a, step_b in zip(PUSH_PICK_PLACE_PLAN, [*shove_steps, shove_steps[-1]], strict=True):
        together_b.append((transition_record(b.step(action(b, *step_b))), b.unwrapped._sim.poses))
        together_a.append((transition_record(a.step(action(a, *step_a))), a.unwrapped._sim.poses))
    assert together_a == alone_a
    assert together_b[:2] == alone_b
    b.close()  # closing one leaves the other working
    assert a.reset(seed=0) is not None and a.step(action(a, *PUSH_PICK_PLACE_PLAN[0]))[4]["invalid_action"] is None
    a.close()


def test_async_vector_envs_work_and_agree_with_sync_ones():
    runs = {}
    for mode in ("async", "sync"):
        envs = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode=mode)
        observations, _ = envs.reset(seed=[5, 6])
        masks = np.stack(envs.call("action_masks"))
        assert masks.shape == (2, int(envs.single_action_space.nvec.sum()))
        records = [observations["observation"].copy()]
        rng = np.random.default_rng(0)
        for _ in range(5):
            actions = rng.integers(0, envs.single_action_space.nvec, size=(2, 5))
            actions[:, :2] = rng.integers(20, 80, size=(2, 2))  # cells well inside the room: real moves
            observations, rewards, *_ = envs.step(actions)
            records.append((observations["observation"].copy(), rewards.copy()))
        envs.close()
        runs[mode] = records
    assert runs["async"][0].shape == (2, gym.make(ENV_ID).observation_space["observation"].shape[0])
    for got, expected in zip(runs["async"][1:], runs["sync"][1:], strict=True):
        assert np.array_equal(got[0], expected[0]) and np.array_equal(got[1], expected[1])


# ---------------------------------------------------------------------- copies
COPIES = {
    "copy.copy": lambda env: copy.copy(env.unwrapped),
    "copy.deepcopy": copy.deepcopy,
    "pickle": lambda env: pickle.loads(pickle.dumps(env)),
}


@pytest.mark.parametrize("how", list(COPIES))
@pytest.mark.parametrize("holding", [False, True], ids=["after a push", "holding"])
@pytest.mark.parametrize("world", list(WORLDS))
def test_a_copy_is_independent_and_continues_exactly_as_the_original(world, holding, how):
    scenario, plan, after_push, while_holding = WORLDS[world]
    env = make(scenario(), render_mode="rgb_array", camera="top_down", width=48, height=36)
    scripted_episode(env, plan)  # an episode before: the original world has a history, the copy none
    env.reset(seed=0)
    split = while_holding if holding else after_push
    for step in plan[:split]:
        env.step(action(env, *step))
    clone = COPIES[how](env)
    assert clone.unwrapped is not env.unwrapped
    assert clone.unwrapped._sim is not env.unwrapped._sim
    assert clone.unwrapped.np_random is not env.unwrapped.np_random
    assert clone.unwrapped.state == env.unwrapped.state
    assert np.array_equal(clone.render(), env.render())
    for step in plan[split:]:
        expected = env.step(action(env, *step))
        got = clone.step(action(clone, *step))
        assert transition_record(got) == transition_record(expected)
        assert clone.unwrapped._sim.poses == env.unwrapped._sim.poses
        assert np.array_equal(clone.render(), env.render())
    back = plan[-2][0]  # the last move backwards: the move rule is symmetric, so it is allowed
    clone.step(action(clone, back, "+x", 0, Mode.MOVE))  # the copy moves on alone
    assert clone.unwrapped.state.base != env.unwrapped.state.base
    clone.close()
    assert env.step(action(env, back, "+x", 0, Mode.MOVE))[4]["invalid_action"] is None
    env.close()


def test_a_family_env_copies_with_its_random_generator():
    env = gym.make(ENV_ID, family="multi-2")  # a family drawn by a lambda: copies must not pickle it
    random_episode(env, seed=1)
    clone = pickle.loads(pickle.dumps(env))
    # Unseeded resets draw the next scenario from the copied generator: the same one in both.
    assert [clone.reset()[0]["observation"].tobytes() for _ in range(3)] == [
        env.reset()[0]["observation"].tobytes() for _ in range(3)
    ]
    env.close()
    clone.close()


def test_what_cannot_be_copied_says_so(monkeypatch):
    env = make(push_pick_place())
    with pytest.raises(TypeError, match="copy the environment instead"):
        pickle.dumps(env.unwrapped._sim)
    with pytest.raises(TypeError, match="cannot be pickled or copied"):
        copy.deepcopy(env.unwrapped._sim.client)
    env.close()
    monkeypatch.setenv("DISPLAY", ":99")
    windowed = gym.make(ENV_ID, render_mode="human")  # no window before reset
    with pytest.raises(TypeError, match="render_mode='human' cannot be copied"):
        copy.deepcopy(windowed)


# ---------------------------------------------------------------------- memory
def test_two_thousand_resets_grow_memory_by_under_30_mb():
    layouts = [push_pick_place(), shove()]
    env = make(layouts[0])
    for k in range(50):  # warm up: allocator pools, caches
        env.reset(options={"scenario": layouts[k // 5 % 2]})
    gc.collect()
    before = psutil.Process().memory_info().rss
    for k in range(2000):  # a new layout every fifth reset: 400 rebuilds, 1600 re-uses
        env.reset(options={"scenario": layouts[k // 5 % 2]})
    gc.collect()
    grown = psutil.Process().memory_info().rss - before
    assert env.unwrapped._sim.builds > 400
    assert grown < 30e6, f"{grown / 1e6:.1f} MB"
    env.close()
