"""DAgger on the candidate-phase interface: the expert labels the states the learner visits.

Round 0 is behaviour cloning on the expert's own episodes. Each later round runs the
current policy for some episodes on fresh seeds, asks :class:`expert.ExpertPolicy`
(which plans from any observation) what it would do in every state visited, adds the
states whose expert action is a candidate to the data, and trains again from scratch on
everything gathered (Ross, Gordon and Bagnell, 2011, with the learner acting alone).
In-process and sequential: the expert plans in this process.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from fetchcarry_env.observation import Capacity
from training.baselines.bc import BCConfig, BCPolicy, Demonstrations, record_demonstrations, train_bc


def label_learner_episodes(policy: BCPolicy, family: str, seeds: range | list[int]) -> tuple[Demonstrations, int]:
    """Run ``policy`` on ``seeds``; label each visited state with the expert's candidate. Also return the successes."""
    from expert import ExpertPolicy
    from training.learning.evaluate import make_env

    env = make_env(family)
    expert = ExpertPolicy(env)
    masks_of = env.get_wrapper_attr("action_masks")
    index_of = env.get_wrapper_attr("index_of")
    observations, masks, labels = [], [], []
    successes = 0
    for seed in seeds:
        observation, info = env.reset(seed=seed)
        expert.reset()
        for step in range(env.spec.max_episode_steps):
            mask = masks_of()
            label, _ = expert.predict(observation, episode_start=step == 0, deterministic=True)
            index = index_of(label)
            if index is not None:
                observations.append(observation["observation"].copy())
                masks.append(mask)
                labels.append(index)
            action, _ = policy.predict(observation, action_masks=mask)
            observation, _reward, terminated, truncated, info = env.step(int(action))
            if terminated or truncated:
                break
        successes += bool(info["is_success"])
    env.close()
    size = env.action_space.n
    data = Demonstrations(
        np.asarray(observations, dtype=np.float32).reshape(len(labels), -1),
        np.asarray(masks, dtype=bool).reshape(len(labels), size),
        np.asarray(labels, dtype=np.int64),
    )
    return data, successes


def train_dagger(
    family: str,
    config: BCConfig,
    demonstrations: int,
    rounds: int,
    episodes_per_round: int,
    capacity: Capacity | None = None,
    out: str | Path | None = None,
    progress: Any = None,
) -> BCPolicy:
    """BC on ``demonstrations`` expert episodes (seeds 0...), then ``rounds`` of DAgger on fresh seeds.

    ``progress``, if given, is called after each training (round 0 is the BC) with a dict:
    ``round``, ``labelled`` (states in the data), ``learner_successes`` (in the episodes
    that round labelled; None for round 0) and ``policy``. The run folder (``out``) is a
    BC run folder of the final policy.
    """
    if rounds < 0 or demonstrations < 1 or episodes_per_round < 1:
        raise ValueError("demonstrations and episodes_per_round must be positive, rounds not negative")
    capacity = capacity or Capacity()
    data = record_demonstrations(family, range(demonstrations))
    policy = train_bc(data, config, capacity, out=out if rounds == 0 else None)
    if progress is not None:
        progress({"round": 0, "labelled": len(data), "learner_successes": None, "policy": policy})
    next_seed = demonstrations
    for round_ in range(1, rounds + 1):
        seeds = range(next_seed, next_seed + episodes_per_round)
        next_seed += episodes_per_round
        new, successes = label_learner_episodes(policy, family, seeds)
        data = Demonstrations(
            np.concatenate([data.observations, new.observations]),
            np.concatenate([data.masks, new.masks]),
            np.concatenate([data.labels, new.labels]),
            {**data.stats, "dagger_rounds": round_, "labelled": len(data) + len(new)},
        )
        policy = train_bc(data, config, capacity, out=out if round_ == rounds else None)
        if progress is not None:
            progress({"round": round_, "labelled": len(data), "learner_successes": successes, "policy": policy})
    return policy
