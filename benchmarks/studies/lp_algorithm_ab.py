"""SCIP's LP algorithm through plan(), interleaved: the defaults against primal simplex for the root and the resolves.

Run from the repository: ``python -m benchmarks.studies.lp_algorithm_ab CASES SEEDS`` (CASES of
``benchmarks.speed.oracle``, comma-separated; SEEDS comma-separated). One JSON row per case, seed and
variant: status, cost, phases, CPU and wall seconds, and whether the 120 s safety stop ended the call.
"""

from __future__ import annotations

import json
import sys
import time

from benchmarks.speed.oracle import CASES
from expert import plan

VARIANTS = {"base": {}, "primal": {"params": {"lp/initalgorithm": "p", "lp/resolvealgorithm": "p"}}}


def main(cases: list[str], seeds: list[int]) -> None:
    for case in cases:
        for seed in seeds:
            query = CASES[case](seed)
            for name, extra in VARIANTS.items():
                wall, cpu = time.perf_counter(), time.process_time()
                result = plan(query.scenario, time_limit=120, lattice=query.lattice, holding=query.holding, **extra)
                row = {
                    "case": case, "seed": seed, "variant": name, "status": result.status, "cost": result.objective,
                    "phases": len(result.phases) - 1 if result.phases else 0, "cpu": time.process_time() - cpu,
                    "wall": time.perf_counter() - wall, "clock": result.stats.get("clock_stopped"),
                }  # fmt: skip
                print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main(sys.argv[1].split(","), [int(s) for s in sys.argv[2].split(",")])
