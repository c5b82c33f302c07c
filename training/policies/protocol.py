"""What every policy is: stable-baselines3's ``predict``, and the two helpers the episode loop needs.

A policy is any object with SB3's ``predict`` signature (MaskablePPO's, with
``action_masks=``). Nothing else is required; a policy *may* also have

- ``reset(seed=None)``: called before each episode (a random policy re-seeds from the
  episode's seed; others forget the last episode);
- ``last_decision``: an :class:`expert.policy.Decision` about its last answer (planners);
- ``stats``: totals with a ``to_dict()`` (planners).

A user's policy enters every command as ``package.module:factory`` where
``factory(env)`` returns such an object (``docs/protocol.md`` has a ten-line example;
:mod:`training.policies.user` checks what it gives).
"""

from __future__ import annotations

import abc
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


class MaskedPolicy(abc.ABC):
    """The project's own policies: SB3's ``predict`` written once; a subclass says how it :meth:`act` s.

    ``predict`` hands :meth:`act` the masks it was given (None when it was given none:
    :meth:`env_masks` reads the env's), and resolves ``deterministic=None`` to the
    policy's own default (:attr:`deterministic_default`: a learned or planning policy
    acts deterministically unless asked otherwise, a random one draws).
    """

    env: Any = None  # the env (or VecEnv) whose masks to read when none are given
    deterministic_default: bool = False

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool | None = None,
        action_masks: np.ndarray | None = None,
    ) -> tuple[Any, Any]:
        """The action for ``observation`` (a batch gives a batch) and ``state`` unchanged."""
        chosen = self.deterministic_default if deterministic is None else deterministic
        return self.act(observation, action_masks, episode_start, chosen), state

    @abc.abstractmethod
    def act(self, observation: Any, action_masks: np.ndarray | None, episode_start: Any, deterministic: bool) -> Any:
        """The action (or batch of actions) for ``observation``."""

    def env_masks(self) -> np.ndarray:
        """The env's ``action_masks()`` (stacked over a stable-baselines3 ``VecEnv``), as bools."""
        if self.env is None:
            raise ValueError("give action_masks= or build the policy with an env")
        if hasattr(self.env, "env_method"):  # a VecEnv (sb3-contrib's get_action_masks would import torch)
            return np.stack(self.env.env_method("action_masks")).astype(bool)
        return np.asarray(self.env.get_wrapper_attr("action_masks")(), dtype=bool)


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
