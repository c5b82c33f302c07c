"""The planner benchmark: the paper's Section V on this machine, next to the paper's figures.

``python -m expert.bench`` (or ``fetchcarry bench planner``) plans seeded scenarios of
:mod:`expert.bench_cases` in this process, one call of :func:`expert.planner.plan`
each (model building included; one untimed warm-up call first pays for the imports),
and prints, per case: the median, 95th percentile, mean (SD) and maximum of
``total_s``, the statuses (every benchmark plan must be ``optimal``), the number of
phases of the plans, the paper's mean (SD) and our goal. A second table says where the
time goes: preprocessing, the lower bound and the reachability check, model building, SCIP proving smaller N
infeasible, and SCIP solving the final N. Every plan is also checked by the validator.

Units: seconds in the data, milliseconds in the printed tables.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field

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


def _ms(seconds: float) -> str:
    return f"{seconds * 1000:.0f}" if seconds >= 0.0095 else f"{seconds * 1000:.1f}"


def _goal(case_or_group: Case) -> str:
    if case_or_group.goal_median_s is None:
        return "-"
    text = f"median {_ms(case_or_group.goal_median_s)}"
    if case_or_group.goal_p95_s is not None:
        text += f", p95 {_ms(case_or_group.goal_p95_s)}"
    return text


def print_tables(rows: list[Case], runs: list[Run], out=sys.stdout) -> None:
    """The results table, the per-goal table and the time breakdown, in milliseconds."""
    head = (
        f"{'case':<16} {'n':>3} {'median':>7} {'p95':>7} {'mean (SD)':>14} {'max':>7}  "
        f"{'statuses':<14} {'phases':<8} {'paper s mean (SD)':<18}"
    )
    print(head, file=out)
    print("-" * len(head), file=out)
    for case in rows:
        s = summary([r for r in runs if r.case == case.name])
        statuses = " ".join(f"{k} {v}" for k, v in sorted(s["statuses"].items()))
        phases = ",".join(str(p) for p in s["phases"])
        mean_sd = f"{_ms(s['mean_s'])} ({_ms(s['sd_s'])})"
        print(
            f"{case.name:<16} {s['count']:>3} {_ms(s['median_s']):>7} {_ms(s['p95_s']):>7} {mean_sd:>14} "
            f"{_ms(s['max_s']):>7}  {statuses:<14} {phases:<8} {case.paper:<18}",
            file=out,
        )
    print("(times in ms; paper in s)", file=out)
    print(file=out)
    print(f"{'group':<8} {'n':>3} {'median':>7} {'p95':>7}  {'goal (ms)':<20} {'met':<4} {'optimal':>8}", file=out)
    for group in dict.fromkeys(c.group for c in rows):
        first = next(c for c in rows if c.group == group)
        s = summary([r for r in runs if r.group == group])
        met = "-"
        if first.goal_median_s is not None:
            ok = s["median_s"] <= first.goal_median_s
            if first.goal_p95_s is not None:
                ok = ok and s["p95_s"] <= first.goal_p95_s
            met = "yes" if ok else "no"
        optimal = f"{s['statuses'].get('optimal', 0)}/{s['count']}"
        print(
            f"{group:<8} {s['count']:>3} {_ms(s['median_s']):>7} {_ms(s['p95_s']):>7}  {_goal(first):<20} {met:<4} "
            f"{optimal:>8}",
            file=out,
        )
    print(file=out)
    print("where the time goes (share of the summed total_s):", file=out)
    print(
        f"{'group':<8} {'prepare+bound':>13} {'build':>7} {'prove N<N*':>10} {'solve N*':>9} {'other':>6} "
        f"{'extra N tried':>13}",
        file=out,
    )
    for group in dict.fromkeys(c.group for c in rows):
        selected = [r for r in runs if r.group == group]
        total = sum(r.total_s for r in selected)
        parts = [
            sum(getattr(r, name) for r in selected)
            for name in ("prepare_s", "build_s", "infeasible_solve_s", "final_solve_s")
        ]
        other = total - sum(parts)
        extra = sum(len(r.phases_tried) - 1 for r in selected) / len(selected)
        shares = " ".join(f"{100 * p / total:>{w}.0f}%" for p, w in zip([*parts, other], (12, 6, 9, 8, 5), strict=True))
        print(f"{group:<8} {shares} {extra:>13.2f}", file=out)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The benchmark's options (shared by ``python -m expert.bench`` and ``fetchcarry bench planner``)."""
    parser.add_argument(
        "--seed", type=int, default=DEFAULT_SEED, help=f"seed of every case's generator (default {DEFAULT_SEED})"
    )
    parser.add_argument(
        "--scale",
        type=float,
        default=1.0,
        help="multiply the scenarios per case (default 1: 20 per V-B area, 5 per V-C pattern and corridor, "
        "10 for 2 and 3 objects, 5 for 4)",
    )
    parser.add_argument(
        "--only", nargs="+", metavar="GROUP", help="run only these groups (V-B V-C L '2 obj' '3 obj' '4 obj')"
    )
    parser.add_argument("--time-limit", type=float, default=DEFAULT_TIME_LIMIT, help="seconds per planning call")
    parser.add_argument(
        "--baseline",
        action="store_true",
        help="SCIP's default settings and the paper's deepening from N = 3, without the lower bounds and cuts",
    )
    parser.add_argument("--json", action="store_true", help="print every run and the summaries as JSON")


def run(args: argparse.Namespace, out=sys.stdout) -> int:
    """Run the benchmark; exit status 0 when every plan is optimal and valid, 1 otherwise."""
    rows = cases(args.scale)
    if args.only:
        known = {c.group for c in rows}
        unknown = [g for g in args.only if g not in known]
        if unknown:
            from fetchcarry_env.errors import UsageError

            raise UsageError(f"unknown benchmark group(s) {', '.join(unknown)}; known: {', '.join(sorted(known))}")
        rows = [c for c in rows if c.group in args.only]
    from expert.planner import plan, solver_name  # here, so that the CLI starts without the solver

    plan(bench_cases.basic("I", np.random.default_rng(0)))  # warm-up: imports, first SCIP model
    started = time.perf_counter()
    runs: list[Run] = []
    for case in rows:
        runs.extend(run_case(case, args.seed, args.time_limit, BASELINE_OPTIONS if args.baseline else None))
    wall = time.perf_counter() - started
    ok = all(r.status == "optimal" and r.valid for r in runs)
    if args.json:
        data = {
            "solver": solver_name(),
            "seed": args.seed,
            "baseline": bool(args.baseline),
            "wall_s": wall,
            "cases": {c.name: {**summary([r for r in runs if r.case == c.name]), "paper": c.paper} for c in rows},
            "runs": [asdict(r) for r in runs],
        }
        print(json.dumps(data, indent=2), file=out)
        return 0 if ok else 1
    settings = "baseline: SCIP defaults, N from 3" if args.baseline else "tuned settings"
    print(
        f"planner benchmark: {solver_name()}, {settings}, seed {args.seed}, {len(runs)} plans in {wall:.1f} s", file=out
    )
    print(file=out)
    print_tables(rows, runs, out)
    if not ok:
        bad = [
            f"{r.scenario} ({r.status}{', invalid' if not r.valid else ''})"
            for r in runs
            if r.status != "optimal" or not r.valid
        ]
        print(f"\nnot optimal or invalid: {', '.join(bad)}", file=out)
    return 0 if ok else 1


def register(bench: argparse._SubParsersAction) -> None:
    """Add ``planner`` to ``fetchcarry bench``."""
    parser = bench.add_parser(
        "planner",
        help="the paper's Section V timings: V-B, V-C, L corridor, 2-4 objects",
        description=__doc__.split("\n\n")[1],
    )
    add_arguments(parser)
    parser.set_defaults(handler=run)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m expert.bench", description=__doc__.split("\n\n")[1])
    add_arguments(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
