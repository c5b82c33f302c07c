"""A/B of SCIP's presolving "default" (the planner's) against "fast": whole ``plan()`` calls, one at a time.

    python -m benchmarks.studies.presolve_fast_ab OUT.jsonl [SAFETY_S]

Fresh seeds: ``objects-8`` 5300400-5300409, ``objects-10`` and ``covered-4`` 5300400-5300405,
drawn as :data:`benchmarks.speed.oracle.CASES` draws them. Per scenario the two variants
run back to back, the order alternating (even seed: default first). Before every call
the process's geometry caches are cleared and the garbage collected, so that the second
call of a scenario does not inherit the first one's tables; one unrecorded warm-up pair
first. Each call has a wall-clock safety stop of ``SAFETY_S`` seconds (default 60):
compare CPU seconds, SCIP's nodes and LP iterations, which the load does not move. One
JSON row per call (status, objective, phases, CPU and wall seconds, SCIP's share, nodes,
LP iterations, whether the clock stopped it) is appended to ``OUT.jsonl``.
"""

from __future__ import annotations

import gc
import json
import os
import sys
import time
from typing import Any

import expert.milp.moves as moves
import expert.planning.solving as solving
import fetchcarry_env.regions as regions
from benchmarks.speed.oracle import CASES
from expert import plan

VARIANTS: dict[str, dict[str, Any]] = {"base": {}, "cand": {"presolving": "fast"}}
PLAN = (
    ("objects-8", range(5300400, 5300410)),
    ("objects-10", range(5300400, 5300406)),
    ("covered-4", range(5300400, 5300406)),
)
WARM_UP = ("objects-8", 5300100)  # a development seed
SCIP: dict[str, Any] = {}  # what the SCIP solves of the current call counted
_optimize = solving.optimize


def counted_optimize(model: Any, deadline: Any, nodes: int | None = None) -> Any:
    """The planner's SCIP solve, counting its nodes, LP iterations and CPU seconds into :data:`SCIP`."""
    cpu, wall = time.process_time(), time.perf_counter()
    status = _optimize(model, deadline, nodes)
    SCIP["models"] += 1
    SCIP["nodes"] += model.getNTotalNodes()
    SCIP["lpiter"] += model.getNLPIterations()
    SCIP["scip_cpu_s"] += time.process_time() - cpu
    SCIP["scip_wall_s"] += time.perf_counter() - wall
    return status


def clear_caches() -> None:
    """Forget the geometry the planner caches per process, and collect the garbage."""
    moves.geometry_moves.cache_clear()
    for name in dir(regions):
        cached = getattr(regions, name)
        if callable(getattr(cached, "cache_clear", None)):
            cached.cache_clear()
    gc.collect()


def call(case: str, seed: int, variant: str, safety_s: float, first: bool | None) -> dict[str, Any]:
    """One ``plan()`` call of ``variant`` on ``case`` ``seed``, and its figures."""
    problem = CASES[case](seed)
    clear_caches()
    SCIP.update(models=0, nodes=0, lpiter=0, scip_cpu_s=0.0, scip_wall_s=0.0)
    cpu, wall = time.process_time(), time.perf_counter()
    result = plan(
        problem.scenario, time_limit=safety_s, lattice=problem.lattice, holding=problem.holding, **VARIANTS[variant]
    )
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    stats = result.stats
    return {
        "case": case, "seed": seed, "variant": variant, "opts": VARIANTS[variant], "first": first,
        "status": result.status, "objective": result.objective, "phases": len(result.phases),
        "cpu_s": round(cpu, 3), "wall_s": round(wall, 3),
        **{key: round(value, 3) if isinstance(value, float) else value for key, value in SCIP.items()},
        "clock_stopped": bool(stats.get("clock_stopped")), "stopped_by": stats.get("stopped_by"),
        "loadavg": os.getloadavg()[0],
    }  # fmt: skip


def main(out: str, safety_s: float) -> None:
    solving.optimize = counted_optimize
    for variant in VARIANTS:
        call(*WARM_UP, variant, safety_s, None)
    for case, seeds in PLAN:
        for seed in seeds:
            order = ("base", "cand") if seed % 2 == 0 else ("cand", "base")
            for k, variant in enumerate(order):
                row = call(case, seed, variant, safety_s, k == 0)
                print(json.dumps(row), flush=True)
                with open(out, "a") as file:
                    file.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else 60.0)
