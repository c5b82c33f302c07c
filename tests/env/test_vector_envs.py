"""Vector envs of both ids: ``gym.make_vec`` in sync and async mode, autoreset, masks, seeds.

Every vector env here is compared with single envs stepped by hand: sub-env ``i`` of a
vector reset with ``seed=s`` is the single env reset with ``seed=s + i`` (Gymnasium's
convention), stepped with the same actions, and the autoreset mode the vector declares
in ``metadata["autoreset_mode"]`` is what it does (checked against a hand-written
loop of that mode).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import fetchcarry_env  # noqa: F401  (registers the ids)
from fetchcarry_env.registration import ENV_ID, PHASES_ENV_ID

EPISODE = 4  # phases per episode here, so that every sub-env ends (and autoresets) a few times
STEPS = 11


def _make_vec(env_id: str, mode: str, autoreset: AutoresetMode = AutoresetMode.NEXT_STEP) -> gym.vector.VectorEnv:
    kwargs: dict[str, Any] = {"autoreset_mode": autoreset}
    if mode == "async":
        kwargs["context"] = "fork"  # the facts' 0.05 s start-up (spawn: 0.44 s)
    return gym.make_vec(env_id, num_envs=2, vectorization_mode=mode, vector_kwargs=kwargs, family="basic",
                        max_episode_steps=EPISODE)  # fmt: skip


def _action(rng: np.random.Generator, env_id: str, mask: np.ndarray, nvec: np.ndarray | None) -> Any:
    """A random allowed candidate (phases) or a random action within the flat component mask (plain)."""
    if env_id == PHASES_ENV_ID:
        return int(rng.choice(np.flatnonzero(mask)))
    parts = np.split(mask, np.cumsum(nvec)[:-1])
    return np.array([rng.choice(np.flatnonzero(part)) for part in parts])


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    return np.array_equal(a, b)


def _single_run(env_id: str, seed: int, actions: list[Any], mode: AutoresetMode) -> list[tuple]:
    """One env stepped by hand as the vector's sub-env does in ``mode``: (obs, reward, terminated, truncated, mask)."""
    env = gym.make(env_id, family="basic", max_episode_steps=EPISODE)
    env.reset(seed=seed)
    rows, ended = [], False
    for action in actions:
        if mode == AutoresetMode.NEXT_STEP and ended:
            obs, _ = env.reset()
            reward, terminated, truncated = 0.0, False, False
        else:
            obs, reward, terminated, truncated, _ = env.step(action)
            if mode == AutoresetMode.SAME_STEP and (terminated or truncated):
                obs, _ = env.reset()
        ended = terminated or truncated
        rows.append((obs, reward, terminated, truncated, env.get_wrapper_attr("action_masks")()))
    env.close()
    return rows


@pytest.mark.parametrize("env_id", [PHASES_ENV_ID, ENV_ID])
@pytest.mark.parametrize("mode", ["sync", "async"])
@pytest.mark.parametrize("autoreset", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_a_vector_env_is_its_single_envs_with_seeds_s_plus_i(env_id: str, mode: str, autoreset: AutoresetMode) -> None:
    venv = _make_vec(env_id, mode, autoreset)
    try:
        assert venv.metadata["autoreset_mode"] == autoreset
        single = gym.make(env_id, family="basic")
        assert venv.single_action_space == single.action_space
        assert venv.single_observation_space == single.observation_space
        single.close()
        nvec = None if env_id == PHASES_ENV_ID else venv.single_action_space.nvec
        rng = np.random.default_rng(3)
        venv.reset(seed=5)
        actions: list[list[Any]] = [[], []]
        got: list[list[tuple]] = [[], []]
        ends = 0
        for _ in range(STEPS):
            masks = venv.call("action_masks")
            assert len(masks) == 2 and all(m.dtype == bool and m.shape == masks[0].shape for m in masks)
            step = [_action(rng, env_id, masks[i], nvec) for i in range(2)]
            obs, rewards, terminated, truncated, infos = venv.step(np.stack(step))
            ends += int(np.sum(terminated | truncated))
            if autoreset == AutoresetMode.SAME_STEP and (terminated | truncated).any():
                assert infos["_final_obs"].tolist() == (terminated | truncated).tolist()
            masks = venv.call("action_masks")
            for i in range(2):
                actions[i].append(step[i])
                sub_obs = {k: v[i] for k, v in obs.items()}
                got[i].append((sub_obs, rewards[i], terminated[i], truncated[i], masks[i]))
        assert ends >= 2  # autoreset was exercised
        for i in range(2):
            want = _single_run(env_id, 5 + i, actions[i], autoreset)
            for g, w in zip(got[i], want, strict=True):
                assert _same(g[0], w[0]) and g[1] == w[1] and (g[2], g[3]) == (w[2], w[3])
                assert np.array_equal(g[4], w[4])
    finally:
        venv.close()


def test_the_phases_mask_is_one_bool_per_candidate_and_allows_something() -> None:
    venv = _make_vec(PHASES_ENV_ID, "sync")
    try:
        venv.reset(seed=0)
        masks = np.stack(venv.call("action_masks"))
        assert masks.shape == (2, venv.single_action_space.n) and masks.any(axis=1).all()
    finally:
        venv.close()


def test_making_an_env_connects_no_physics_server() -> None:
    """``AsyncVectorEnv`` builds one env in the parent to read its spaces: it must not connect PyBullet there."""
    env = gym.make(PHASES_ENV_ID, family="basic")
    assert not env.unwrapped._sim.connected
    env.reset(seed=0)
    assert env.unwrapped._sim.connected
    env.close()
