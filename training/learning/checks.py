"""Learning checks on the candidate-phase interface: do a small BC and a small MaskablePPO learn?

``python -m training.learning.checks bc --family basic --episodes 300`` records the
expert's episodes through ``FetchCarryPushPhases-v0``, trains BC (both encoders) and
evaluates it on held-out seeds next to the masked random policy, the greedy baseline
and the expert.
``python -m training.learning.checks ppo --family basic --steps 20000`` trains
sb3-contrib's MaskablePPO (``MultiInputPolicy``) through the interface with the
learning reward and evaluates it the same way. Held-out seeds start at 100,000, far
from the training seeds (0 onwards). Figures print; nothing is timed by a test.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

from training.baselines.bc import BCConfig, record_demonstrations, train_bc
from training.baselines.greedy import GreedyPolicy
from training.baselines.random_phases import RandomPhasePolicy
from training.learning.evaluate import evaluate, evaluate_env_actions, expert_costs, make_env, summarise

HELD_OUT = 100_000  # first evaluation seed


def check_bc(
    family: str,
    episodes: int,
    eval_episodes: int,
    encoders: list[str],
    epochs: int,
    out: Path | None,
    also: list[str] | None = None,
) -> None:
    """Record, train each encoder, evaluate on held-out seeds of ``family`` (and of each family in ``also``)."""
    torch.set_num_threads(1)
    start = time.perf_counter()
    data = record_demonstrations(family, range(episodes))
    print(f"recorded {data.stats} in {time.perf_counter() - start:.1f} s")
    seeds = range(HELD_OUT, HELD_OUT + eval_episodes)
    policies = {}
    for encoder in encoders:
        start = time.perf_counter()
        config = BCConfig(encoder=encoder, epochs=epochs)
        policies[f"bc-{encoder}"] = train_bc(
            data, config, make_env(family).unwrapped.capacity, out / f"bc-{encoder}" if out else None
        )
        print(f"bc-{encoder} trained in {time.perf_counter() - start:.0f} s")
    for evaluated in [family, *(also or [])]:
        expert = expert_costs(evaluated, seeds)
        print(f"\n{evaluated}: the expert solved {len(expert)}/{eval_episodes} held-out seeds")
        print(summarise(evaluate(RandomPhasePolicy(seed=0), evaluated, seeds), expert).line("random"))
        greedy = evaluate_env_actions(GreedyPolicy(make_env(evaluated)), evaluated, seeds)
        print(summarise(greedy, expert).line("greedy"))
        for name, policy in policies.items():
            print(summarise(evaluate(policy, evaluated, seeds), expert).line(name))


def check_dagger(
    family: str, demonstrations: int, rounds: int, per_round: int, eval_episodes: int, nearest_moves: bool = False
) -> None:
    """BC on ``demonstrations`` episodes, then DAgger rounds; the policy of each round evaluated on held-out seeds."""
    from training.baselines.dagger import train_dagger

    torch.set_num_threads(1)
    seeds = range(HELD_OUT, HELD_OUT + eval_episodes)
    expert = expert_costs(family, seeds)
    start = time.perf_counter()

    def report(row: dict) -> None:
        line = summarise(evaluate(row["policy"], family, seeds), expert).line(f"dagger {row['round']}")
        new = f", {row['new_labels']} of {row['visited']} visited states labelled" if "visited" in row else ""
        print(
            f"{line}  data {row['labelled']}{new}, learner successes {row['learner_successes']}"
            f"  ({time.perf_counter() - start:.0f} s)"
        )

    train_dagger(family, BCConfig(), demonstrations, rounds, per_round, progress=report, nearest_moves=nearest_moves)


def check_ppo(family: str, steps: int, eval_episodes: int, seed: int, out: Path | None) -> None:
    from sb3_contrib import MaskablePPO
    from stable_baselines3.common.env_util import make_vec_env

    torch.set_num_threads(1)
    env = make_vec_env(lambda: make_env(family, reward="learning"), n_envs=1, seed=seed)
    model = MaskablePPO("MultiInputPolicy", env, n_steps=512, batch_size=128, gamma=0.99, seed=seed, verbose=0)
    start = time.perf_counter()
    curve: list[tuple[int, float, float, float]] = []
    seeds = range(HELD_OUT, HELD_OUT + eval_episodes)
    expert = expert_costs(family, seeds)
    print(summarise(evaluate(RandomPhasePolicy(seed=0), family, seeds), expert).line("random"))
    chunk = max(steps // 5, 512)
    done = 0
    while done < steps:
        model.learn(chunk, reset_num_timesteps=False)
        done += chunk
        summary = summarise(evaluate(_Masked(model), family, seeds), expert)
        curve.append((done, time.perf_counter() - start, summary.success, summary.cost_ratio))
        print(summary.line(f"ppo {done}") + f"  ({time.perf_counter() - start:.0f} s)")
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        model.save(out / "ppo.zip")
        lines = ["steps,seconds,success,cost_ratio", *(",".join(str(v) for v in row) for row in curve)]
        (out / "metrics.csv").write_text("\n".join(lines) + "\n")


class _Masked:
    """MaskablePPO's predict with the masks passed through (the evaluation gives them)."""

    def __init__(self, model: Any) -> None:
        self.model = model

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
        action_masks: np.ndarray | None = None,
    ) -> tuple[np.ndarray, Any]:
        return self.model.predict(observation, state, episode_start, deterministic, action_masks=action_masks)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    bc = sub.add_parser("bc", help="behaviour cloning from expert episodes")
    bc.add_argument("--family", default="basic")
    bc.add_argument("--episodes", type=int, default=300, help="expert episodes to learn from (default: %(default)s)")
    bc.add_argument("--eval-episodes", type=int, default=100, help="held-out seeds (default: %(default)s)")
    bc.add_argument("--encoders", nargs="+", default=["mlp", "set"])
    bc.add_argument("--epochs", type=int, default=BCConfig.epochs)
    bc.add_argument("--out", type=Path, default=None, help="write the run folders here")
    bc.add_argument("--also", nargs="*", default=[], help="other families to evaluate on (e.g. multi-3)")
    ppo = sub.add_parser("ppo", help="MaskablePPO with the learning reward")
    ppo.add_argument("--family", default="basic")
    ppo.add_argument("--steps", type=int, default=20_000)
    ppo.add_argument("--eval-episodes", type=int, default=50)
    ppo.add_argument("--seed", type=int, default=0)
    ppo.add_argument("--out", type=Path, default=None)
    dagger = sub.add_parser("dagger", help="BC, then DAgger rounds with the expert labelling")
    dagger.add_argument("--family", default="push")
    dagger.add_argument("--episodes", type=int, default=100, help="expert episodes before round 1")
    dagger.add_argument("--rounds", type=int, default=2)
    dagger.add_argument("--per-round", type=int, default=50, help="learner episodes labelled per round")
    dagger.add_argument("--eval-episodes", type=int, default=50)
    dagger.add_argument(
        "--nearest-moves", action="store_true", help="label inexpressible expert moves with the nearest allowed move"
    )
    args = parser.parse_args(argv)
    if args.what == "bc":
        check_bc(args.family, args.episodes, args.eval_episodes, args.encoders, args.epochs, args.out, args.also)
    elif args.what == "dagger":
        check_dagger(args.family, args.episodes, args.rounds, args.per_round, args.eval_episodes, args.nearest_moves)
    else:
        check_ppo(args.family, args.steps, args.eval_episodes, args.seed, args.out)


if __name__ == "__main__":
    main()
