"""Learning checks on the candidate-phase interface: do a small BC and a small MaskablePPO learn?

:func:`check_bc` (``python -m benchmarks learning-checks bc``) records the expert's episodes
through ``FetchCarryPushPhases-v0``, trains BC (each encoder) and evaluates it on
held-out seeds next to the masked random policy, the greedy baseline and the expert.
:func:`check_ppo` (``python -m benchmarks learning-checks ppo``) trains sb3-contrib's
MaskablePPO (``MultiInputPolicy``) through the interface with the learning reward and
evaluates it the same way. Held-out seeds start at
:data:`~training.learners.options.HELDOUT_SEED_BASE` (100,000), far from the training
seeds (0 onwards). Each figure goes to ``report`` (a line of text) as it is measured.
DAgger is ``fetchcarry train dagger`` (:mod:`training.learners.dagger`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import torch

from training.envs import make_env
from training.learners.bc import BCConfig, record_demonstrations, train_bc
from training.learners.heldout import evaluate, evaluate_env_actions, expert_costs, summarise
from training.learners.options import HELDOUT_SEED_BASE
from training.policies.greedy import GreedyPolicy
from training.policies.random import RandomPhasePolicy


def check_bc(
    family: str,
    episodes: int,
    eval_episodes: int,
    encoders: list[str],
    epochs: int,
    out: Path | None,
    also: list[str] | None = None,
    report: Callable[[str], None] = print,
) -> None:
    """Record, train each encoder, evaluate on held-out seeds of ``family`` (and of each family in ``also``).

    ``episodes`` expert episodes (seeds 0...) to learn from, ``eval_episodes`` held-out
    seeds, ``epochs`` of BC per encoder; ``out``, if given, gets a run folder per encoder.
    """
    torch.set_num_threads(1)
    start = time.perf_counter()
    data = record_demonstrations(family, range(episodes))
    report(f"recorded {data.stats} in {time.perf_counter() - start:.1f} s")
    seeds = range(HELDOUT_SEED_BASE, HELDOUT_SEED_BASE + eval_episodes)
    policies = {}
    for encoder in encoders:
        start = time.perf_counter()
        config = BCConfig(encoder=encoder, epochs=epochs)
        policies[f"bc-{encoder}"] = train_bc(
            data, config, make_env("phases", family=family).unwrapped.capacity, out / f"bc-{encoder}" if out else None
        )
        report(f"bc-{encoder} trained in {time.perf_counter() - start:.0f} s")
    for evaluated in [family, *(also or [])]:
        expert = expert_costs(evaluated, seeds)
        report(f"\n{evaluated}: the expert solved {len(expert)}/{eval_episodes} held-out seeds")
        report(summarise(evaluate(RandomPhasePolicy(seed=0), evaluated, seeds), expert).line("random"))
        greedy = evaluate_env_actions(GreedyPolicy(make_env("phases", family=evaluated)), evaluated, seeds)
        report(summarise(greedy, expert).line("greedy"))
        for name, policy in policies.items():
            report(summarise(evaluate(policy, evaluated, seeds), expert).line(name))


def check_ppo(
    family: str, steps: int, eval_episodes: int, seed: int, out: Path | None, report: Callable[[str], None] = print
) -> None:
    """MaskablePPO for ``steps`` env steps, evaluated on held-out seeds five times on the way.

    ``out``, if given, gets ``ppo.zip`` and ``metrics.csv`` (steps, seconds, success, cost ratio).
    """
    from sb3_contrib import MaskablePPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.logger import Logger

    torch.set_num_threads(1)
    env = make_vec_env(lambda: make_env("phases", family=family, reward="learning"), n_envs=1, seed=seed)
    model = MaskablePPO("MultiInputPolicy", env, n_steps=512, batch_size=128, gamma=0.99, seed=seed, verbose=0)
    model.set_logger(Logger(folder=None, output_formats=[]))  # no empty SB3-* folder in /tmp
    start = time.perf_counter()
    curve: list[tuple[int, float, float, float]] = []
    seeds = range(HELDOUT_SEED_BASE, HELDOUT_SEED_BASE + eval_episodes)
    expert = expert_costs(family, seeds)
    report(summarise(evaluate(RandomPhasePolicy(seed=0), family, seeds), expert).line("random"))
    chunk = max(steps // 5, 512)
    done = 0
    while done < steps:
        model.learn(chunk, reset_num_timesteps=False)
        done += chunk
        summary = summarise(evaluate(model, family, seeds), expert)
        curve.append((done, time.perf_counter() - start, summary.success, summary.cost_ratio))
        report(summary.line(f"ppo {done}") + f"  ({time.perf_counter() - start:.0f} s)")
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        model.save(out / "ppo.zip")
        lines = ["steps,seconds,success,cost_ratio", *(",".join(str(v) for v in row) for row in curve)]
        (out / "metrics.csv").write_text("\n".join(lines) + "\n")
