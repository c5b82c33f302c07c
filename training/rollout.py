"""The one episode loop: a policy acts in an env from a seeded reset until the episode ends, recorded step by step.

:func:`run_episode` is the loop every part of the project runs: the ``rollout`` and
``demo`` commands, dataset generation, the expert's evaluation in physics, the
benchmark, held-out evaluation of learners and DAgger's labelling. It resets the env
with a seed, resets the policy, asks it for each action (stable-baselines3's
``predict``, with the env's masks when it takes them), steps the env and keeps
everything a dataset needs (observations, actions, rewards, flags, per-step infos)
plus the figures a person wants (delivered objects, path length, collisions, invalid
actions, pushes, seconds in the policy, the masks and the simulation, replans).
Masks, frames, timings, a labeller and a step cap are options.

An expert that cannot act does not crash the episode: the episode ends after the
policy's idle fallback action, truncated, with the outcome ``planner_failed (<status>)``
(no plan: infeasible, time limit) or ``expert_stuck`` (the env would refuse the planned
action and no escape move helps), and the policy's reason in ``failure``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from expert.policy import Decision
from fetchcarry_env.observation import WorldState
from fetchcarry_env.scenario import Scenario
from training.policies.phase_expert import MASK_INFO, PROJECTED_INFO, UNEXPRESSIBLE
from training.policies.protocol import reset_policy, takes_masks
from training.policies.saved_plan import PLAN_ENDED

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


def is_timing(name: str) -> bool:
    """Whether a figure, info or record field named ``name`` is a wall-clock time (``planning_s``, ``mask_ms``):
    never reproducible, so left out of datasets and of comparisons between runs."""
    return name.endswith(("_s", "_ms"))


@dataclass(frozen=True)
class EpisodeFigures:
    """What happened in one episode (units in comments)."""

    seed: int | None
    scenario: str  # scenario name
    objects: int  # objects to deliver
    delivered: int  # objects standing at their goals at the end
    success: bool  # every object delivered and the hand empty
    outcome: str  # "delivered", "truncated" (time limit), "planner_failed (<status>)", "expert_stuck",
    # "unexpressible", "plan_ended" (a saved plan's phases ran out)
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
    objective: float | None  # the first plan's objective (its task cost), if the policy plans
    plan_status: str | None = None  # that plan's status: "optimal" (proven), "feasible" (not proven), ...
    fallback_plans: int = 0  # planning calls answered by the expert's unproven decoupled fallback plan
    pushes: int = 0  # steps that pushed a piece of clutter (info["push"] present)
    mask_s: float = 0.0  # seconds in the env's action_masks() (0 when no mask was asked for)

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
    info: dict[str, Any] = field(default_factory=dict)  # the env's info after the last step


Observer = Callable[[Any, Any, "np.ndarray | None"], None]
"""Called at every state before the step: ``(observation, action, mask)`` (``mask`` None unless masks are computed)."""


def run_episode(
    env: gym.Env,
    policy: Any,
    seed: int | None,
    *,
    options: dict[str, Any] | None = None,
    deterministic: bool = True,
    render: bool = False,
    max_steps: int | None = None,
    record_masks: bool = False,
    stop_on_failure: bool = True,
    step: Callable[[Any], tuple] | None = None,
    observe: Observer | None = None,
) -> EpisodeRecord:
    """Run one episode of ``policy`` in ``env`` from ``env.reset(seed=seed, options=options)`` and record it.

    ``policy`` has stable-baselines3's ``predict`` (:class:`training.policies.protocol.Policy`);
    it is reset first (:func:`~training.policies.protocol.reset_policy`: a random policy is
    re-seeded from ``seed``). A policy whose ``predict`` takes ``action_masks=`` is given
    the env's ``action_masks()`` at every state (timed apart from the policy). A planning
    policy (:class:`~expert.policy.ExpertPolicy`) reports each step through its
    ``last_decision`` and its totals through ``stats``.

    - ``deterministic``: handed to ``predict``;
    - ``render``: keep an rgb frame per state (the env must have ``render_mode="rgb_array"``);
    - ``max_steps``: cap the episode (for envs without a time limit, or a ``step`` that bypasses it);
    - ``record_masks`` (an env with ``action_masks()``, such as ``FetchCarryPushPhases-v0``):
      add the per-step info ``action_mask``, each state's mask (the reset's first: the mask
      the step from that state was chosen under), and ``projected``, whether the step's
      action is an expert move projected onto its nearest candidate (the policy's
      ``last_projected``);
    - ``stop_on_failure``: end the episode, truncated, when a planning policy reports a
      failure (it could only idle); the benchmark lets it run out its phases instead;
    - ``step``: what executes an action (default ``env.step``), for example the phase env's
      ``step_env_action`` for a policy that answers in the plain env's actions;
    - ``observe``: called at every state before the step with the observation, the action
      and the mask (DAgger's labeller, the expert's labels in the candidate interface).
    """
    given = takes_masks(policy)
    masks_of = env.get_wrapper_attr("action_masks") if given or record_masks or observe else None
    candidates = step is None and isinstance(env.action_space, gym.spaces.Discrete)  # actions are candidate indices
    step = env.step if step is None else step
    reset_policy(policy, seed)
    clock = _Clock()
    observation, _ = clock.time("simulation", env.reset, seed=seed, options=options)
    mask = clock.time("mask", masks_of) if masks_of is not None else None
    trace = _Trace(env, observation, render)
    if record_masks:
        trace.infos[0] |= {MASK_INFO: mask, PROJECTED_INFO: False}
    while True:
        extra = {"action_masks": mask} if given else {}
        start = np.array([not trace.actions])
        action, _ = clock.time("policy", policy.predict, observation, episode_start=start,
                               deterministic=deterministic, **extra)  # fmt: skip
        if candidates:
            action = int(np.asarray(action).reshape(-1)[0])
        if observe is not None:
            observe(observation, action, mask)
        decision = _decision(policy)
        observation, reward, terminated, truncated, info = clock.time("simulation", step, action)
        if stop_on_failure and decision.failure is not None and not terminated:
            trace.failure = decision
            truncated = True
        if max_steps is not None and len(trace.actions) + 1 >= max_steps:
            truncated = truncated or not terminated
        if masks_of is not None and (record_masks or not (terminated or truncated)):
            mask = clock.time("mask", masks_of)
        trace.add(observation, action, reward, terminated, truncated, info, decision)
        if record_masks:
            trace.infos[-1] |= {MASK_INFO: mask, PROJECTED_INFO: bool(getattr(policy, "last_projected", False))}
        if terminated or truncated:
            return trace.record(seed, policy, clock)


class _Trace:
    """What an episode has produced so far, and the record it becomes."""

    def __init__(self, env: gym.Env, observation: Any, render: bool) -> None:
        self.env, self.unwrapped, self.render = env, env.unwrapped, render
        self.scenario: Scenario = self.unwrapped.scenario
        self.frames = [env.render()] if render else []
        self.observations = [observation]
        self.states = [self.unwrapped.state]
        self.actions: list[np.ndarray] = []
        self.rewards: list[float] = []
        self.terminations: list[bool] = []
        self.truncations: list[bool] = []
        self.infos = [{**dict.fromkeys(INFO_KEYS, 0), "objective": math.nan, "delivered": self._delivered()}]
        self.pushes = 0
        self.failure: Decision | None = None  # the planning policy's failure that ended the episode
        self.first_objective: float | None = None
        self.first_status: str | None = None
        self.info: dict[str, Any] = {}

    def _delivered(self) -> int:
        return len(self.unwrapped.state.delivered(self.scenario))

    def add(self, observation: Any, action: Any, reward: float, terminated: bool, truncated: bool,
            info: dict[str, Any], decision: Decision) -> None:  # fmt: skip
        """Keep one step."""
        if self.first_objective is None and decision.objective is not None:
            self.first_objective, self.first_status = decision.objective, decision.status
        self.observations.append(observation)
        self.states.append(self.unwrapped.state)
        self.actions.append(np.asarray(action, dtype=np.int64))
        self.rewards.append(float(reward))
        self.terminations.append(bool(terminated))
        self.truncations.append(bool(truncated))
        self.pushes += info.get("push") is not None
        self.info = info
        self.infos.append(
            {
                "planning_s": decision.planning_s,
                "planned": decision.planned,
                "replanned": decision.replanned,
                "repaired": decision.repaired,
                "fallback": decision.failure is not None,
                "objective": math.nan if decision.objective is None else decision.objective,
                "invalid_action": bool(info.get("invalid_action")),
                "contact": bool(info.get("contact")),
                "delivered": self._delivered(),
            }
        )
        if self.render:
            self.frames.append(self.env.render())

    def record(self, seed: int | None, policy: Any, clock: _Clock) -> EpisodeRecord:
        """The finished episode."""
        state, scenario = self.unwrapped.state, self.scenario
        delivered = len(state.delivered(scenario))
        success = delivered == len(scenario.objects) and state.holding is None
        stats = _policy_stats(policy)
        figures = EpisodeFigures(
            seed=seed,
            scenario=scenario.name,
            objects=len(scenario.objects),
            delivered=delivered,
            success=success,
            outcome=_outcome(success, self.failure),
            failure=None if success or self.failure is None else self.failure.failure,
            steps=len(self.actions),
            episode_return=float(sum(self.rewards)),
            path_length_m=self.info["path_length"],
            collisions=sum(int(i["contact"]) for i in self.infos),
            invalid_actions=sum(int(i["invalid_action"]) for i in self.infos),
            planning_s=float(stats.get("planning_s", 0.0)),
            policy_s=clock.seconds["policy"],
            simulation_s=clock.seconds["simulation"],
            plans=int(stats.get("plans", 0)),
            replans=int(stats.get("replans", 0)),
            repairs=int(stats.get("repairs", 0)),
            planner_failures=int(stats.get("failures", 0)),
            objective=self.first_objective,
            plan_status=self.first_status,
            fallback_plans=int(stats.get("decoupled", 0)),
            pushes=self.pushes,
            mask_s=clock.seconds["mask"],
        )
        observations = self.observations
        return EpisodeRecord(
            seed=seed,
            scenario=scenario.to_dict(),
            observations={key: np.stack([o[key] for o in observations]) for key in observations[0]},
            actions=np.stack(self.actions),
            rewards=np.asarray(self.rewards, dtype=np.float64),
            terminations=np.asarray(self.terminations, dtype=bool),
            truncations=np.asarray(self.truncations, dtype=bool),
            infos={key: np.asarray([i[key] for i in self.infos]) for key in self.infos[0]},
            figures=figures,
            states=self.states,
            frames=self.frames,
            info=self.info,
        )


class _Clock:
    """Seconds spent in each kind of call (``policy``, ``mask``, ``simulation``)."""

    def __init__(self) -> None:
        self.seconds = {"policy": 0.0, "mask": 0.0, "simulation": 0.0}

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
    if failure.status in (UNEXPRESSIBLE, PLAN_ENDED):
        return failure.status
    if failure.status in ("infeasible", "time_limit") and failure.failure.startswith("no plan"):
        return f"planner_failed ({failure.status})"
    return "expert_stuck"


def _decision(policy: Any) -> Decision:
    """The last decision of a planning policy (``ExpertPolicy.last_decision``), or a neutral one."""
    decision = getattr(policy, "last_decision", None)
    return decision if decision is not None else Decision(planned=False, replanned=False, reason="no planner")


def _policy_stats(policy: Any) -> dict[str, Any]:
    stats = getattr(policy, "stats", None)
    return stats.to_dict() if stats is not None else {}
