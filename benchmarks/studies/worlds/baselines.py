"""Greedy and random-phases success on the graded worlds: ``python -m benchmarks.studies.worlds.baselines N``.

Episode ``k`` of each family uses ``reset(seed=k)``, ``k = 0 .. N-1`` (the scenarios the
expert's figures use). ``greedy`` (``training.policies.greedy``) acts in the env's own
actions, ``random-phases`` (the masked random policy over the candidate phases, seeded
by the episode) in ``FetchCarryPushPhases-v0``; both get the env's 50 phases. Prints one
JSON object per family and policy: success, its 95 % Wilson interval, mean phases and
refused steps, and milliseconds per decision.
"""

from __future__ import annotations

import json
import sys
import time

from training.envs import make_env
from training.learners.heldout import evaluate, evaluate_env_actions, summarise
from training.resolve import build, resolve

FAMILIES = (*(f"objects-{k}" for k in range(1, 9)), "apartment", "unseen-layouts", "perturbed")


def main(episodes: int, families: tuple[str, ...] = FAMILIES) -> None:
    seeds = range(episodes)
    for family in families:
        started = time.perf_counter()
        greedy = build(resolve("greedy"), make_env("env", family=family))
        rows = {"greedy": evaluate_env_actions(greedy, family, seeds)}
        random = build(resolve("random-phases"), make_env("phases", family=family))
        rows["random-phases"] = evaluate(random, family, seeds, deterministic=False)
        for name, results in rows.items():
            summary = summarise(results, {})
            print(json.dumps({"family": family, "policy": name, "episodes": summary.episodes,
                              "success": summary.success, "low": summary.success_low, "high": summary.success_high,
                              "phases": summary.phases, "refused": summary.refused,
                              "decision_ms": summary.decision_ms}), flush=True)  # fmt: skip
        print(json.dumps({"family": family, "wall_s": time.perf_counter() - started}), flush=True)


if __name__ == "__main__":
    chosen = tuple(sys.argv[2].split(",")) if len(sys.argv) > 2 else FAMILIES
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 24, chosen)
