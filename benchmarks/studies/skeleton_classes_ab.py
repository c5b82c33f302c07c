"""A/B: the skeleton graph with alike objects and pieces merged into classes (at most ``MAX_SETS`` sets) or exact.

    python -m benchmarks.studies.skeleton_classes_ab CASE SEEDS > OUT.jsonl

``CASE`` is one of :data:`benchmarks.speed.oracle.CASES`, ``SEEDS`` comma-separated. Each
seed is planned twice in-process, merged first, then exact, with a 60 s safety stop; one
JSON row per call (status, task cost, CPU seconds, the phase lower bound, whether the
clock stopped it).
"""

from __future__ import annotations

import json
import sys
import time

import expert.milp.bounds as bounds
from benchmarks.speed.oracle import CASES
from expert import plan

EXACT = 1 << 62


def main(case: str, seeds: list[int]) -> None:
    for seed in seeds:
        for max_sets in (bounds.MAX_SETS, EXACT):
            bounds.PairCosts.__init__.__defaults__ = (bounds.NEVER, max_sets)
            query = CASES[case](seed)
            cpu = time.process_time()
            result = plan(query.scenario, time_limit=60, lattice=query.lattice, holding=query.holding)
            row = {
                "case": case,
                "seed": seed,
                "max_sets": max_sets,
                "status": result.status,
                "cost": result.objective,
                "cpu_s": round(time.process_time() - cpu, 1),
                "lower_bound": result.stats.get("lower_bound"),
                "clock_stopped": bool(result.stats.get("clock_stopped")),
            }
            print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main(sys.argv[1], [int(s) for s in sys.argv[2].split(",")])
