"""One episode of a policy in the environment, recorded step by step with its figures.

:func:`run_episode` is the single loop that the ``rollout`` command, dataset generation,
the expert evaluation and the demo share: it resets the env with a seed, asks the
policy (stable-baselines3's ``predict`` protocol) for each action, steps the env and
keeps everything a dataset needs (observations, actions, rewards, flags, per-step
infos) plus the figures a person wants (delivered objects, path length, contacts,
invalid actions, planning and simulation seconds, replans).

An expert that finds no plan does not crash the episode: the episode ends after the
policy's fallback action, truncated, with the outcome ``planner_failed (<status>)``.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from fetchcarry_env.scenario import Scenario

# The per-step infos recorded for every episode (Minari needs the same keys at every step).
INFO_KEYS = ("planning_s", "planned", "replanned", "fallback", "invalid_action", "contact", "delivered")


@dataclass(frozen=True)
class EpisodeFigures:
    """What happened in one episode (units in comments)."""

    seed: int | None
    scenario: str  # scenario name
    objects: int  # objects to deliver
    delivered: int  # objects standing at their goals at the end
    success: bool  # every object delivered and the hand empty
    outcome: str  # "delivered", "truncated", "planner_failed (<status>)"
    steps: int  # actions taken
    episode_return: float  # sum of rewards
    path_length_m: float  # metres the base travelled (straight segments between phases)
    collisions: int  # steps whose move stopped at a contact
    invalid_actions: int  # steps whose action the env refused
    planning_s: float  # seconds in the policy's planner (0 for a policy that does not plan)
    policy_s: float  # seconds in policy.predict, planning included
    simulation_s: float  # seconds in env.reset and env.step
    plans: int  # planning calls
    replans: int  # planning calls after the first
    planner_failures: int  # planning calls that found no plan
    objective: float | None  # objective (Eq. 1) of the first plan, if the policy plans

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class EpisodeRecord:
    """Everything one episode produced: the data a dataset stores and the figures.

    ``observations`` maps each key of the Dict observation to an array with one row per
    state (``steps + 1`` rows, the reset observation first); ``actions``, ``rewards``,
    ``terminations`` and ``truncations`` have one row per step; ``infos`` maps each of
    :data:`INFO_KEYS` to ``steps + 1`` values (the reset's first, all zero).
    """

    seed: int | None
    scenario: dict[str, Any]  # the scenario JSON (fetchcarry-scenario/1) the env drew at reset
    observations: dict[str, np.ndarray]
    actions: np.ndarray
    rewards: np.ndarray
    terminations: np.ndarray
    truncations: np.ndarray
    infos: dict[str, np.ndarray]
    figures: EpisodeFigures
    frames: list[np.ndarray] = field(default_factory=list)  # rgb renders, one per state, when asked


def run_episode(
    env: gym.Env,
    policy: Any,
    seed: int | None,
    *,
    render: bool = False,
    max_steps: int | None = None,
) -> EpisodeRecord:
    """Run one episode of ``policy`` in ``env`` from ``env.reset(seed=seed)`` and record it.

    ``policy`` has stable-baselines3's ``predict``; if it has ``reset()`` it is called
    first (a seeded random policy is re-seeded with ``seed``). ``render`` keeps an rgb frame
    per state (the env must have ``render_mode="rgb_array"``). ``max_steps`` caps the
    episode for envs without a time limit.
    """
    _reset_policy(policy, seed)
    simulation_s = policy_s = 0.0
    started = time.perf_counter()
    observation, _ = env.reset(seed=seed)
    simulation_s += time.perf_counter() - started
    unwrapped = env.unwrapped
    scenario: Scenario = unwrapped.scenario
    frames = [env.render()] if render else []
    observations = [observation]
    actions, rewards, terminations, truncations = [], [], [], []
    infos = [dict.fromkeys(INFO_KEYS, 0)]
    infos[0]["delivered"] = len(unwrapped.state.delivered(scenario))
    path_length = 0.0
    outcome = "truncated"
    first_objective: float | None = None
    episode_start = True
    while True:
        started = time.perf_counter()
        action, _ = policy.predict(observation, episode_start=np.array([episode_start]), deterministic=True)
        policy_s += time.perf_counter() - started
        episode_start = False
        decision = _decision(policy)
        if decision["planned"] and first_objective is None:
            first_objective = _last_objective(policy)
        base_before = unwrapped.state.base
        started = time.perf_counter()
        observation, reward, terminated, truncated, info = env.step(action)
        simulation_s += time.perf_counter() - started
        path_length += math.dist(base_before, unwrapped.state.base)
        failed = bool(decision["fallback"])
        if failed and not terminated:
            truncated = True
            outcome = f"planner_failed ({decision['status']})"
        if max_steps is not None and len(actions) + 1 >= max_steps and not terminated:
            truncated = True
        observations.append(observation)
        actions.append(np.asarray(action, dtype=np.int64))
        rewards.append(float(reward))
        terminations.append(bool(terminated))
        truncations.append(bool(truncated))
        infos.append(
            {
                "planning_s": decision["planning_s"],
                "planned": decision["planned"],
                "replanned": decision["replanned"],
                "fallback": failed,
                "invalid_action": bool(info.get("invalid_action")),
                "contact": bool(info.get("contact")),
                "delivered": len(unwrapped.state.delivered(scenario)),
            }
        )
        if render:
            frames.append(env.render())
        if terminated or truncated:
            break

    state = unwrapped.state
    delivered = len(state.delivered(scenario))
    success = delivered == len(scenario.objects) and state.holding is None
    if success:
        outcome = "delivered"
    stats = _policy_stats(policy)
    figures = EpisodeFigures(
        seed=seed,
        scenario=scenario.name,
        objects=len(scenario.objects),
        delivered=delivered,
        success=success,
        outcome=outcome,
        steps=len(actions),
        episode_return=float(sum(rewards)),
        path_length_m=path_length,
        collisions=sum(int(i["contact"]) for i in infos),
        invalid_actions=sum(int(i["invalid_action"]) for i in infos),
        planning_s=float(stats.get("planning_s", 0.0)),
        policy_s=policy_s,
        simulation_s=simulation_s,
        plans=int(stats.get("plans", 0)),
        replans=int(stats.get("replans", 0)),
        planner_failures=int(stats.get("failures", 0)),
        objective=first_objective,
    )
    return EpisodeRecord(
        seed=seed,
        scenario=scenario.to_dict(),
        observations={key: np.stack([o[key] for o in observations]) for key in observations[0]},
        actions=np.stack(actions),
        rewards=np.asarray(rewards, dtype=np.float64),
        terminations=np.asarray(terminations, dtype=bool),
        truncations=np.asarray(truncations, dtype=bool),
        infos={key: np.asarray([i[key] for i in infos]) for key in INFO_KEYS},
        figures=figures,
        frames=frames,
    )


def _reset_policy(policy: Any, seed: int | None) -> None:
    reset = getattr(policy, "reset", None)
    if reset is None:
        return
    try:
        reset(seed=seed)
    except TypeError:
        reset()


def _decision(policy: Any) -> dict[str, Any]:
    """The last decision of a planning policy (``ExpertPolicy.last_decision``), or a neutral one."""
    decision = getattr(policy, "last_decision", None)
    if decision is None:
        return {"planned": False, "replanned": False, "planning_s": 0.0, "fallback": False, "status": None}
    return {
        "planned": bool(decision.planned),
        "replanned": bool(decision.replanned),
        "planning_s": float(decision.planning_s),
        "fallback": bool(decision.fallback),
        "status": decision.status,
    }


def _policy_stats(policy: Any) -> dict[str, Any]:
    stats = getattr(policy, "stats", None)
    return stats.to_dict() if stats is not None else {}


def _last_objective(policy: Any) -> float | None:
    return _policy_stats(policy).get("last_objective")
