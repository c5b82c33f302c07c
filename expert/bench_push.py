"""Push-aside while carrying against the empty-hand push: travel and phases of the planner's plans.

Plans every scenario of the push family (seeds ``0 .. FAMILY_SEEDS - 1``) and of the
paper's patterns A-E (``bench_cases.push``, ``PATTERN_SEEDS`` seeds each) and prints,
per group, the plans' phase counts and travel cost (Eq. 1's distance term: Manhattan
plus ``W2`` times the diagonal term, metres) and how many plans push while holding.
Only the public planner is used, so the same file measures an older checkout too::

    PYTHONPATH=$PWD python expert/bench_push.py after.json
    PYTHONPATH=/path/to/old/checkout python expert/bench_push.py before.json
    PYTHONPATH=$PWD python expert/bench_push.py after.json before.json   # compare

The first path is where the records are written (JSON, one per scenario); with a
second path, the records there are compared with these scenario by scenario.
"""

from __future__ import annotations

import itertools
import json
import statistics
import sys
from pathlib import Path

import numpy as np

from expert import bench_cases, plan
from fetchcarry_env.families import get_family
from fetchcarry_env.kinematics import travel_cost

FAMILY_SEEDS = 40  # push family scenarios
PATTERN_SEEDS = 8  # scenarios per pattern of the paper's Table I
TIME_LIMIT = 30.0  # seconds per plan


def scenarios():
    """``(group, name, scenario)`` for every benchmarked scenario, seeded."""
    family = get_family("push")
    for seed in range(FAMILY_SEEDS):
        yield "push family", f"push-{seed}", family.sample(np.random.default_rng(seed))
    for pattern in bench_cases.PATTERNS:
        for seed in range(PATTERN_SEEDS):
            yield f"pattern {pattern}", f"{pattern}-{seed}", bench_cases.push(pattern, np.random.default_rng(seed))


def measure() -> list[dict]:
    """One record per scenario: status, phases, travel (metres), objective, pushes made holding an object."""
    records = []
    for group, name, scenario in scenarios():
        result = plan(scenario, time_limit=TIME_LIMIT)
        phases = result.phases
        travel = sum(travel_cost(a.base, b.base) for a, b in itertools.pairwise(phases))
        holding_pushes = sum(
            1 for before, now in itertools.pairwise(phases) if now.action == "push" and before.holding is not None
        )
        records.append(
            {
                "group": group,
                "name": name,
                "status": result.status,
                "phases": len(phases),
                "travel": travel,
                "objective": result.objective,
                "holding_pushes": holding_pushes,
                "seconds": result.stats.get("total_s"),
            }
        )
    return records


def summary(records: list[dict]) -> None:
    print(f"{'group':12} {'plans':>5} {'phases':>7} {'travel m':>9} {'holding-push plans':>19} {'median s':>9}")
    for group, rows in itertools.groupby(records, key=lambda r: r["group"]):
        rows = [r for r in rows if r["phases"]]
        print(
            f"{group:12} {len(rows):5d} {statistics.mean(r['phases'] for r in rows):7.2f} "
            f"{statistics.mean(r['travel'] for r in rows):9.2f} {sum(r['holding_pushes'] > 0 for r in rows):19d} "
            f"{statistics.median(r['seconds'] for r in rows):9.3f}"
        )


def compare(after: list[dict], before: list[dict]) -> None:
    """Per group: mean travel and phases before and after, how many plans got shorter or fewer phases."""
    old = {r["name"]: r for r in before}
    print(
        f"\n{'group':12} {'n':>3} {'travel before':>13} {'after':>7} {'saved':>6} {'saved %':>7} {'max %':>6} "
        f"{'phases before':>13} {'after':>6} {'fewer phases':>12} {'longer':>6}"
    )
    groups = [(g, list(rows)) for g, rows in itertools.groupby(after, key=lambda r: r["group"])]
    everything = [("all", after), *groups]
    for group, rows in everything:
        pairs = [(old[r["name"]], r) for r in rows if r["phases"] and old.get(r["name"], {}).get("phases")]
        if not pairs:
            continue
        t0 = statistics.mean(b["travel"] for b, _ in pairs)
        t1 = statistics.mean(a["travel"] for _, a in pairs)
        worst = max((b["travel"] - a["travel"]) / b["travel"] for b, a in pairs if b["travel"] > 0)
        p0 = statistics.mean(b["phases"] for b, _ in pairs)
        p1 = statistics.mean(a["phases"] for _, a in pairs)
        fewer = sum(a["phases"] < b["phases"] for b, a in pairs)
        longer = sum(a["travel"] > b["travel"] + 1e-9 for b, a in pairs)
        print(
            f"{group:12} {len(pairs):3d} {t0:13.2f} {t1:7.2f} {t0 - t1:6.2f} {100 * (t0 - t1) / t0:7.1f} "
            f"{100 * worst:6.1f} {p0:13.2f} {p1:6.2f} {fewer:12d} {longer:6d}"
        )


def main(argv: list[str]) -> None:
    if not argv:
        print(__doc__)
        raise SystemExit(2)
    records = measure()
    Path(argv[0]).write_text(json.dumps(records, indent=1))
    summary(records)
    if len(argv) > 1:
        compare(records, json.loads(Path(argv[1]).read_text()))


if __name__ == "__main__":
    main(sys.argv[1:])
