"""The MILP expert through the candidate-phase interface: its actions as candidate indices.

:func:`expert_episode` runs one episode of :class:`expert.ExpertPolicy` on a
``FetchCarryPushPhases-v0`` env. At every state it records the observation, the
candidate mask and the expert's action as a candidate index (``-1`` when no allowed
candidate stands for it), and it executes the expert's own env action, so that the
episode is the expert's whether or not each action is expressible.

:func:`nearest_move` is the stand-in for an expert move no candidate expresses (phase
datasets record it, :mod:`training.policies.phase_expert`); :func:`check_projection` runs the
expert through that projection and on its own on the same seeds, and
``fetchcarry bench projection --family F --episodes N`` prints the figures
(success, projected moves per episode, extra travel cost).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from expert import ExpertPolicy
from fetchcarry_env.actions import Mode
from fetchcarry_env.kinematics import travel_cost

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


NEAREST_RULES = ("end", "detour")  # how nearest_move ranks the allowed move candidates


def nearest_move(env: gym.Env, action: np.ndarray, rule: str = "end") -> int | None:
    """The allowed move candidate nearest the env move ``action``, or None (not a move, or no move allowed).

    A stand-in for an expert move that no candidate expresses (the expert's waypoints
    lie anywhere along a line, the candidates at fixed points). ``rule`` ``end``: the
    candidate whose end lies nearest the expert's end (lattice cells, Manhattan; ties to
    the lower index). ``detour``: the candidate that adds the least travel cost on the
    way from the base to the expert's end (the paper's cost, metres; ties to the nearer end).
    """
    if rule not in NEAREST_RULES:
        raise ValueError(f"unknown rule {rule!r}: choose one of {', '.join(NEAREST_RULES)}")
    if int(action[4]) != Mode.MOVE:
        return None
    table = env.get_wrapper_attr("table")
    moves = np.flatnonzero(table.mask & (table.actions[:, 4] == int(Mode.MOVE)))
    if moves.size == 0:
        return None
    gaps = np.abs(table.actions[moves, :2] - np.asarray(action[:2])).sum(axis=1)
    if rule == "end":
        return int(moves[int(np.argmin(gaps))])
    unwrapped = env.unwrapped
    lattice, base = unwrapped.lattice, unwrapped.state.base
    end = lattice.point(int(action[0]), int(action[1]))
    detours = []
    for index, gap in zip(moves, gaps, strict=True):
        via = lattice.point(int(table.actions[index, 0]), int(table.actions[index, 1]))
        detours.append((round(travel_cost(base, via) + travel_cost(via, end), 9), int(gap), int(index)))
    return min(detours)[2]


@dataclass(frozen=True)
class ProjectionCheck:
    """One seed: the expert through the projection against its own episode (costs in metres)."""

    seed: int
    success: bool  # the projected episode delivered everything
    projected: int  # expert moves projected onto a candidate
    steps: int  # actions of the projected episode
    cost: float  # travel cost of the projected episode (info["travel_cost"])
    expert_success: bool  # the expert's own episode (env actions) delivered everything
    expert_cost: float  # its travel cost


def check_projection(
    family: str, seeds: range | list[int], *, time_limit: float = 10.0, rule: str = "end"
) -> list[ProjectionCheck]:
    """Run the expert through the projection and on its own (env actions) on each seed of ``family``."""
    from training.policies.phase_expert import PhaseExpert

    env = gym.make("FetchCarryPushPhases-v0", family=family)
    limit = env.spec.max_episode_steps if env.spec is not None and env.spec.max_episode_steps else 50
    rows = []
    try:
        for seed in seeds:
            own = expert_episode(env, ExpertPolicy(env, time_limit=time_limit), seed)
            phase = PhaseExpert(env, time_limit=time_limit, rule=rule)
            phase.reset()
            observation, info = env.reset(seed=seed)
            steps = 0
            for steps in range(1, limit + 1):
                index, _ = phase.predict(observation, episode_start=steps == 1)
                observation, _reward, terminated, truncated, info = env.step(index)
                failed = phase.last_decision is not None and phase.last_decision.failure is not None
                if terminated or truncated or failed:
                    break
            rows.append(
                ProjectionCheck(
                    seed=seed,
                    success=bool(info.get("is_success", False)),
                    projected=phase.projected,
                    steps=steps,
                    cost=float(info.get("travel_cost", 0.0)),
                    expert_success=own.success,
                    expert_cost=own.travel_cost,
                )
            )
    finally:
        env.close()
    return rows


def summarise_projection(rows: list[ProjectionCheck]) -> dict[str, float]:
    """Success rates, projected moves per episode and the extra travel cost where both episodes succeeded."""
    both = [r for r in rows if r.success and r.expert_success and r.expert_cost > 0]
    extra = np.array([r.cost / r.expert_cost - 1.0 for r in both]) if both else np.zeros(0)
    return {
        "episodes": len(rows),
        "success": float(np.mean([r.success for r in rows])),
        "expert_success": float(np.mean([r.expert_success for r in rows])),
        "projected_per_episode": float(np.mean([r.projected for r in rows])),
        "episodes_with_projection": float(np.mean([r.projected > 0 for r in rows])),
        "extra_cost_mean": float(extra.mean()) if both else float("nan"),
        "extra_cost_median": float(np.median(extra)) if both else float("nan"),
        "extra_cost_max": float(extra.max()) if both else float("nan"),
        "extra_cost_projected_mean": float(np.mean([e for e, r in zip(extra, both, strict=True) if r.projected]))
        if any(r.projected for r in both)
        else float("nan"),
    }


def mode_name(mode: int) -> str:
    return Mode(mode).name.lower()
