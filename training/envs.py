"""The one way the training side makes an env: an interface name (or env id) and ``gym.make``'s options.

Every policy acts in one *interface*: ``env`` (``FetchCarryPush-v0``'s
``MultiDiscrete`` phase actions) or ``phases`` (``FetchCarryPushPhases-v0``'s
``Discrete`` candidate phases with exact masks). :func:`make_env` builds the env of
either, from a family or a fixed scenario, with an observation capacity given as a
:class:`~fetchcarry_env.observation.Capacity` or as the plain dict a run folder stores.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

import fetchcarry_env  # noqa: F401  (importing registers the env ids)
from fetchcarry_env.observation import Capacity
from fetchcarry_env.registration import ENV_ID, PHASES_ENV_ID

MAX_SEED = 2**32 - 1  # numpy and Gymnasium take seeds 0 .. 2**32 - 1

INTERFACES = {"env": ENV_ID, "phases": PHASES_ENV_ID}
"""Interface name -> the env id a policy of that interface acts in."""


def env_id_of(interface: str) -> str:
    """The env id of ``interface`` (``env`` or ``phases``); ``KeyError`` for another name."""
    return INTERFACES[interface]


def make_env(
    interface: str = "env",
    *,
    env_id: str | None = None,
    capacity: Capacity | dict[str, int] | None = None,
    **options: Any,
) -> gym.Env:
    """``gym.make`` of ``interface``'s env (or of ``env_id``), with ``options`` (``family``, ``scenario``, render ...).

    ``capacity`` may be the dict a run folder's ``config.json`` stores; ``None`` keeps the
    env's default.
    """
    if isinstance(capacity, dict):
        capacity = Capacity(**capacity)
    if capacity is not None:
        options["capacity"] = capacity
    return gym.make(env_id or env_id_of(interface), **options)
