"""``RandomPhasePolicy``: a uniformly random allowed candidate phase (the masked random baseline).

It speaks stable-baselines3's ``predict`` protocol on a ``FetchCarryPushPhases-v0``
env, draws from its own ``numpy`` generator (seeded at construction, re-seedable with
:meth:`reset`), and takes the masks from ``action_masks=`` (as MaskablePPO's predict
does) or from the env it was given.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces


class RandomPhasePolicy:
    """Each call: one allowed candidate, uniformly at random (per env of a batch)."""

    def __init__(self, env: Any = None, *, seed: int | None = None) -> None:
        if env is not None and not isinstance(env.action_space, spaces.Discrete):
            raise TypeError(f"RandomPhasePolicy needs a Discrete action space, got {env.action_space}")
        self.env = env
        self.rng = np.random.default_rng(seed)

    def reset(self, seed: int | None = None) -> None:
        """Re-seed the generator (``None`` keeps the current stream)."""
        if seed is not None:
            self.rng = np.random.default_rng(seed)

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = False,
        action_masks: np.ndarray | None = None,
    ) -> tuple[np.ndarray, Any]:
        """A random allowed candidate for each mask row; ``deterministic`` is accepted for the protocol."""
        if action_masks is None:
            if self.env is None:
                raise ValueError("give action_masks= or build the policy with an env")
            action_masks = self.env.get_wrapper_attr("action_masks")()
        masks = np.asarray(action_masks, dtype=bool)
        rows = masks if masks.ndim == 2 else masks[None, :]
        actions = np.array([self._draw(row) for row in rows], dtype=np.int64)
        return (actions if masks.ndim == 2 else actions[0]), state

    def _draw(self, mask: np.ndarray) -> int:
        allowed = np.flatnonzero(mask)
        return int(self.rng.choice(allowed)) if allowed.size else int(self.rng.integers(mask.size))
