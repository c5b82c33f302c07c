"""The MILP expert through the candidate-phase interface: its actions as candidate indices.

:func:`expert_episode` runs one episode of :class:`expert.ExpertPolicy` on a
``FetchCarryPushPhases-v0`` env. At every state it records the observation, the
candidate mask and the expert's action as a candidate index (``-1`` when no allowed
candidate stands for it), and it executes the expert's own env action, so that the
episode is the expert's whether or not each action is expressible.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from expert import ExpertPolicy
from fetchcarry_env.actions import Mode

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
    """Run the expert for one episode (``reset(seed=seed)``) on a phase env and record it."""
    index_of = env.get_wrapper_attr("index_of")
    masks = env.get_wrapper_attr("action_masks")
    step_env_action = env.get_wrapper_attr("step_env_action")
    limit = env.spec.max_episode_steps if env.spec is not None and env.spec.max_episode_steps else 50
    record = ExpertEpisode(seed)
    observation, info = env.reset(seed=seed, options=options)
    expert.reset()
    for step in range(limit):
        action, _ = expert.predict(observation, episode_start=step == 0, deterministic=True)
        start = time.perf_counter()
        mask = masks()
        label = index_of(action)
        record.mask_s += time.perf_counter() - start
        record.observations.append({k: v.copy() for k, v in observation.items()})
        record.masks.append(mask)
        record.labels.append(NOT_EXPRESSIBLE if label is None else int(label))
        record.modes.append(int(action[4]))
        observation, _reward, terminated, _truncated, info = step_env_action(action)
        if terminated:
            break
    record.success = bool(info["is_success"])
    record.travel_cost = float(info["travel_cost"])
    return record


def nearest_move(env: gym.Env, action: np.ndarray) -> int | None:
    """The allowed move candidate whose end lies nearest the end of the env move ``action``, or None.

    A stand-in label for an expert move that no candidate expresses (the expert's
    waypoints lie anywhere along a line, the candidates at fixed points).
    """
    if int(action[4]) != Mode.MOVE:
        return None
    table = env.get_wrapper_attr("table")
    moves = np.flatnonzero(table.mask & (table.actions[:, 4] == int(Mode.MOVE)))
    if moves.size == 0:
        return None
    gaps = np.abs(table.actions[moves, :2] - np.asarray(action[:2])).sum(axis=1)
    return int(moves[int(np.argmin(gaps))])


def mode_name(mode: int) -> str:
    return Mode(mode).name.lower()
