"""Where a dataset's episodes come from: the env (a family or one scenario), the policy and the seeds.

Shared by generation (:mod:`training.data.generate`), assembly (:mod:`training.data.datasets`)
and the commands that run single episodes.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import gymnasium as gym

from fetchcarry_env.errors import InputError
from fetchcarry_env.families import FAMILY_NAMES
from fetchcarry_env.observation import Capacity
from fetchcarry_env.observations import mode_names
from fetchcarry_env.registration import ENV_ID, PHASES_ENV_ID
from training.envs import INTERFACES as ENV_IDS
from training.envs import MAX_SEED, make_env
from training.policies.protocol import Policy
from training.resolve import recording_policy

INTERFACES = tuple(ENV_IDS)  # the env's own MultiDiscrete actions, or the Discrete candidate phases
POLICIES = ("expert", "random")
DEFAULT_TIME_LIMIT = 10.0  # seconds per planning call
PROJECTION = "nearest move candidate"  # what a phases dataset records for an expert move no candidate expresses


@dataclass(frozen=True)
class EpisodeSource:
    """Where episodes come from: the env (a family or one scenario), the policy and the seeds.

    Episode ``k`` uses the seed ``seed + k``; the env draws its scenario from that seed.
    ``interface`` is the action interface episodes are recorded in: ``env`` (the env's
    own ``MultiDiscrete`` actions, ``env_id``) or ``phases`` (``FetchCarryPushPhases-v0``'s
    candidate indices, with each state's candidate mask; see :mod:`training.policies.phase_expert`).
    ``obs_mode`` is the env's observation mode (``state``, ``topdown``, ``rgbd``): what the
    episodes' observations hold besides the state.
    """

    family: str | None = None  # a scenario family name, or
    scenario: dict[str, Any] | None = None  # one fixed scenario (fetchcarry-scenario/1 JSON)
    seed: int = 0  # episode k uses seed + k
    policy: str = "expert"
    time_limit: float = DEFAULT_TIME_LIMIT  # seconds per planning call (expert)
    env_id: str = ENV_ID
    interface: str = "env"
    capacity: str | None = None  # the observation's slots, "objects=8,clutter=12"; None: the env's default
    obs_mode: str = "state"

    def __post_init__(self) -> None:
        if self.obs_mode not in mode_names():
            raise InputError(f"unknown observation mode {self.obs_mode!r}: choose one of {', '.join(mode_names())}")
        if self.interface not in INTERFACES:
            raise InputError(f"unknown interface {self.interface!r}: choose one of {', '.join(INTERFACES)}")
        if (self.family is None) == (self.scenario is None):
            raise InputError("give exactly one of a scenario family and a fixed scenario")
        if self.family is not None and self.family not in FAMILY_NAMES:
            raise InputError(f"unknown family {self.family!r}: choose one of {', '.join(FAMILY_NAMES)}")
        if self.policy not in POLICIES:
            raise InputError(f"unknown policy {self.policy!r}: choose one of {', '.join(POLICIES)}")
        if self.time_limit <= 0:
            raise InputError(f"the time limit must be a positive number of seconds, got {self.time_limit}")
        if not 0 <= self.seed <= MAX_SEED:
            raise InputError(f"a seed must be between 0 and 2**32 - 1 ({MAX_SEED}), got {self.seed}")
        if self.capacity is not None:
            Capacity.parse(self.capacity)  # a CapacityError (bad input) names what is wrong

    @property
    def env_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of ``gym.make`` (JSON-serialisable, so Minari can store the env spec)."""
        kwargs: dict[str, Any] = {"family": self.family} if self.family is not None else {"scenario": self.scenario}
        if self.capacity is not None:
            kwargs["capacity"] = self.capacity
        if self.obs_mode != "state":  # a state dataset's env spec stays as it was before observation modes
            kwargs["obs_mode"] = self.obs_mode
        return kwargs

    @property
    def gym_id(self) -> str:
        """The id ``gym.make`` builds: ``env_id``, or ``FetchCarryPushPhases-v0`` for the ``phases`` interface."""
        return PHASES_ENV_ID if self.interface == "phases" else self.env_id

    @property
    def label(self) -> str:
        return f"family {self.family}" if self.family is not None else f"scenario {self.scenario['name']}"

    def episode_seed(self, index: int) -> int:
        return self.seed + index

    def build_env(self, render_mode: str | None = None, **render_options: Any) -> gym.Env:
        """A fresh env for this source (``render_options``: the env's ``camera``, ``width``, ``height``)."""
        return make_env(env_id=self.gym_id, render_mode=render_mode, **self.env_kwargs, **render_options)

    def build_policy(self, env: gym.Env) -> Policy:
        """The policy named by ``policy`` for ``env``, acting in ``interface`` (``resolve.recording_policy``)."""
        return recording_policy(self.policy, self.interface, env, time_limit=self.time_limit)


@dataclass(frozen=True)
class GenerationConfig:
    """A dataset to make: its id, how many episodes, and where they come from."""

    dataset_id: str
    episodes: int
    source: EpisodeSource

    def __post_init__(self) -> None:
        if self.episodes < 1:
            raise InputError(f"a dataset needs at least 1 episode, got {self.episodes}")
        last = self.source.seed + self.episodes - 1
        if last > MAX_SEED:
            raise InputError(
                f"seed {self.source.seed} with {self.episodes} episodes uses seeds up to {last}, beyond 2**32 - 1: "
                f"give a seed of at most {MAX_SEED - self.episodes + 1}"
            )

    def manifest(self) -> dict[str, Any]:
        """The options that identify the staged episodes (everything but how many there are)."""
        manifest = {"dataset_id": self.dataset_id, **asdict(self.source)}
        if manifest["capacity"] is None:  # datasets made before --capacity existed keep their manifest
            del manifest["capacity"]
        if manifest["obs_mode"] == "state":  # datasets made before observation modes keep their manifest
            del manifest["obs_mode"]
        if manifest["interface"] == "env":  # datasets made before the interface existed keep their manifest
            del manifest["interface"]
        else:  # phases: how an expert move no candidate expresses is recorded (truncated datasets did not say)
            manifest["inexpressible_moves"] = PROJECTION
        return manifest
