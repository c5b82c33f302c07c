"""Benchmark of MaskablePPO's training speed on the candidate phases: env steps per second with N envs.

:func:`ppo_speed` trains the ``ppo`` learner's model (:mod:`training.learners.ppo`: the
candidate actor-critic, the learning reward, SB3's vector env of ``envs`` envs) for a
number of env steps and times ``model.learn`` alone: the rollouts (policy, masks, env
steps) and the updates (PPO's epochs over each rollout), nothing else (no evaluation,
no run folder, no set-up). ``python -m benchmarks ppo`` prints it for 1 and 2 envs.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, replace
from typing import Any

from training.learners.options import BCConfig, PPOOptions


@dataclass(frozen=True)
class PPOSpeed:
    """One timed ``learn``: env steps, wall-clock seconds and where they went."""

    family: str
    envs: int
    steps: int  # env steps taken, over all envs
    seconds: float  # model.learn, wall clock
    rollout_seconds: float  # collecting the rollouts (policy, masks, env steps)
    load: float  # the one-minute load average at the end (the machine may be shared)

    @property
    def steps_per_s(self) -> float:
        return self.steps / self.seconds

    @property
    def rollout_steps_per_s(self) -> float:
        return self.steps / self.rollout_seconds


def ppo_speed(family: str, envs: int, steps: int, options: PPOOptions | None = None) -> PPOSpeed:
    """Train MaskablePPO on ``family`` with ``envs`` envs for ``steps`` env steps; time ``learn`` and its rollouts.

    ``options`` (by default the published :class:`PPOOptions`, a scratch MLP actor) set
    the rollout size, epochs and network; their ``envs`` and ``steps`` are replaced.
    """
    import torch
    from stable_baselines3.common.callbacks import BaseCallback

    from training.learners.ppo import actor_spec, make_model, make_training_env, make_vec_env

    torch.set_num_threads(1)
    options = replace(options or PPOOptions(), envs=envs, steps=steps)
    probe = make_training_env(family)
    capacity, candidates = probe.unwrapped.capacity, int(probe.action_space.n)
    features = int(probe.observation_space.shape[0])
    probe.close()
    config = BCConfig(encoder=options.encoder, hidden=options.hidden, seed=options.seed)
    actor = actor_spec(family, config, capacity, candidates, features)
    spent: list[float] = []

    class RolloutTimer(BaseCallback):
        def _on_rollout_start(self) -> None:
            self.started = time.perf_counter()

        def _on_rollout_end(self) -> None:
            spent.append(time.perf_counter() - self.started)

        def _on_step(self) -> bool:
            return True

    env = make_vec_env(family, envs)
    try:
        torch.manual_seed(options.seed)
        model = make_model(env, options, actor)
        start = time.perf_counter()
        model.learn(steps, callback=RolloutTimer())
        seconds = time.perf_counter() - start
        taken = int(model.num_timesteps)
    finally:
        env.close()
    return PPOSpeed(family, envs, taken, seconds, sum(spent), os.getloadavg()[0])


def as_row(result: PPOSpeed) -> dict[str, Any]:
    """The record ``python -m benchmarks ppo --json`` prints."""
    return {
        "family": result.family,
        "envs": result.envs,
        "steps": result.steps,
        "seconds": result.seconds,
        "steps_per_s": result.steps_per_s,
        "rollout_seconds": result.rollout_seconds,
        "rollout_steps_per_s": result.rollout_steps_per_s,
        "load": result.load,
    }
