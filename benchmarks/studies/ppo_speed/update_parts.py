"""One PPO update of the ppo learner's model on ``basic`` timed with 1 and 2 torch threads, and Adam's step alone.

    python -m benchmarks.studies.ppo_speed.update_parts > update-parts.json

Collects one rollout (256 env steps, one env), then times ``model.train()`` (10 epochs of
4 minibatches of 64: what follows every rollout) twice with each thread count, and one
Adam step over the actor's and critic's weights in its three implementations (per-tensor
loop, ``foreach``, ``fused``), one thread. Prints one JSON object with the load average.
"""

from __future__ import annotations

import json
import os
import time

import torch

from training.learners.options import BCConfig, PPOOptions
from training.learners.ppo import actor_spec, make_model, make_training_env, make_vec_env


def update_seconds() -> tuple[dict[str, list[float]], list[torch.Tensor]]:
    torch.set_num_threads(1)
    probe = make_training_env("basic")
    capacity, candidates = probe.unwrapped.capacity, int(probe.action_space.n)
    features = int(probe.observation_space.shape[0])
    probe.close()
    env = make_vec_env("basic", 1)
    try:
        model = make_model(env, PPOOptions(), actor_spec("basic", BCConfig(), capacity, candidates, features))
        model.learn(256)
        seconds: dict[str, list[float]] = {"1": [], "2": []}
        for _ in range(2):
            for threads in (1, 2):
                torch.set_num_threads(threads)
                clock = time.perf_counter()
                model.train()
                seconds[str(threads)].append(time.perf_counter() - clock)
        torch.set_num_threads(1)
        return seconds, list(model.policy.parameters())
    finally:
        env.close()


def adam_ms(parameters: list[torch.Tensor], steps: int = 50) -> dict[str, float]:
    out = {}
    for name, options in (("loop", {"foreach": False}), ("foreach", {"foreach": True}), ("fused", {"fused": True})):
        weights = [p.detach().clone().requires_grad_() for p in parameters]
        for w in weights:
            w.grad = torch.randn_like(w)
        optimiser = torch.optim.Adam(weights, lr=3e-4, eps=1e-5, **options)
        optimiser.step()
        clock = time.perf_counter()
        for _ in range(steps):
            optimiser.step()
        out[name] = 1e3 * (time.perf_counter() - clock) / steps
    return out


if __name__ == "__main__":
    start = os.getloadavg()[0]
    seconds, parameters = update_seconds()
    result = {"load_start": start, "update_seconds_by_threads": seconds,
              "weights": sum(p.numel() for p in parameters), "adam_step_ms": adam_ms(parameters),
              "load_end": os.getloadavg()[0]}  # fmt: skip
    print(json.dumps(result, indent=2))
