"""The planner under short time limits: first plans, their quality and their proven gaps.

:func:`measure` plans the scale cases of the planner benchmark (the families
``paper-multi-4``, ``-5``, ``-6`` and ``paper-covered-3``; seed 2024, the first
``COUNTS`` scenarios of each) at every time limit of ``LIMITS`` and at ``REFERENCE_S``
(the reference: usually proven optimal), checks every plan with the validator and returns
one record per call; :func:`summary` gives, per group and limit, how many calls returned
a valid plan, how many are optimal, how many have the reference's phases and how far
their Eq. 1 is above it, and the proven gaps. Only the public planner is used, so records
written by an older checkout can be summarised against this run's reference plans. Times
are wall-clock seconds of one in-process call each (one untimed warm-up first).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

import expert  # the planner (and its solver) load at the first expert.plan call
from benchmarks.speed.planner import warm_up
from expert.validate import validate_plan
from fetchcarry_env.families import get_family

LIMITS = (0.1, 1.0)  # seconds
REFERENCE_S = 30.0  # seconds: the reference call's limit
SEED = 2024
COUNTS = {"4 obj": 5, "5 obj": 5, "6 obj": 3, "cov 3": 5}
FAMILIES = {"4 obj": "paper-multi-4", "5 obj": "paper-multi-5", "6 obj": "paper-multi-6", "cov 3": "paper-covered-3"}
RECORD_KEYS = (  # the keys of every record measure() writes
    "group",
    "index",
    "limit",
    "reference",
    "status",
    "phases",
    "objective",
    "gap",
    "seconds",
    "valid",
)
WITHIN = 0.05  # the goal: at a 1 s limit within 5 % of the optimum


def measure(
    limits: tuple[float, ...] = LIMITS,
    reference_s: float = REFERENCE_S,
    report: Callable[[dict[str, Any]], None] | None = None,
) -> list[dict[str, Any]]:
    """One record per call: group, index, limit (s), status, phases, Eq. 1, gap, seconds, valid.

    ``report``, if given, is called with each record as soon as it is measured.
    """
    warm_up()
    records = []
    for group, count in COUNTS.items():
        family = get_family(FAMILIES[group])
        rng = np.random.default_rng(SEED)
        for index in range(count):
            scenario = family.sample(rng)
            for limit in (*limits, reference_s):
                t0 = time.perf_counter()
                result = expert.plan(scenario, time_limit=limit)
                seconds = time.perf_counter() - t0
                records.append(
                    {
                        "group": group,
                        "index": index,
                        "limit": limit,
                        "reference": limit == reference_s,
                        "status": result.status,
                        "phases": len(result.phases),
                        "objective": result.objective,
                        "gap": result.stats.get("gap"),
                        "seconds": round(seconds, 4),
                        "valid": bool(result.phases) and validate_plan(scenario, result) == [],
                    }
                )
                if report is not None:
                    report(records[-1])
    return records


def summary(records: list[dict[str, Any]], reference: list[dict[str, Any]]) -> list[str]:
    """Lines of the table: per group and limit, against the reference records."""
    best = {(r["group"], r["index"]): r for r in reference if r["reference"]}
    lines = [
        f"{'group':6} {'limit s':>7} {'valid':>7} {'optimal':>7} {'ref phases':>10} "
        f"{'within 5%':>9}  Eq. 1 above the reference (%) / proven gaps (%)"
    ]
    for group in COUNTS:
        for limit in sorted({r["limit"] for r in records if not r["reference"]}):
            rows = [r for r in records if r["group"] == group and r["limit"] == limit and not r["reference"]]
            lines.append(_summary_line(group, limit, rows, best))
    return lines


def _summary_line(group: str, limit: float, rows: list[dict[str, Any]], best: dict[tuple, dict[str, Any]]) -> str:
    above, gaps, within = [], [], 0
    for r in rows:
        ref = best.get((group, r["index"]))
        if r["valid"] and ref is not None and r["phases"] == ref["phases"]:
            excess = (r["objective"] - ref["objective"]) / abs(ref["objective"])
            above.append(f"{100 * excess:.2f}")
            within += ref["status"] == "optimal" and excess <= WITHIN
        if r["gap"] is not None:
            gaps.append(f"{100 * r['gap']:.2f}")
    valid = sum(r["valid"] for r in rows)
    optimal = sum(r["status"] == "optimal" for r in rows)
    return (
        f"{group:6} {limit:7.2f} {valid:3}/{len(rows):<3} {optimal:7} {len(above):10} {within:9}  "
        f"{', '.join(above) or '-'} / {', '.join(gaps) or '-'}"
    )
