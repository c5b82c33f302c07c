"""What every policy is: stable-baselines3's ``predict``, and the two helpers the episode loop needs.

A policy is any object with SB3's ``predict`` signature (MaskablePPO's, with
``action_masks=``). Nothing else is required; a policy *may* also have

- ``reset(seed=None)``: called before each episode (a random policy re-seeds from the
  episode's seed; others forget the last episode);
- ``last_decision``: an :class:`expert.policy.Decision` about its last answer (planners);
- ``stats``: totals with a ``to_dict()`` (planners).

A user's policy enters every command as ``package.module:factory`` where
``factory(env)`` returns such an object (``docs/design.md`` has a ten-line example).
"""

from __future__ import annotations

import inspect
from typing import Any, Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class Policy(Protocol):
    """Anything with stable-baselines3's ``predict`` (the masks as sb3-contrib's MaskablePPO takes them)."""

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = False,
        action_masks: np.ndarray | None = None,
    ) -> tuple[Any, Any]:
        """The action for ``observation`` (a batch gives a batch) and the next recurrent ``state``."""
        ...


def reset_policy(policy: Any, seed: int | None) -> None:
    """Prepare ``policy`` for an episode: ``reset(seed=seed)`` if its ``reset`` takes a seed, else ``reset()``."""
    reset = getattr(policy, "reset", None)
    if reset is None:
        return
    if "seed" in inspect.signature(reset).parameters:
        reset(seed=seed)
    else:
        reset()


def takes_masks(policy: Any) -> bool:
    """Whether ``policy.predict`` accepts ``action_masks=`` (a planner reads what it needs from the env)."""
    parameters = inspect.signature(policy.predict).parameters
    return "action_masks" in parameters or any(p.kind is p.VAR_KEYWORD for p in parameters.values())
