"""One episode of a policy in the environment, recorded step by step with its figures.

:func:`run_episode` is the single loop that the ``rollout`` command, dataset generation,
the expert evaluation and the demo share: it resets the env with a seed, asks the
policy (stable-baselines3's ``predict`` protocol) for each action, steps the env and
keeps everything a dataset needs (observations, actions, rewards, flags, per-step
infos) plus the figures a person wants (delivered objects, path length, collisions,
invalid actions, planning and simulation seconds, replans).

An expert that cannot act does not crash the episode: the episode ends after the
policy's idle fallback action, truncated, with the outcome ``planner_failed (<status>)``
(no plan: infeasible, time limit) or ``expert_stuck`` (the env would refuse the planned
action and no escape move helps), and the policy's reason in ``failure``.
"""

from __future__ import annotations

import inspect
import math
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from expert.policy import Decision
from fetchcarry_env.observation import WorldState
from fetchcarry_env.scenario import Scenario
from training.policies.phase_expert import MASK_INFO, PROJECTED_INFO, UNEXPRESSIBLE

# The per-step infos recorded for every episode (Minari needs the same keys at every step):
# seconds in the planner before the step, whether the policy planned / replanned / repaired its
# action / fell back to the idle action, the objective (Eq. 1) of the plan made before the step
# (NaN when it did not plan), whether the env refused the action or stopped the base at a
# contact, and how many objects stand at their goals after the step.
INFO_KEYS = (
    "planning_s",
    "planned",
    "replanned",
    "repaired",
    "fallback",
    "objective",
    "invalid_action",
    "contact",
    "delivered",
)


@dataclass(frozen=True)
class EpisodeFigures:
    """What happened in one episode (units in comments)."""

    seed: int | None
    scenario: str  # scenario name
    objects: int  # objects to deliver
    delivered: int  # objects standing at their goals at the end
    success: bool  # every object delivered and the hand empty
    outcome: str  # "delivered", "truncated" (time limit), "planner_failed (<status>)", "expert_stuck", "unexpressible"
    failure: str | None  # the policy's reason when it could not act, else None
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
    repairs: int  # actions the expert moved so that the env acts on the planned item
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
    states: list[WorldState] = field(default_factory=list)  # the env's state after reset and after each step
    frames: list[np.ndarray] = field(default_factory=list)  # rgb renders, one per state, when asked


def run_episode(
    env: gym.Env,
    policy: Any,
    seed: int | None,
    *,
    render: bool = False,
    max_steps: int | None = None,
    record_masks: bool = False,
) -> EpisodeRecord:
    """Run one episode of ``policy`` in ``env`` from ``env.reset(seed=seed)`` and record it.

    ``policy`` has stable-baselines3's ``predict``; if it has ``reset()`` it is called
    first (with ``seed=`` when it takes one: a random policy is re-seeded). A planning
    policy (:class:`~expert.policy.ExpertPolicy`) reports each step through its
    ``last_decision`` and its totals through ``stats``. ``render`` keeps an rgb frame per
    state (the env must have ``render_mode="rgb_array"``). ``max_steps`` caps the episode
    for envs without a time limit. ``record_masks`` (an env with ``action_masks()``, such
    as ``FetchCarryPushPhases-v0``) adds the per-step info ``action_mask``: each state's
    mask, the reset's first (the mask the step from that state was chosen under); and
    ``projected``: whether the step's action is an expert move projected onto its nearest
    candidate (the policy's ``last_projected``; False for the reset and other policies).
    """
    _reset_policy(policy, seed)
    clock = _Clock()
    observation, _ = clock.time("simulation", env.reset, seed=seed)
    unwrapped = env.unwrapped
    scenario: Scenario = unwrapped.scenario
    frames = [env.render()] if render else []
    observations = [observation]
    states = [unwrapped.state]
    actions: list[np.ndarray] = []
    rewards: list[float] = []
    terminations: list[bool] = []
    truncations: list[bool] = []
    masks = env.get_wrapper_attr("action_masks") if record_masks else None
    infos = [{**dict.fromkeys(INFO_KEYS, 0), "objective": math.nan, "delivered": _delivered(unwrapped)}]
    if masks is not None:
        infos[0][MASK_INFO] = masks()
        infos[0][PROJECTED_INFO] = False
    failure: Decision | None = None
    first_objective: float | None = None
    episode_start = True
    while True:
        action, _ = clock.time(
            "policy", policy.predict, observation, episode_start=np.array([episode_start]), deterministic=True
        )
        episode_start = False
        decision = _decision(policy)
        if first_objective is None and decision.objective is not None:
            first_objective = decision.objective
        observation, reward, terminated, truncated, info = clock.time("simulation", env.step, action)
        if decision.failure is not None and not terminated:
            failure = decision
            truncated = True
        if max_steps is not None and len(actions) + 1 >= max_steps:
            truncated = truncated or not terminated
        observations.append(observation)
        states.append(unwrapped.state)
        actions.append(np.asarray(action, dtype=np.int64))
        rewards.append(float(reward))
        terminations.append(bool(terminated))
        truncations.append(bool(truncated))
        infos.append(
            {
                "planning_s": decision.planning_s,
                "planned": decision.planned,
                "replanned": decision.replanned,
                "repaired": decision.repaired,
                "fallback": decision.failure is not None,
                "objective": math.nan if decision.objective is None else decision.objective,
                "invalid_action": bool(info.get("invalid_action")),
                "contact": bool(info.get("contact")),
                "delivered": _delivered(unwrapped),
            }
        )
        if masks is not None:
            infos[-1][MASK_INFO] = masks()
            infos[-1][PROJECTED_INFO] = bool(getattr(policy, "last_projected", False))
        if render:
            frames.append(env.render())
        if terminated or truncated:
            break

    state = unwrapped.state
    delivered = len(state.delivered(scenario))
    success = delivered == len(scenario.objects) and state.holding is None
    stats = _policy_stats(policy)
    figures = EpisodeFigures(
        seed=seed,
        scenario=scenario.name,
        objects=len(scenario.objects),
        delivered=delivered,
        success=success,
        outcome=_outcome(success, failure),
        failure=None if success or failure is None else failure.failure,
        steps=len(actions),
        episode_return=float(sum(rewards)),
        path_length_m=info["path_length"],
        collisions=sum(int(i["contact"]) for i in infos),
        invalid_actions=sum(int(i["invalid_action"]) for i in infos),
        planning_s=float(stats.get("planning_s", 0.0)),
        policy_s=clock.seconds["policy"],
        simulation_s=clock.seconds["simulation"],
        plans=int(stats.get("plans", 0)),
        replans=int(stats.get("replans", 0)),
        repairs=int(stats.get("repairs", 0)),
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
        infos={key: np.asarray([i[key] for i in infos]) for key in infos[0]},
        figures=figures,
        states=states,
        frames=frames,
    )


class _Clock:
    """Seconds spent in each kind of call (``policy``, ``simulation``)."""

    def __init__(self) -> None:
        self.seconds = {"policy": 0.0, "simulation": 0.0}

    def time(self, kind: str, function: Any, *args: Any, **kwargs: Any) -> Any:
        started = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            self.seconds[kind] += time.perf_counter() - started


def _outcome(success: bool, failure: Decision | None) -> str:
    if success:
        return "delivered"
    if failure is None:
        return "truncated"
    if failure.status == UNEXPRESSIBLE:
        return UNEXPRESSIBLE
    if failure.status in ("infeasible", "time_limit") and failure.failure.startswith("no plan"):
        return f"planner_failed ({failure.status})"
    return "expert_stuck"


def _delivered(unwrapped: Any) -> int:
    return len(unwrapped.state.delivered(unwrapped.scenario))


def _reset_policy(policy: Any, seed: int | None) -> None:
    reset = getattr(policy, "reset", None)
    if reset is None:
        return
    if "seed" in inspect.signature(reset).parameters:
        reset(seed=seed)
    else:
        reset()


def _decision(policy: Any) -> Decision:
    """The last decision of a planning policy (``ExpertPolicy.last_decision``), or a neutral one."""
    decision = getattr(policy, "last_decision", None)
    return decision if decision is not None else Decision(planned=False, replanned=False, reason="no planner")


def _policy_stats(policy: Any) -> dict[str, Any]:
    stats = getattr(policy, "stats", None)
    return stats.to_dict() if stats is not None else {}
