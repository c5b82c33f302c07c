"""Benchmark of the candidate-phase interface: the expert's actions in it, and its speed.

:func:`expressibility` measures, per scenario family, how many of the MILP expert's
actions an allowed candidate stands for (by mode, and whole episodes); :func:`speed`
measures a step of ``FetchCarryPushPhases-v0`` with its mask (a random masked policy
over the candidates) next to a step of ``FetchCarryPush-v0`` (the random masked
``MultiDiscrete`` policy) in the same run. ``python -m benchmarks phases`` prints both.
"""

from __future__ import annotations

import time
from collections import Counter
from typing import Any

import gymnasium as gym
import numpy as np

import fetchcarry_env  # noqa: F401  (registers the ids)
from expert import ExpertPolicy
from fetchcarry_env.families import TRAINING_FAMILIES, get_family
from training.data.expert_labels import NOT_EXPRESSIBLE, expert_episode, mode_name
from training.policies.random import RandomMaskedPolicy

FAMILIES = TRAINING_FAMILIES


def expressibility(family: str, episodes: int, first_seed: int = 0) -> dict[str, Any]:
    """The expert on ``episodes`` seeds of ``family``: its actions that a candidate stands for."""
    env = gym.make("FetchCarryPushPhases-v0", family=family)
    expert = ExpertPolicy(env, interface="env")  # its own env actions, as expert_episode executes them
    by_mode, expressible_by_mode = Counter(), Counter()
    whole, successes, steps, mask_s = 0, 0, 0, 0.0
    for seed in range(first_seed, first_seed + episodes):
        record = expert_episode(env, expert, seed)
        for mode, label in zip(record.modes, record.labels, strict=True):
            by_mode[mode_name(mode)] += 1
            expressible_by_mode[mode_name(mode)] += label != NOT_EXPRESSIBLE
        whole += record.expressible == record.steps
        successes += record.success
        steps += record.steps
        mask_s += record.mask_s
    env.close()
    return {
        "family": family,
        "episodes": episodes,
        "expert_success": successes / episodes,
        "actions": steps,
        "expressible": sum(expressible_by_mode.values()) / max(steps, 1),
        "by_mode": {m: (expressible_by_mode[m], n) for m, n in sorted(by_mode.items())},
        "whole_episodes": whole / episodes,
        "mask_ms": 1e3 * mask_s / max(steps, 1),
    }


def speed(family: str, steps: int, seed: int = 0) -> dict[str, float]:
    """Steps per second of the phase env (random masked candidates) and of the plain env (random masked components).

    Also the mask's time per step (``action_masks()``, the first call of a state: it
    computes the table), mean and median in milliseconds.
    """
    rates = {}
    env = gym.make("FetchCarryPushPhases-v0", family=family)
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    masks = env.get_wrapper_attr("action_masks")
    mask_s, refused, contacts = [], 0, 0
    start = time.perf_counter()
    for _ in range(steps):
        t0 = time.perf_counter()
        mask = masks()
        mask_s.append(time.perf_counter() - t0)
        _obs, _r, terminated, truncated, info = env.step(int(rng.choice(np.flatnonzero(mask))))
        refused += info["invalid_action"] is not None
        contacts += info["contact"] is not None
        if terminated or truncated:
            env.reset()
    rates["phases_steps_per_s"] = steps / (time.perf_counter() - start)
    rates["mask_ms"] = 1e3 * sum(mask_s) / steps
    rates["mask_median_ms"] = 1e3 * float(np.median(mask_s))
    rates["refused"], rates["contacts"] = refused, contacts
    env.close()
    plain = gym.make("FetchCarryPush-v0", family=family)
    policy = RandomMaskedPolicy(plain, seed=seed)
    observation, _ = plain.reset(seed=seed)
    start = time.perf_counter()
    for _ in range(steps):
        action, _ = policy.predict(observation)
        observation, _r, terminated, truncated, _info = plain.step(action)
        if terminated or truncated:
            observation, _ = plain.reset()
    rates["plain_steps_per_s"] = steps / (time.perf_counter() - start)
    plain.close()
    return rates


def time_split(family: str, steps: int, seed: int = 0) -> dict[str, Any]:
    """Where the time of :func:`speed`'s two walks goes: milliseconds per ``steps`` steps, by part.

    The phase env: ``resets`` (count), ``reset``, ``mask`` (``action_masks()``), ``step``
    (choosing a candidate and stepping); the plain env: ``resets``, ``reset``, ``policy``,
    ``step``. ``sample_ms``: the mean milliseconds of drawing one scenario of the
    family (``Family.sample``, which checks that its targets are reachable), the part of
    a reset that the env does before building its PyBullet world.
    """
    phases = {"resets": 1.0, "reset": 0.0, "mask": 0.0, "step": 0.0}
    env = gym.make("FetchCarryPushPhases-v0", family=family)
    rng = np.random.default_rng(seed)
    clock = time.perf_counter()
    env.reset(seed=seed)
    phases["reset"] += time.perf_counter() - clock
    masks = env.get_wrapper_attr("action_masks")
    for _ in range(steps):
        t0 = time.perf_counter()
        mask = masks()
        t1 = time.perf_counter()
        _obs, _r, terminated, truncated, _info = env.step(int(rng.choice(np.flatnonzero(mask))))
        t2 = time.perf_counter()
        phases["mask"] += t1 - t0
        phases["step"] += t2 - t1
        if terminated or truncated:
            env.reset()
            phases["reset"] += time.perf_counter() - t2
            phases["resets"] += 1
    env.close()
    plain_env = gym.make("FetchCarryPush-v0", family=family)
    policy = RandomMaskedPolicy(plain_env, seed=seed)
    plain = {"resets": 1.0, "reset": 0.0, "policy": 0.0, "step": 0.0}
    clock = time.perf_counter()
    observation, _ = plain_env.reset(seed=seed)
    plain["reset"] += time.perf_counter() - clock
    for _ in range(steps):
        t0 = time.perf_counter()
        action, _ = policy.predict(observation)
        t1 = time.perf_counter()
        observation, _r, terminated, truncated, _info = plain_env.step(action)
        t2 = time.perf_counter()
        plain["policy"] += t1 - t0
        plain["step"] += t2 - t1
        if terminated or truncated:
            observation, _ = plain_env.reset()
            plain["reset"] += time.perf_counter() - t2
            plain["resets"] += 1
    plain_env.close()
    draws = np.random.default_rng(seed)
    clock = time.perf_counter()
    for _ in range(int(phases["resets"])):
        get_family(family).sample(draws)
    sample_ms = 1e3 * (time.perf_counter() - clock) / phases["resets"]
    in_ms = {key: value if key == "resets" else 1e3 * value for key, value in phases.items()}
    plain_ms = {key: value if key == "resets" else 1e3 * value for key, value in plain.items()}
    return {"phases": in_ms, "plain": plain_ms, "sample_ms": sample_ms}
