"""The planner benchmark: the paper's Section V on this machine, next to the paper's figures.

``fetchcarry bench planner`` (its options and tables are in :mod:`training.cli.bench`)
plans seeded scenarios of :mod:`expert.bench_cases` in this process, one call of :func:`expert.planner.plan`
each (model building included; one untimed warm-up call first pays for the imports),
and prints, per case: the median, 95th percentile, mean (SD) and maximum of
``total_s``, the statuses (every benchmark plan must be ``optimal``), the number of
phases of the plans, the paper's mean (SD) and our goal. A second table says where the
time goes: preprocessing, the lower bound and the reachability check, model building, SCIP proving smaller N
infeasible, and SCIP solving the final N. Every plan is also checked by the validator.

Units: seconds in the data, milliseconds in the printed tables.
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from expert import bench_cases
from fetchcarry_env.scenario import Scenario

DEFAULT_SEED = 2024
DEFAULT_TIME_LIMIT = 60.0  # seconds per planning call: generous, so that statuses are about optimality
BASELINE_OPTIONS = {
    "separating": "default",
    "heuristics": "default",
    "lower_bound": False,
    "params": {"presolving/maxrestarts": -1, "branching/relpscost/maxlookahead": 9},
}
"""``--baseline``: SCIP's default settings and the paper's deepening from N = 3, without our bounds and cuts."""


@dataclass(frozen=True)
class Case:
    """One row of the benchmark: a scenario generator, the paper's figure and our goal."""

    name: str
    group: str  # rows of a group share a goal (the goal is on the group's pooled times)
    draw: Callable[[np.random.Generator], Scenario]
    repeats: int
    paper: str  # the paper's mean (SD), seconds, as printed in Section V
    goal_median_s: float | None = None
    goal_p95_s: float | None = None


def cases(scale: float = 1.0) -> list[Case]:
    """The benchmark's rows; ``scale`` multiplies the number of scenarios per row (at least 1)."""

    def n(count: int) -> int:
        return max(1, round(count * scale))

    paper_vb = {"I": "0.05 (0.02)", "II": "0.13 (0.09)", "III": "0.22 (0.20)", "IV": "0.19 (0.23)", "V": "0.36 (0.23)"}
    paper_vc = {"A": "0.29 (0.18)", "B": "0.53 (0.08)", "C": "0.46 (0.15)", "D": "0.64 (0.19)", "E": "0.55 (0.23)"}
    out = [
        Case(f"V-B area {a}", "V-B", lambda rng, a=a: bench_cases.basic(a, rng), n(20), paper_vb[a], 0.020, 0.050)
        for a in bench_cases.AREAS
    ]
    out += [
        Case(f"V-C pattern {p}", "V-C", lambda rng, p=p: bench_cases.push(p, rng), n(5), paper_vc[p], 0.060)
        for p in bench_cases.PATTERNS
    ]
    out.append(Case("IV-F L corridor", "L", bench_cases.corridor, n(5), "0.2", 0.030))
    out.append(Case("2 objects", "2 obj", lambda rng: bench_cases.multi(2, rng), n(10), "under 1", 0.3))
    out.append(Case("3 objects", "3 obj", lambda rng: bench_cases.multi(3, rng), n(10), "-", 1.0))
    out.append(Case("4 objects", "4 obj", lambda rng: bench_cases.multi(4, rng), n(5), "-", 0.3, 1.0))
    out.append(Case("5 objects", "5 obj", lambda rng: bench_cases.multi(5, rng), n(5), "-", 1.0, 5.0))
    out.append(Case("6 objects", "6 obj", lambda rng: bench_cases.multi(6, rng), n(3), "-", 5.0))
    out.append(Case("covered 2 obj", "cov 2", lambda rng: bench_cases.covered(2, rng), n(5), "-"))
    out.append(Case("covered 3 obj", "cov 3", lambda rng: bench_cases.covered(3, rng), n(5), "-", 1.0))
    return out


@dataclass
class Run:
    """One planning call's figures."""

    case: str
    group: str
    scenario: str
    status: str
    phases: int
    total_s: float
    prepare_s: float  # preprocessing and the lower bound
    build_s: float
    infeasible_solve_s: float  # SCIP proving smaller N infeasible
    final_solve_s: float  # SCIP on the N of the answer
    phases_tried: list[int] = field(default_factory=list)
    valid: bool = True


def run_case(case: Case, seed: int, time_limit: float, options: dict | None = None) -> list[Run]:
    """Plan ``case.repeats`` scenarios drawn from one generator seeded with ``seed`` (``options`` go to ``plan``)."""
    from expert.planner import plan
    from expert.validate import validate_plan

    rng = np.random.default_rng(seed)
    runs = []
    for _ in range(case.repeats):
        scenario = case.draw(rng)
        result = plan(scenario, time_limit=time_limit, **(options or {}))
        stats = result.stats
        solves = stats.get("solves", [])
        final = solves[-1]["solve_s"] if solves and result.found else 0.0
        runs.append(
            Run(
                case=case.name,
                group=case.group,
                scenario=scenario.name,
                status=result.status,
                phases=len(result.phases),
                total_s=stats["total_s"],
                prepare_s=stats.get("prepare_s", 0.0) + stats.get("lower_bound_s", 0.0) + stats.get("reach_s", 0.0),
                build_s=stats["build_s"],
                infeasible_solve_s=stats["solve_s"] - final,
                final_solve_s=final,
                phases_tried=list(stats["phases_tried"]),
                valid=not result.found or validate_plan(scenario, result) == [],
            )
        )
    return runs


def summary(runs: Sequence[Run]) -> dict:
    """Median, p95, mean, SD and max of ``total_s`` (seconds), statuses and phases."""
    times = [r.total_s for r in runs]
    statuses: dict[str, int] = {}
    for r in runs:
        statuses[r.status] = statuses.get(r.status, 0) + 1
    return {
        "count": len(runs),
        "median_s": statistics.median(times),
        "p95_s": float(np.percentile(times, 95)),
        "mean_s": statistics.fmean(times),
        "sd_s": statistics.stdev(times) if len(times) > 1 else 0.0,
        "max_s": max(times),
        "statuses": statuses,
        "phases": sorted({r.phases for r in runs}),
        "invalid": sum(not r.valid for r in runs),
    }
