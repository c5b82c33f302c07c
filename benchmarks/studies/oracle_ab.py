"""A/B of whole ``plan()`` calls on the oracle benchmark's cases: two checkouts, each call in a fresh process.

    python -m benchmarks.studies.oracle_ab OLD_CHECKOUT NEW_CHECKOUT CASES SEEDS [--limit S] > rows.jsonl
    python -m benchmarks.studies.oracle_ab --summarize rows.jsonl [more.jsonl ...]

``CASES`` and ``SEEDS`` are comma-separated (``objects-8,covered-4`` and ``5300100,5300101``;
cases of :data:`benchmarks.speed.oracle.CASES`, drawn as that benchmark draws them, the
held object and the env's lattice included). Scenario after scenario, both checkouts
plan it, the first one alternating (``old`` first on the first scenario), so the load
falls on both alike. One JSON line per call: the checkout's name (``old`` or ``new``),
the case, seed, status, task cost, CPU and wall seconds, whether the safety stop ``S``
(default 90 s) ended it, the lower bounds' and the solves' seconds, and a digest of the
plan without its timings (equal digests: the same plan). ``--summarize`` prints, per case
and checkout, how many calls were proven optimal, the median and 95th percentile of the
wall seconds, the median CPU seconds, and for the pairs: the same plan, new cheaper, new
dearer (task cost, 1e-6); then the paired CPU seconds over every case (:func:`paired_cpu`).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import scipy.stats

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


def summary(rows: Sequence[dict]) -> list[str]:
    """The table of the module docstring, one line per case, as Markdown."""
    lines = [
        "| case | scenarios | proven old / new | median wall s old / new | p95 wall s old / new "
        "| median CPU s old / new | same plan | new cheaper | new dearer |",
        "| --- | ---: | --- | --- | --- | --- | ---: | ---: | ---: |",
    ]
    by_call = {(r["checkout"], r["case"], r["seed"]): r for r in rows}
    for case in dict.fromkeys(r["case"] for r in rows):
        seeds = sorted({r["seed"] for r in rows if r["case"] == case})
        pairs = [
            (by_call[("old", case, s)], by_call[("new", case, s)])
            for s in seeds
            if ("old", case, s) in by_call and ("new", case, s) in by_call
        ]
        if not pairs:
            continue
        old, new = zip(*pairs, strict=True)

        def both(f, old=old, new=new) -> str:
            return f"{f(old)} / {f(new)}"

        def proven(calls) -> int:
            return sum(c["status"] == "optimal" for c in calls)

        def median(key):
            return lambda calls: f"{np.median([c[key] for c in calls]):.2f}"

        def p95(calls) -> str:
            return f"{np.percentile([c['wall_s'] for c in calls], 95):.2f}"

        def cost(c) -> float:
            return np.inf if c["cost"] is None else c["cost"]

        same = sum(a["plan_digest"] == b["plan_digest"] for a, b in pairs)
        cheaper = sum(cost(b) < cost(a) - 1e-6 for a, b in pairs)
        dearer = sum(cost(b) > cost(a) + 1e-6 for a, b in pairs)
        lines.append(
            f"| {case} | {len(pairs)} | {both(proven)} | {both(median('wall_s'))} | {both(p95)} "
            f"| {both(median('cpu_s'))} | {same} | {cheaper} | {dearer} |"
        )
    lines += ["", paired_cpu(rows)]
    return lines


def paired_cpu(rows: Sequence[dict]) -> str:
    """Over every scenario both checkouts planned: CPU seconds summed, faster and slower counts (by more than
    0.05 s), the geometric mean of new / old, and the Wilcoxon signed-rank test's two-sided p-value."""
    by_call = {(r["checkout"], r["case"], r["seed"]): r["cpu_s"] for r in rows}
    keys = sorted(
        {(case, seed) for _, case, seed in by_call if ("old", case, seed) in by_call and ("new", case, seed) in by_call}
    )
    old = np.array([by_call[("old", *key)] for key in keys])
    new = np.array([by_call[("new", *key)] for key in keys])
    if len(keys) < 2:
        return f"{len(keys)} paired scenario(s): too few for a test"
    ratio = float(np.exp(np.mean(np.log(np.maximum(new, 0.01) / np.maximum(old, 0.01)))))
    p_value = float(scipy.stats.wilcoxon(old, new).pvalue)
    return (
        f"CPU over {len(keys)} paired scenarios: old {old.sum():.1f} s, new {new.sum():.1f} s; new faster on "
        f"{int((new < old - 0.05).sum())}, slower on {int((new > old + 0.05).sum())}; geometric mean new/old "
        f"{ratio:.2f}; Wilcoxon signed-rank p = {p_value:.3f}"
    )


def main(argv: list[str] | None = None) -> None:
    if argv is None:
        argv = sys.argv[1:]
    if argv and argv[0] == "--summarize":
        rows = [json.loads(line) for path in argv[1:] for line in Path(path).read_text().splitlines() if line.strip()]
        print("\n".join(summary(rows)))
        return
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
