"""What the task cost changes against the paper's rule: one row per scenario, both answers.

    python -m benchmarks.studies.task_cost_departure > docs/benchmarks/raw/task-cost-departure.jsonl

The paper deepens to the fewest phases that admit a plan and minimises Eq. 1 among those
(``plan(..., extra_phases=0)``); the project minimises the task cost over every phase
count (``plan(...)``, the default: the phase bound proves that more phases cannot pay).
Each row gives, for one scenario (seeds 900000 + k of each family, which no doc reports
and no split draws), both answers' phases, task cost, Eq. 1 and seconds, the phase cap
the bound proved, and whether the answers differ. Every plan is solved to proven
optimality (no node budget; 300 s safety stop).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from expert.planner import plan
from expert.plans import eq1_value
from fetchcarry_env.families import get_family

FAMILIES = ("basic", "push", "corridor", "multi-2", "multi-3", "multi-4", "objects-3", "objects-4", "objects-5")
SEEDS = range(900_000, 900_010)


def row(family: str, seed: int) -> dict:
    """Both answers on ``family``'s scenario of ``seed``."""
    scenario = get_family(family).sample(np.random.default_rng(seed))
    out: dict = {"family": family, "seed": seed, "objects": len(scenario.objects)}
    for name, extra in (("paper", 0), ("task", None)):
        started = time.perf_counter()
        result = plan(scenario, time_limit=300.0, extra_phases=extra)
        seconds = time.perf_counter() - started
        phases = len(result.phases)
        out[name] = {
            "status": result.status,
            "phases": phases,
            "task_cost": result.objective,
            "eq1": eq1_value(scenario, result.phases, phases) if result.phases else None,
            "seconds": seconds,
            "phase_cap": result.stats.get("phase_cap"),
        }
    out["differ"] = out["paper"]["phases"] != out["task"]["phases"] or (
        out["paper"]["task_cost"] is not None
        and out["task"]["task_cost"] is not None
        and out["task"]["task_cost"] < out["paper"]["task_cost"] - 1e-6
    )
    return out


def main() -> int:
    for family in FAMILIES:
        for seed in SEEDS:
            print(json.dumps(row(family, seed)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
