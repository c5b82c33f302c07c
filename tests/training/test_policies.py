"""RandomMaskedPolicy: stable-baselines3's predict protocol, masks respected, seeded."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

from training.policies.random import RandomMaskedPolicy

NVEC = np.array([5, 4, 4, 2, 4])


class MaskedToyEnv(gym.Env):
    """A MultiDiscrete env whose mask allows a few values of each component."""

    def __init__(self, mask: np.ndarray) -> None:
        self.action_space = spaces.MultiDiscrete(NVEC)
        self.observation_space = spaces.Dict({"observation": spaces.Box(-1, 1, shape=(3,))})
        self.mask = mask

    def action_masks(self) -> np.ndarray:
        return self.mask


def _mask(allowed: list[list[int]]) -> np.ndarray:
    parts = []
    for n, values in zip(NVEC, allowed, strict=True):
        part = np.zeros(n, dtype=bool)
        part[values] = True
        parts.append(part)
    return np.concatenate(parts)


ALLOWED = [[1, 3], [2], [0, 1, 2], [1], [0, 3]]
OBS = {"observation": np.zeros(3, dtype=np.float32)}


def test_actions_stay_within_the_mask_through_wrappers() -> None:
    env = gym.wrappers.PassiveEnvChecker(MaskedToyEnv(_mask(ALLOWED)))
    policy = RandomMaskedPolicy(env, seed=3)
    seen = [set() for _ in NVEC]
    for _ in range(200):
        action, state = policy.predict(OBS)
        assert action.shape == (5,) and state is None
        for k, value in enumerate(action):
            seen[k].add(int(value))
    assert [sorted(s) for s in seen] == ALLOWED  # every allowed value drawn, nothing else


def test_same_seed_same_actions_and_reset_reseeds() -> None:
    env = MaskedToyEnv(_mask(ALLOWED))
    first = RandomMaskedPolicy(env, seed=11)
    second = RandomMaskedPolicy(env, seed=11)
    a = [first.predict(OBS)[0] for _ in range(20)]
    b = [second.predict(OBS)[0] for _ in range(20)]
    assert np.array_equal(a, b)
    first.reset(seed=11)
    assert np.array_equal([first.predict(OBS)[0] for _ in range(20)], a)


def test_batch_of_observations_and_explicit_masks() -> None:
    env = MaskedToyEnv(_mask(ALLOWED))
    policy = RandomMaskedPolicy(env, seed=0)
    other = [[0], [0], [3], [0], [2]]
    masks = np.stack([_mask(ALLOWED), _mask(other)])
    batch = {"observation": np.zeros((2, 3), dtype=np.float32)}
    actions, _ = policy.predict(batch, action_masks=masks)
    assert actions.shape == (2, 5)
    assert list(actions[1]) == [0, 0, 3, 0, 2]


def test_mask_of_the_wrong_length_is_refused() -> None:
    policy = RandomMaskedPolicy(MaskedToyEnv(np.ones(3, dtype=bool)), seed=0)
    with pytest.raises(ValueError, match="sum\\(nvec\\)"):
        policy.predict(OBS)
