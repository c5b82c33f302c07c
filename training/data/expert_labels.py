"""The MILP expert's episodes seen through the candidate-phase interface: each state's mask and its label.

:func:`expert_episode` runs :class:`expert.ExpertPolicy` for one episode on a
``FetchCarryPushPhases-v0`` env. At every state it records the observation, the
candidate mask and the expert's action as a candidate index (:data:`NOT_EXPRESSIBLE`
when no allowed candidate stands for it), and it executes the expert's own env action,
so that the episode is the expert's whether or not each action is expressible. BC's
in-process demonstrations, the learners' reference costs and the interface's benchmark
read these labels; :func:`record_demonstrations` gathers them as :class:`Demonstrations`
(the labelled states BC and DAgger train on).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from expert import ExpertPolicy
from fetchcarry_env.actions import Mode
from training.envs import make_env
from training.rollout import run_episode

NOT_EXPRESSIBLE = -1  # the label of an expert action that no allowed candidate stands for


@dataclass
class ExpertEpisode:
    """One expert episode seen through the interface."""

    seed: int
    observations: list[dict[str, np.ndarray]] = field(default_factory=list)
    masks: list[np.ndarray] = field(default_factory=list)
    labels: list[int] = field(default_factory=list)  # candidate index, or NOT_EXPRESSIBLE
    modes: list[int] = field(default_factory=list)  # the expert action's Mode
    success: bool = False
    travel_cost: float = 0.0  # the paper's cost of the episode's moves (info["travel_cost"])
    mask_s: float = 0.0  # seconds spent computing masks

    @property
    def steps(self) -> int:
        return len(self.labels)

    @property
    def expressible(self) -> int:
        """How many of the expert's actions a candidate stands for."""
        return sum(label != NOT_EXPRESSIBLE for label in self.labels)


def expert_episode(
    env: gym.Env, expert: ExpertPolicy, seed: int, options: dict[str, Any] | None = None
) -> ExpertEpisode:
    """Run the expert for one episode (``reset(seed=seed)``) on a phase env and record it.

    The expert's own env actions are executed (the phase env's ``step_env_action``), so
    the episode is the expert's whether or not a candidate expresses each action.
    """
    index_of = env.get_wrapper_attr("index_of")
    limit = env.spec.max_episode_steps if env.spec is not None and env.spec.max_episode_steps else 50
    record = ExpertEpisode(seed)

    def label(observation: dict[str, np.ndarray], action: np.ndarray, mask: np.ndarray) -> None:
        index = index_of(action)
        record.observations.append({k: v.copy() for k, v in observation.items()})
        record.masks.append(mask)
        record.labels.append(NOT_EXPRESSIBLE if index is None else int(index))
        record.modes.append(int(action[4]))

    episode = run_episode(env, expert, seed, options=options, max_steps=limit, stop_on_failure=False,
                                  step=env.get_wrapper_attr("step_env_action"), observe=label)  # fmt: skip
    record.success = bool(episode.info["is_success"])
    record.travel_cost = float(episode.info["travel_cost"])
    record.mask_s = episode.figures.mask_s
    return record


@dataclass
class Demonstrations:
    """Labelled states: flat observation vectors, candidate masks and the expert's candidate."""

    observations: np.ndarray  # (N, D) float32, the env's observation["observation"]
    masks: np.ndarray  # (N, K) bool
    labels: np.ndarray  # (N,) int64 candidate indices
    stats: dict[str, Any] = field(default_factory=dict)  # episodes, steps, labelled steps, expert successes

    def __len__(self) -> int:
        return len(self.labels)


def record_demonstrations(family: str, seeds: range | list[int], **env_options: Any) -> Demonstrations:
    """The expert's episodes on ``seeds`` of ``family``, its expressible actions as labels."""
    env = make_env("phases", family=family, **env_options)
    expert = ExpertPolicy(env, interface="env")  # its own env actions, as expert_episode executes them
    observations, masks, labels = [], [], []
    steps = successes = 0
    for seed in seeds:
        record = expert_episode(env, expert, seed)
        successes += record.success
        steps += record.steps
        for observation, mask, label in zip(record.observations, record.masks, record.labels, strict=True):
            if label != NOT_EXPRESSIBLE:
                observations.append(observation["observation"])
                masks.append(mask)
                labels.append(label)
    env.close()
    size = env.action_space.n
    return Demonstrations(
        np.asarray(observations, dtype=np.float32).reshape(len(labels), -1),
        np.asarray(masks, dtype=bool).reshape(len(labels), size),
        np.asarray(labels, dtype=np.int64),
        {"episodes": len(seeds), "steps": steps, "labelled": len(labels), "expert_successes": successes},
    )


def mode_name(mode: int) -> str:
    return Mode(mode).name.lower()
