"""Push-aside while carrying against the empty-hand push: travel and phases of the planner's plans.

:func:`measure` plans every scenario of the ``push`` family (seeds ``0 .. FAMILY_SEEDS - 1``)
and of the paper's patterns A-E (the ``paper-push-A`` ... ``paper-push-E`` families,
``PATTERN_SEEDS`` seeds each) and returns one record per scenario; :func:`summary` gives,
per group, the plans' phase counts and travel cost (Eq. 1's distance term: Manhattan plus
``W2`` times the diagonal term, metres) and how many plans push while holding;
:func:`compare` sets the records against those of another checkout, scenario by scenario.
"""

from __future__ import annotations

import itertools
import statistics
from collections.abc import Iterator
from typing import Any

import numpy as np

import expert  # the planner (and its solver) load at the first expert.plan call
from fetchcarry_env.families import PUSH_PATTERNS, get_family
from fetchcarry_env.kinematics import travel_cost
from fetchcarry_env.scenario import Scenario

FAMILY_SEEDS = 40  # push family scenarios
PATTERN_SEEDS = 8  # scenarios per pattern of the paper's Table I
TIME_LIMIT = 30.0  # seconds per plan
RECORD_KEYS = ("group", "name", "status", "phases", "travel", "objective", "holding_pushes", "seconds")


def scenarios() -> Iterator[tuple[str, str, Scenario]]:
    """``(group, name, scenario)`` for every benchmarked scenario, seeded."""
    family = get_family("push")
    for seed in range(FAMILY_SEEDS):
        yield "push family", f"push-{seed}", family.sample(np.random.default_rng(seed))
    for pattern in PUSH_PATTERNS:
        paper = get_family(f"paper-push-{pattern}")
        for seed in range(PATTERN_SEEDS):
            yield f"pattern {pattern}", f"{pattern}-{seed}", paper.sample(np.random.default_rng(seed))


def measure() -> list[dict[str, Any]]:
    """One record per scenario: status, phases, travel (metres), objective, pushes made holding, seconds."""
    records = []
    for group, name, scenario in scenarios():
        result = expert.plan(scenario, time_limit=TIME_LIMIT)
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


def summary(records: list[dict[str, Any]]) -> list[str]:
    """Lines of the table: per group, plans, mean phases and travel (m), holding-push plans, median seconds."""
    lines = [f"{'group':12} {'plans':>5} {'phases':>7} {'travel m':>9} {'holding-push plans':>19} {'median s':>9}"]
    for group, rows in itertools.groupby(records, key=lambda r: r["group"]):
        rows = [r for r in rows if r["phases"]]
        if not rows:
            continue
        lines.append(
            f"{group:12} {len(rows):5d} {statistics.mean(r['phases'] for r in rows):7.2f} "
            f"{statistics.mean(r['travel'] for r in rows):9.2f} {sum(r['holding_pushes'] > 0 for r in rows):19d} "
            f"{statistics.median(r['seconds'] for r in rows):9.3f}"
        )
    return lines


def compare(after: list[dict[str, Any]], before: list[dict[str, Any]]) -> list[str]:
    """Lines per group: mean travel and phases before and after, how many plans got fewer phases or longer."""
    old = {r["name"]: r for r in before}
    lines = [
        f"{'group':12} {'n':>3} {'travel before':>13} {'after':>7} {'saved':>6} {'saved %':>7} {'max %':>6} "
        f"{'phases before':>13} {'after':>6} {'fewer phases':>12} {'longer':>6}"
    ]
    groups = [(g, list(rows)) for g, rows in itertools.groupby(after, key=lambda r: r["group"])]
    for group, rows in [("all", after), *groups]:
        pairs = [(old[r["name"]], r) for r in rows if r["phases"] and old.get(r["name"], {}).get("phases")]
        if pairs:
            lines.append(_compare_line(group, pairs))
    return lines


def _compare_line(group: str, pairs: list[tuple[dict[str, Any], dict[str, Any]]]) -> str:
    t0 = statistics.mean(b["travel"] for b, _ in pairs)
    t1 = statistics.mean(a["travel"] for _, a in pairs)
    worst = max(((b["travel"] - a["travel"]) / b["travel"] for b, a in pairs if b["travel"] > 0), default=0.0)
    p0 = statistics.mean(b["phases"] for b, _ in pairs)
    p1 = statistics.mean(a["phases"] for _, a in pairs)
    fewer = sum(a["phases"] < b["phases"] for b, a in pairs)
    longer = sum(a["travel"] > b["travel"] + 1e-9 for b, a in pairs)
    saved = 100 * (t0 - t1) / t0 if t0 else 0.0
    return (
        f"{group:12} {len(pairs):3d} {t0:13.2f} {t1:7.2f} {t0 - t1:6.2f} {saved:7.1f} "
        f"{100 * worst:6.1f} {p0:13.2f} {p1:6.2f} {fewer:12d} {longer:6d}"
    )
