"""A/B of whole ``plan()`` calls: two checkouts (or more), case by case in turn, each case in a fresh process.

    python -m benchmarks.studies.plan_ab OLD_CHECKOUT NEW_CHECKOUT [--limit S] [CASE ...] > rows.jsonl
    python -m benchmarks.studies.plan_ab NAME=CHECKOUT NAME=CHECKOUT ... [--limit S] [CASE ...] > rows.jsonl

Cases as in ``bounds_ab.py`` (``covered:K:SEED``, ``multi:K:SEED`` or ``FAMILY:SEED``,
read by ``conditional_digest.scenario_of``). Per case and checkout one JSON line: the
call's status, phases, Eq. 1, nodes of the final solve, how the first plan was made and
the stages' seconds. Each process plans a one-object scenario first, so that imports and
SCIP's start are not in the figures. The checkouts run in the order given, case after
case, so the load moves them alike. Two unnamed checkouts are called ``old`` and ``new``.
"""

from __future__ import annotations

import json
import os
import sys

from benchmarks.studies.bounds_ab import run  # a case in a fresh process of a checkout

ONE_CASE = r"""
import hashlib, json, sys
import numpy as np
from conditional_digest import scenario_of  # this folder's, on the path after the checkout
from expert.planner import plan
from fetchcarry_env.families import draw_paper_multi

case, limit = sys.argv[1], float(sys.argv[2])
plan(draw_paper_multi(np.random.default_rng(1), 1), time_limit=10)  # imports, SCIP's first model
scenario, lattice = scenario_of(case)
result = plan(scenario, time_limit=limit, lattice=lattice)
stats = result.stats
solves = stats.get("solves", [])
print(json.dumps({
    "status": result.status, "phases": len(result.phases), "objective": result.objective,
    "digest": hashlib.sha256(repr(result.phases).encode()).hexdigest()[:16],
    "gap": stats.get("gap"), "nodes": solves[-1].get("nodes") if solves else None,
    "first_plan": stats.get("decoupled"),
    **{k: round(stats.get(k) or 0.0, 3)
       for k in ("lower_bound_s", "decoupled_s", "ordered_s", "build_s", "solve_s", "total_s")},
}))
"""


def main(argv: list[str]) -> int:
    checkouts, cases, limit = [], [], 30.0
    args = iter(argv)
    for arg in args:
        if arg == "--limit":
            limit = float(next(args))
        elif os.path.isdir(arg.split("=", 1)[-1]):  # a checkout, named (NAME=PATH) or not
            checkouts.append(arg.split("=", 1) if "=" in arg else (None, arg))
        else:
            cases.append(arg)
    if sum(name is None for name, _ in checkouts) > 2 or len(checkouts) < 2:
        sys.exit("plan_ab.py: give two checkouts (old, new) or name each one NAME=PATH")
    named = [(name or ("old", "new")[i], path) for i, (name, path) in enumerate(checkouts)]
    for case in cases:
        for name, checkout in named:
            print(json.dumps({"case": case, "code": name, **run(checkout, case, limit, ONE_CASE)}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
