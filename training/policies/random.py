"""The masked random policies, one per interface: the lower bounds of every benchmark.

- :class:`RandomMaskedPolicy` (``FetchCarryPush-v0``) samples each component of the
  ``MultiDiscrete`` phase action uniformly among the values the env's action mask allows
  (the same per-component masking as sb3-contrib's MaskablePPO). It drives the dataset
  pipeline when no planner is wanted.
- :class:`RandomPhasePolicy` (``FetchCarryPushPhases-v0``) picks one allowed candidate
  phase uniformly: the masked random baseline of the learnable interface.

Each draws from its own ``numpy`` generator, seeded at construction and re-seeded by
``reset(seed)`` (the episode loop does so with the episode's seed), so the same seed
gives the same actions bit for bit. Both take the masks as ``action_masks=`` (as
MaskablePPO's ``predict`` does) or from the env they were given.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from training.policies.protocol import MaskedPolicy


class _SeededPolicy(MaskedPolicy):
    """A policy that draws from its own generator, re-seeded by :meth:`reset`."""

    def __init__(self, seed: int | None) -> None:
        self.rng = np.random.default_rng(seed)

    def reset(self, seed: int | None = None) -> None:
        """Re-seed the generator (``None`` keeps the current stream)."""
        if seed is not None:
            self.rng = np.random.default_rng(seed)


class RandomMaskedPolicy(_SeededPolicy):
    """Uniformly random valid-looking actions: each component drawn among its unmasked values.

    ``env`` is a Gymnasium env (wrapped or not) or a stable-baselines3 ``VecEnv`` whose
    env exposes ``action_masks()`` (one flat bool vector of length ``sum(nvec)``).
    ``predict`` also accepts the masks directly (``action_masks=``), as MaskablePPO does.
    """

    def __init__(self, env: Any, *, seed: int | None = None) -> None:
        space = env.action_space
        if not isinstance(space, spaces.MultiDiscrete):
            raise TypeError(f"RandomMaskedPolicy needs a MultiDiscrete action space, got {space}")
        super().__init__(seed)
        self.env = env
        self.nvec = np.asarray(space.nvec, dtype=np.int64).reshape(-1)
        self._bounds = np.concatenate([[0], np.cumsum(self.nvec)])

    def act(self, observation: Any, action_masks: np.ndarray | None, episode_start: Any, deterministic: bool) -> Any:
        """One action per observation (a batch gives a batch); random either way (reproducible through the seed)."""
        masks = self.env_masks() if action_masks is None else np.asarray(action_masks, dtype=bool)
        if masks.shape[-1] != self._bounds[-1]:
            raise ValueError(f"action mask has length {masks.shape[-1]}, expected sum(nvec) = {self._bounds[-1]}")
        actions = np.stack([self._sample(mask) for mask in np.atleast_2d(masks)])
        return actions if _is_batched(observation, self.env) else actions[0]

    def _sample(self, mask: np.ndarray) -> np.ndarray:
        action = np.empty(len(self.nvec), dtype=np.int64)
        for k in range(len(self.nvec)):
            allowed = np.flatnonzero(mask[self._bounds[k] : self._bounds[k + 1]])
            # A component with nothing allowed falls back to all values: the env will reject it.
            action[k] = self.rng.choice(allowed) if allowed.size else self.rng.integers(self.nvec[k])
        return action


class RandomPhasePolicy(_SeededPolicy):
    """Each call: one allowed candidate, uniformly at random (per env of a batch)."""

    def __init__(self, env: Any = None, *, seed: int | None = None) -> None:
        if env is not None and not isinstance(env.action_space, spaces.Discrete):
            raise TypeError(f"RandomPhasePolicy needs a Discrete action space, got {env.action_space}")
        super().__init__(seed)
        self.env = env

    def act(self, observation: Any, action_masks: np.ndarray | None, episode_start: Any, deterministic: bool) -> Any:
        """A random allowed candidate for each mask row (one row: one candidate)."""
        masks = self.env_masks() if action_masks is None else np.asarray(action_masks, dtype=bool)
        actions = np.array([self._draw(row) for row in np.atleast_2d(masks)], dtype=np.int64)
        return actions if masks.ndim == 2 else actions[0]

    def _draw(self, mask: np.ndarray) -> int:
        allowed = np.flatnonzero(mask)
        return int(self.rng.choice(allowed)) if allowed.size else int(self.rng.integers(mask.size))


def _is_batched(observation: dict[str, np.ndarray] | np.ndarray, env: Any) -> bool:
    """True when ``observation`` has a leading batch dimension over the env's observation space."""
    space = env.observation_space
    if isinstance(space, spaces.Dict) and isinstance(observation, dict):
        key = next(iter(space.spaces))
        return np.ndim(observation[key]) > len(space.spaces[key].shape)
    if isinstance(space, gym.spaces.Box):
        return np.ndim(observation) > len(space.shape)
    return False
