"""A/B of whole ``plan()`` calls on the oracle benchmark's cases: two checkouts, each call in a fresh process.

    python -m benchmarks.studies.oracle_ab OLD_CHECKOUT NEW_CHECKOUT CASES SEEDS [--limit S] > rows.jsonl

``CASES`` and ``SEEDS`` are comma-separated (``objects-8,covered-4`` and ``5300100,5300101``;
cases of :data:`benchmarks.speed.oracle.CASES`, drawn as that benchmark draws them, the
held object and the env's lattice included). Scenario after scenario, both checkouts
plan it, the first one alternating (``old`` first on the first scenario), so the load
falls on both alike. One JSON line per call: the checkout's name (``old`` or ``new``),
the case, seed, status, task cost, CPU and wall seconds, whether the safety stop ``S``
(default 90 s) ended it, the lower bounds' and the solves' seconds, and a digest of the
plan without its timings (equal digests: the same plan).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from benchmarks.studies.bounds_ab import run

ONE_CALL = r"""
import hashlib, json, sys, time
from benchmarks.speed.oracle import CASES
from expert import plan

case, seed = sys.argv[1].rsplit(":", 1)
seed, limit = int(seed), float(sys.argv[2])
query = CASES[case](seed)
cpu, wall = time.process_time(), time.perf_counter()
result = plan(query.scenario, time_limit=limit, lattice=query.lattice, holding=query.holding)
cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
answer = {k: v for k, v in result.to_dict().items() if k != "stats"}  # the plan without its timings
print(json.dumps({
    "case": case, "seed": seed, "status": result.status, "cost": result.objective,
    "cpu_s": round(cpu, 2), "wall_s": round(wall, 2), "clock_stopped": bool(result.stats.get("clock_stopped")),
    "lower_bound_s": round(result.stats.get("lower_bound_s", 0.0), 2),
    "solve_s": round(result.stats.get("solve_s", 0.0), 2),
    "plan_digest": hashlib.sha256(json.dumps(answer, sort_keys=True).encode()).hexdigest()[:16],
}))
"""


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.studies.oracle_ab",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("old", type=Path, help="a checkout of the code before the change")
    parser.add_argument("new", type=Path, help="a checkout of the code after it")
    parser.add_argument("cases", help="comma-separated cases of the oracle benchmark")
    parser.add_argument("seeds", help="comma-separated seeds")
    parser.add_argument("--limit", type=float, default=90.0, help="each call's safety stop, seconds (default 90)")
    args = parser.parse_args(argv)
    checkouts = {"old": args.old, "new": args.new}
    scenarios = [(c, int(s)) for c in args.cases.split(",") for s in args.seeds.split(",")]
    for index, (case, seed) in enumerate(scenarios):
        for name in ("old", "new") if index % 2 == 0 else ("new", "old"):
            row = run(str(checkouts[name]), f"{case}:{seed}", args.limit, ONE_CALL)  # a fresh process of the checkout
            print(json.dumps({"checkout": name, **row}), flush=True)


if __name__ == "__main__":
    main()
