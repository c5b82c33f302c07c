"""Seeded scenarios whose optima were recorded with the planner before the exact reductions of issue 9, section 5.

``tests/expert/data/recorded_optima.json`` holds, per scenario name, the status, the
number of phases and Eq. 1 of the plan made by the planner of commit d6f6ec6 (without
the fewest-phases cuts, the union and order windows and the bound on Eq. 1 per pose box).
Regenerate it with that commit on ``PYTHONPATH`` and ``python tests/expert/optima_cases.py OUT.json``.
"""

from __future__ import annotations

import dataclasses
import json
import sys

import numpy as np

from fetchcarry_env.families import (
    PAPER_AREAS,
    PUSH_PATTERNS,
    draw_paper_basic,
    draw_paper_corridor,
    draw_paper_covered,
    draw_paper_multi,
    draw_paper_push,
)
from fetchcarry_env.scenario import Scenario


def recorded_cases() -> list[Scenario]:
    """V-B (one per area), V-C (two per pattern), L (two), 2-4 objects, covered goals; each with a unique name."""
    rng = np.random.default_rng(11)
    cases = [draw_paper_basic(rng, area) for area in PAPER_AREAS]
    cases += [draw_paper_push(rng, pattern) for pattern in PUSH_PATTERNS for _ in range(2)]
    cases += [draw_paper_corridor(rng) for _ in range(2)]
    cases += [draw_paper_multi(rng, 2) for _ in range(4)]
    cases += [draw_paper_multi(rng, 3) for _ in range(3)]
    cases += [draw_paper_covered(rng, 2) for _ in range(2)]
    cases += [draw_paper_multi(rng, 4) for _ in range(2)]
    return [dataclasses.replace(s, name=f"{s.name}-{k}") for k, s in enumerate(cases)]


def main(out: str) -> None:
    from expert.planner import plan

    record = {}
    for scenario in recorded_cases():
        result = plan(scenario, time_limit=120.0)
        record[scenario.name] = {"status": result.status, "phases": len(result.phases), "objective": result.objective}
        print(scenario.name, record[scenario.name], flush=True)
    with open(out, "w") as f:
        json.dump(record, f, indent=1, sort_keys=True)


if __name__ == "__main__":
    main(sys.argv[1])
