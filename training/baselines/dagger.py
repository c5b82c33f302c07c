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


def label_learner_episodes(
    policy: BCPolicy, family: str, seeds: range | list[int], nearest_moves: bool = False
) -> tuple[Demonstrations, int, int]:
    """Run ``policy`` on ``seeds``; label each visited state with the expert's candidate.

    Returns the labelled states, the learner's successes and the number of states visited.

    A state whose expert action no candidate expresses is left out, or, with
    ``nearest_moves``, labelled with the allowed move nearest the expert's move
    (:func:`training.learning.expert_phases.nearest_move`).
    """
    from expert import ExpertPolicy
    from training.learning.evaluate import make_env
    from training.learning.expert_phases import nearest_move

    env = make_env(family)
    expert = ExpertPolicy(env)
    masks_of = env.get_wrapper_attr("action_masks")
    index_of = env.get_wrapper_attr("index_of")
    observations, masks, labels = [], [], []
    successes = visited = 0
    for seed in seeds:
        observation, info = env.reset(seed=seed)
        expert.reset()
        for step in range(env.spec.max_episode_steps):
            mask = masks_of()
            visited += 1
            label, _ = expert.predict(observation, episode_start=step == 0, deterministic=True)
            index = index_of(label)
            if index is None and nearest_moves:
                index = nearest_move(env, label)
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
    return data, successes, visited


def train_dagger(
    family: str,
    config: BCConfig,
    demonstrations: int,
    rounds: int,
    episodes_per_round: int,
    capacity: Capacity | None = None,
    out: str | Path | None = None,
    progress: Any = None,
    nearest_moves: bool = False,
) -> BCPolicy:
    """BC on ``demonstrations`` expert episodes (seeds 0...), then ``rounds`` of DAgger on fresh seeds.

    ``progress``, if given, is called after each training (round 0 is the BC) with a dict:
    ``round``, ``labelled`` (states in the data), ``learner_successes`` (in the episodes
    that round labelled; None for round 0) and ``policy``; from round 1, ``visited``
    (states the learner visited) and ``new_labels`` (those the round labelled). The run folder (``out``) is a
    BC run folder of the final policy. ``nearest_moves``: see :func:`label_learner_episodes`.
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
        new, successes, visited = label_learner_episodes(policy, family, seeds, nearest_moves)
        data = Demonstrations(
            np.concatenate([data.observations, new.observations]),
            np.concatenate([data.masks, new.masks]),
            np.concatenate([data.labels, new.labels]),
            {**data.stats, "dagger_rounds": round_, "labelled": len(data) + len(new)},
        )
        policy = train_bc(data, config, capacity, out=out if round_ == rounds else None)
        if progress is not None:
            row = {"round": round_, "labelled": len(data), "learner_successes": successes, "policy": policy}
            progress({**row, "visited": visited, "new_labels": len(new)})
    return policy
