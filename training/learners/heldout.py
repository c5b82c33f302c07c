"""Held-out evaluation of a learner: success and travel cost seed by seed, against the MILP expert.

:func:`evaluate` runs a policy (stable-baselines3's ``predict`` protocol, given the
masks as ``action_masks=``) for one episode per seed on ``FetchCarryPushPhases-v0``
and reports success, the paper's travel cost, phases and refusals; :func:`heldout_success`
gives a learner's success rate and mean cost on the held-out seeds (PPO's learning
curves); :func:`expert_costs` runs the expert on the same seeds so that costs compare
scenario by scenario.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from expert import ExpertPolicy
from training.data.expert_labels import expert_episode
from training.envs import make_env
from training.learners.options import HELDOUT_SEED_BASE
from training.rollout import EpisodeRecord, run_episode
from training.stats import wilson


@dataclass(frozen=True)
class EpisodeResult:
    """One episode of a policy."""

    seed: int
    success: bool
    travel_cost: float  # the paper's cost of the episode's moves (metres, Manhattan plus 0.1 x the diagonal term)
    phases: int  # steps taken
    refused: int  # steps the env refused
    decision_s: float = 0.0  # seconds spent in the policy's predict (masks not included)


@dataclass(frozen=True)
class Summary:
    """A policy's results over a set of seeds (the cost ratio over seeds both it and the expert solved)."""

    episodes: int
    success: float
    success_low: float  # 95 % Wilson interval
    success_high: float
    cost_ratio: float  # mean over successful seeds of cost / expert's cost on the same seed (nan if none)
    phases: float  # mean phases per episode
    refused: float  # mean refused steps per episode
    decision_ms: float  # mean milliseconds per decision (the policy's predict, masks not included)

    def line(self, name: str) -> str:
        return (
            f"{name:10} success {self.success:6.1%} [{self.success_low:.0%}, {self.success_high:.0%}]  "
            f"cost ratio {self.cost_ratio:5.2f}  phases {self.phases:5.1f}  refused {self.refused:4.1f}  "
            f"decision {self.decision_ms:6.2f} ms"
        )


def evaluate(
    policy: Any, family: str, seeds: Iterable[int], deterministic: bool = True, **env_options: Any
) -> list[EpisodeResult]:
    """One episode per seed of ``policy`` on ``family`` through the candidate phases (masks given to it).

    ``env_options``: more ``gym.make`` keywords: the observation mode and image options of an image
    network, ``capacity`` (the observation's slots, as :func:`training.envs.make_env` takes them; None or
    absent: the family's).
    """
    return _episodes(policy, make_env("phases", family=family, **env_options), seeds, deterministic)


def evaluate_env_actions(policy: Any, family: str, seeds: Iterable[int]) -> list[EpisodeResult]:
    """One episode per seed of a policy that returns the env's own actions, on ``FetchCarryPush-v0``."""
    return _episodes(policy, make_env("env", family=family), seeds, True)


def _episodes(policy: Any, env: gym.Env, seeds: Iterable[int], deterministic: bool) -> list[EpisodeResult]:
    """Run ``policy`` one episode per seed in ``env`` (closed at the end) until the env ends it."""
    try:
        return [
            _result(seed, run_episode(env, policy, seed, deterministic=deterministic, stop_on_failure=False))
            for seed in seeds
        ]
    finally:
        env.close()


def _result(seed: int, episode: EpisodeRecord) -> EpisodeResult:
    figures, info = episode.figures, episode.info
    return EpisodeResult(seed, bool(info["is_success"]), float(info["travel_cost"]), figures.steps,
                         figures.invalid_actions, figures.policy_s)  # fmt: skip


def heldout_success(policy: Any, family: str, episodes: int, **env_options: Any) -> tuple[float, float]:
    """Success rate and mean travel cost (metres) of ``policy`` on ``episodes`` held-out seeds of ``family``.

    The seeds are ``HELDOUT_SEED_BASE + k`` (:mod:`training.learners.options`), which no
    training episode of a learner uses; ``(nan, nan)`` for no episode. ``env_options``: as for
    :func:`evaluate` (an image network's observation mode).
    """
    if episodes < 1:
        return math.nan, math.nan
    results = evaluate(policy, family, range(HELDOUT_SEED_BASE, HELDOUT_SEED_BASE + episodes), **env_options)
    return float(np.mean([r.success for r in results])), float(np.mean([r.travel_cost for r in results]))


def expert_costs(family: str, seeds: Iterable[int]) -> dict[int, float]:
    """The expert's travel cost per seed it solves (through the same interface, its own env actions)."""
    env = make_env("phases", family=family)
    expert = ExpertPolicy(env, interface="env")  # its own env actions, as expert_episode executes them
    costs = {}
    try:
        for seed in seeds:
            record = expert_episode(env, expert, seed)
            if record.success:
                costs[seed] = record.travel_cost
    finally:
        env.close()
    return costs


def summarise(results: list[EpisodeResult], expert: dict[int, float]) -> Summary:
    """Success (with its 95 % Wilson interval: :func:`training.evaluation.metrics.wilson`), cost ratio, phases."""
    n = len(results)
    wins = sum(r.success for r in results)
    low, high = wilson(wins, n)
    ratios = [r.travel_cost / expert[r.seed] for r in results if r.success and expert.get(r.seed, 0.0) > 0]
    return Summary(
        episodes=n,
        success=wins / n if n else math.nan,
        success_low=low,
        success_high=high,
        cost_ratio=float(np.mean(ratios)) if ratios else math.nan,
        phases=float(np.mean([r.phases for r in results])) if results else math.nan,
        refused=float(np.mean([r.refused for r in results])) if results else math.nan,
        decision_ms=1e3 * sum(r.decision_s for r in results) / max(sum(r.phases for r in results), 1),
    )
