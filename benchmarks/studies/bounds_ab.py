"""A/B of the planner's lower bounds: two checkouts, case by case in turn, each in a fresh process.

    python -m benchmarks.studies.bounds_ab OLD_CHECKOUT NEW_CHECKOUT [--limit S] [CASE ...] > rows.jsonl

A case is ``covered:K:SEED`` or ``multi:K:SEED`` (``draw_paper_covered`` / ``draw_paper_multi``
with ``default_rng(SEED)`` and K objects, as ``python -m benchmarks.speed.planner scale``
draws them) or ``FAMILY:SEED`` (the scenario ``reset(seed=SEED)`` draws on the family's
env). Per case and checkout, one JSON line: the whole problem's skeleton bound and travel
bound (``expert.milp.bounds.skeleton`` and ``min_travel``, seconds and values), a digest of
the action windows (``action_windows`` at the skeleton's N and N + 1, with and without the
last action at N - 1: every action's phases and the phases given each other action), then one
``plan()`` call with ``--limit`` seconds (default 10, the expert's): status, phases, Eq. 1,
the stages' seconds. The old checkout runs first, then the new, case after case, so the
load moves both alike. Exits 1 if the two checkouts' bounds or windows differ on any case.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent  # conditional_digest.scenario_of reads the cases

ONE_CASE = r"""
import hashlib, json, sys, time
from conditional_digest import _SEARCHED_PER_CALL, costs_of, scenario_of  # this folder's, after the checkout
from expert.milp.bounds import PairCosts, action_windows, min_travel, skeleton
from expert.milp.problem import prepare
from expert.planner import plan

case, limit = sys.argv[1], float(sys.argv[2])
scenario, lattice = scenario_of(case)
problem = prepare(scenario, lattice)
clock = time.perf_counter()
pairs, free = costs_of(problem)
costs = free if _SEARCHED_PER_CALL else pairs  # the shared graph's costs, later
bound = skeleton(problem, costs)
skeleton_s = time.perf_counter() - clock
clock = time.perf_counter()
travel = min_travel(problem) if _SEARCHED_PER_CALL else min_travel(problem, costs)
travel_s = time.perf_counter() - clock
sha = hashlib.sha256()
for phases in (bound.phases, bound.phases + 1):
    for last_at_end in (False, True):
        windows = action_windows(problem, phases, pairs, last_at_end=last_at_end)
        for key in sorted(windows.phases):
            sha.update(repr((key, sorted(windows.phases[key]))).encode())
        for key in sorted(windows.given):
            sha.update(repr((key, sorted(windows.given[key]))).encode())
result = plan(scenario, time_limit=limit, lattice=lattice)
stats = result.stats
print(json.dumps({
    "skeleton_s": round(skeleton_s, 4), "min_travel_s": round(travel_s, 4),
    "skeleton": [bound.phases, list(bound.earliest)], "min_travel": round(travel, 6),
    "windows": sha.hexdigest()[:16],
    "status": result.status, "phases": len(result.phases), "objective": stats.get("milp_objective"),
    **{k: round(stats.get(k) or 0.0, 3) for k in ("lower_bound_s", "decoupled_s", "build_s", "solve_s", "total_s")},
}))
"""

CASES = (
    *(f"covered:3:{seed}" for seed in range(7000, 7004)),
    *(f"covered:4:{seed}" for seed in range(7000, 7002)),
    *(f"multi:8:{seed}" for seed in range(7000, 7002)),
    *(f"objects-8:{seed}" for seed in (7, 9, 14, 17)),
    "apartment:0",
    "apartment:8",
)


def run(checkout: str, case: str, limit: float, script: str = ONE_CASE) -> dict:
    """One case in a fresh process of ``checkout`` running ``script``: its JSON row (``plan_ab.py`` runs its own)."""
    done = subprocess.run(
        [sys.executable, "-c", script, case, str(limit)],
        cwd=checkout,
        env={**os.environ, "PYTHONPATH": os.pathsep.join((checkout, str(HERE)))},
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv: list[str]) -> int:
    old, new, *rest = argv
    limit = 10.0
    if rest[:1] == ["--limit"]:
        limit, rest = float(rest[1]), rest[2:]
    differ = 0
    for case in rest or CASES:
        rows = {name: run(checkout, case, limit) for name, checkout in (("old", old), ("new", new))}
        same = all(rows["old"][k] == rows["new"][k] for k in ("skeleton", "min_travel", "windows"))
        differ += not same
        for name, row in rows.items():
            print(json.dumps({"case": case, "code": name, "bounds_equal": same, **row}), flush=True)
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
