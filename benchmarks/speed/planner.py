"""How long the MILP planner takes on the paper's Section V cases, next to the paper's figures.

:func:`run_case` plans seeded scenarios of one case (a family of
:data:`fetchcarry_env.families.PAPER_FAMILIES`) in this process, one call of
:func:`expert.plan` each (model building included; :func:`warm_up` pays for the imports
first), and returns one :class:`Run` per call: ``total_s``, the status (every
benchmark plan should be ``optimal``), the phases, and where the time went
(preprocessing, the lower bound and the reachability check, model building, SCIP proving
smaller N infeasible, SCIP solving the final N). Every plan is also checked by the
validator. :func:`summary` gives the median, 95th percentile, mean (SD) and maximum.

Units: seconds.
"""

from __future__ import annotations

import argparse
import itertools
import json
import statistics
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

import expert  # the planner (and its solver) load at the first expert.plan call
from expert.guide import compact_phases
from expert.plans import Plan
from expert.validate import validate_plan
from fetchcarry_env.families import PAPER_AREAS, PUSH_PATTERNS, draw_paper_covered, draw_paper_multi, get_family
from fetchcarry_env.kinematics import travel_cost
from training.guidance import rollout_plan

DEFAULT_SEED = 2024
DEFAULT_TIME_LIMIT = 60.0  # seconds per planning call: generous, so that statuses are about optimality
BASELINE_OPTIONS: dict[str, Any] = {
    "separating": "default",
    "heuristics": "default",
    "lower_bound": False,
    "params": {"presolving/maxrestarts": -1, "branching/relpscost/maxlookahead": 9},
}
"""SCIP's default settings and no skeleton bounds (``lower_bound=False``).

Not the paper's plain deepening: the planner still starts at the counting bound (not 3)
and keeps the fewest-phases cuts, the counting delivery-timing cuts, the Eq. 18 link cuts
and the decoupled warm start (``docs/benchmarks/planner.md``, "What made it fast").
"""
WARM_UP_FAMILY = "paper-basic-I"
PAPER_VB = {"I": "0.05 (0.02)", "II": "0.13 (0.09)", "III": "0.22 (0.20)", "IV": "0.19 (0.23)", "V": "0.36 (0.23)"}
PAPER_VC = {"A": "0.29 (0.18)", "B": "0.53 (0.08)", "C": "0.46 (0.15)", "D": "0.64 (0.19)", "E": "0.55 (0.23)"}
"""The paper's mean (SD) per V-B area and V-C pattern, seconds, as printed in Section V."""


@dataclass(frozen=True)
class Case:
    """One row of the benchmark: a scenario family, the paper's figure and our goal (seconds)."""

    name: str
    group: str  # rows of a group share a goal (the goal is on the group's pooled times)
    family: str  # a family of fetchcarry_env.families
    repeats: int
    paper: str  # the paper's mean (SD), seconds, as printed in Section V
    goal_median_s: float | None = None
    goal_p95_s: float | None = None


def cases(scale: float = 1.0) -> list[Case]:
    """The benchmark's rows; ``scale`` multiplies the number of scenarios per row (at least 1)."""

    def n(count: int) -> int:
        return max(1, round(count * scale))

    out = [Case(f"V-B area {a}", "V-B", f"paper-basic-{a}", n(20), PAPER_VB[a], 0.020, 0.050) for a in PAPER_AREAS]
    out += [Case(f"V-C pattern {p}", "V-C", f"paper-push-{p}", n(5), PAPER_VC[p], 0.060) for p in PUSH_PATTERNS]
    out.append(Case("IV-F L corridor", "L", "paper-corridor", n(5), "0.2", 0.030))
    out.append(Case("2 objects", "2 obj", "paper-multi-2", n(10), "under 1", 0.3))
    out.append(Case("3 objects", "3 obj", "paper-multi-3", n(10), "-", 1.0))
    out.append(Case("4 objects", "4 obj", "paper-multi-4", n(5), "-", 0.3, 1.0))
    out.append(Case("5 objects", "5 obj", "paper-multi-5", n(5), "-", 1.0, 5.0))
    out.append(Case("6 objects", "6 obj", "paper-multi-6", n(3), "-", 5.0))
    out.append(Case("covered 2 obj", "cov 2", "paper-covered-2", n(5), "-"))
    out.append(Case("covered 3 obj", "cov 3", "paper-covered-3", n(5), "-", 1.0))
    return out


def groups(rows: Sequence[Case]) -> list[str]:
    """The groups of ``rows`` in their order, each once."""
    return list(dict.fromkeys(c.group for c in rows))


@dataclass
class Run:
    """One planning call's figures (seconds)."""

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


def warm_up() -> None:
    """One untimed planning call: the imports and SCIP's first model."""
    expert.plan(get_family(WARM_UP_FAMILY).sample(np.random.default_rng(0)))


def run_case(case: Case, seed: int, time_limit: float, options: dict[str, Any] | None = None) -> list[Run]:
    """Plan ``case.repeats`` scenarios of ``case.family`` drawn from one generator seeded with ``seed``.

    ``time_limit`` is in seconds per call; ``options`` go to :func:`expert.plan`.
    """
    family = get_family(case.family)
    rng = np.random.default_rng(seed)
    runs = []
    for _ in range(case.repeats):
        scenario = family.sample(rng)
        result = expert.plan(scenario, time_limit=time_limit, **(options or {}))
        runs.append(_run(case, scenario.name, result, not result.found or validate_plan(scenario, result) == []))
    return runs


def _run(case: Case, scenario: str, result: Plan, valid: bool) -> Run:
    stats = result.stats
    solves = stats.get("solves", [])
    final = solves[-1]["solve_s"] if solves and result.found else 0.0
    return Run(
        case=case.name,
        group=case.group,
        scenario=scenario,
        status=result.status,
        phases=len(result.phases),
        total_s=stats["total_s"],
        prepare_s=stats.get("prepare_s", 0.0) + stats.get("lower_bound_s", 0.0) + stats.get("reach_s", 0.0),
        build_s=stats["build_s"],
        infeasible_solve_s=stats["solve_s"] - final,
        final_solve_s=final,
        phases_tried=list(stats["phases_tried"]),
        valid=valid,
    )


def summary(runs: Sequence[Run]) -> dict[str, Any]:
    """Median, p95, mean, SD and max of ``total_s`` (seconds), statuses, phases and invalid plans."""
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


def goal_met(case: Case, group_summary: dict[str, Any]) -> bool | None:
    """Whether a group's pooled times meet its first case's goal; ``None`` without a goal."""
    if case.goal_median_s is None:
        return None
    met = group_summary["median_s"] <= case.goal_median_s
    if case.goal_p95_s is not None:
        met = met and group_summary["p95_s"] <= case.goal_p95_s
    return met


def time_shares(runs: Sequence[Run]) -> dict[str, float]:
    """Shares of the summed ``total_s`` (fractions) and the mean number of extra N tried per plan."""
    total = sum(r.total_s for r in runs)
    names = ("prepare_s", "build_s", "infeasible_solve_s", "final_solve_s")
    shares = {name: sum(getattr(r, name) for r in runs) / total for name in names}
    shares["other"] = 1.0 - sum(shares.values())
    shares["extra_n_tried"] = sum(len(r.phases_tried) - 1 for r in runs) / len(runs)
    return shares


EXTRA_PHASES_CASES = ("2 obj", "3 obj", "cov 2", "cov 3")
"""The multi-object groups of :func:`cases` that :func:`extra_phases_rows` plans (30 scenarios at scale 1)."""


def extra_phases_rows(seed: int = DEFAULT_SEED, time_limit: float = DEFAULT_TIME_LIMIT, k: int = 1) -> list[dict]:
    """Each multi-object scenario planned with ``extra_phases=0`` and ``k``: phases, travel, task cost.

    ``gain`` is how much lower the ``extra_phases=k`` plan's task cost is (0: unchanged).
    Times in seconds, travel and costs in metres.
    """
    rows = []
    for case in (c for c in cases() if c.group in EXTRA_PHASES_CASES):
        rng = np.random.default_rng(seed)
        for _ in range(case.repeats):
            scenario = get_family(case.family).sample(rng)
            base = expert.plan(scenario, time_limit=time_limit, extra_phases=0)
            longer = expert.plan(scenario, time_limit=time_limit, extra_phases=k)
            costs = [base.objective, longer.objective]
            rows.append(
                {
                    "group": case.group,
                    "scenario": scenario.name,
                    "statuses": [base.status, longer.status],
                    "phases": [len(base.phases), len(longer.phases)],
                    "travel_m": [_travel(r.phases) for r in (base, longer)],
                    "task_cost": costs,
                    "gain": costs[0] - costs[1],
                    "time_s": [base.stats["total_s"], longer.stats["total_s"]],
                }
            )
    return rows


SCALE_SEED = 7000  # scale_rows' own seeds: not the benchmark's 2024, not the families' tests'


def scale_rows(
    objects: Sequence[int], covered: Sequence[int], count: int, time_limit: float, options: dict | None = None
) -> list[dict]:
    """``count`` scenarios per size, drawn here: ``draw_paper_multi`` with ``objects`` and ``draw_paper_covered``
    (every goal covered) with ``covered`` objects, scenario ``n`` from ``default_rng(SCALE_SEED + n)``.

    One in-process :func:`expert.plan` call each (with ``options``); times in seconds.
    """
    rows = []
    for kind, sizes, draw in (("multi", objects, draw_paper_multi), ("covered", covered, draw_paper_covered)):
        for size in sizes:
            for n in range(count):
                scenario = draw(np.random.default_rng(SCALE_SEED + n), size)
                result = expert.plan(scenario, time_limit=time_limit, **(options or {}))
                rows.append(
                    {
                        "kind": kind,
                        "objects": size,
                        "seed": SCALE_SEED + n,
                        "status": result.status,
                        "gap": result.stats.get("gap"),
                        "phases": len(result.phases),
                        "total_s": result.stats["total_s"],
                        "valid": not result.found or validate_plan(scenario, result) == [],
                    }
                )
                print(
                    f"{kind} {size} seed {SCALE_SEED + n}: {result.status} {result.stats['total_s']:.2f} s", flush=True
                )
    return rows


def ab_rows(
    objects: Sequence[int], covered: Sequence[int], count: int, time_limit: float, variants: dict[str, dict]
) -> list[dict]:
    """Each scenario of :func:`scale_rows` planned with every variant (``name -> plan() options``) in turn.

    Interleaved per scenario, so the load moves all variants alike. Times in seconds.
    """
    rows = []
    for kind, sizes, draw in (("multi", objects, draw_paper_multi), ("covered", covered, draw_paper_covered)):
        for size in sizes:
            for n in range(count):
                scenario = draw(np.random.default_rng(SCALE_SEED + n), size)
                row: dict[str, Any] = {"kind": kind, "objects": size, "seed": SCALE_SEED + n}
                for name, options in variants.items():
                    result = expert.plan(scenario, time_limit=time_limit, **options)
                    row[name] = {
                        "status": result.status,
                        "objective": result.objective,
                        "total_s": result.stats["total_s"],
                        "valid": not result.found or validate_plan(scenario, result) == [],
                    }
                rows.append(row)
                cells = ", ".join(f"{v} {row[v]['status']} {row[v]['total_s']:.2f} s" for v in variants)
                print(f"{kind} {size} seed {row['seed']}: {cells}", flush=True)
    return rows


GUIDE_CASES = (("multi", 6), ("multi", 8), ("covered", 3), ("covered", 4))


def guide_rows(count: int, time_limit: float) -> list[dict]:
    """The planner with and without a guide: the optimal plan itself (an oracle, the best a learned hint can be).

    Per scenario (drawn as in :func:`scale_rows`): a plain call, a call guided by its
    answer (warm start), one guided with branching priorities too, a second plain call;
    the plain time is the lower of the two. Times in seconds.
    """
    rows = []
    for kind, size in GUIDE_CASES:
        draw = draw_paper_multi if kind == "multi" else draw_paper_covered
        for n in range(count):
            scenario = draw(np.random.default_rng(SCALE_SEED + n), size)
            plain = expert.plan(scenario, time_limit=time_limit)
            warm = expert.plan(scenario, time_limit=time_limit, guide=plain)
            branching = expert.plan(scenario, time_limit=time_limit, guide=plain, guide_branching=True)
            again = expert.plan(scenario, time_limit=time_limit)
            results = {"warm": warm, "branching": branching}
            row = {
                "kind": kind,
                "objects": size,
                "seed": SCALE_SEED + n,
                "status": plain.status,
                "plain_s": min(plain.stats["total_s"], again.stats["total_s"]),
                **{f"{name}_s": r.stats["total_s"] for name, r in results.items()},
                "same_optimum": all(
                    r.status == plain.status and abs((r.objective or 0) - (plain.objective or 0)) < 1e-6
                    for r in results.values()
                ),
                "nodes": {name: r.stats["solves"][-1].get("nodes") for name, r in {"plain": plain, **results}.items()},
            }
            rows.append(row)
            print(
                f"{kind} {size} seed {row['seed']}: {plain.status} plain {row['plain_s']:.2f} s, "
                f"warm {row['warm_s']:.2f} s, +branching {row['branching_s']:.2f} s, nodes {row['nodes']}, "
                f"same optimum {row['same_optimum']}",
                flush=True,
            )
    return rows


LEARNED_GUIDE_CASES = (("objects-6", 6), ("objects-7", 7), ("objects-8", 8), ("covered", 3), ("covered", 4))
LEARNED_GUIDE_SEED = 300_000  # objects-k scenario n is the family's of seed LEARNED_GUIDE_SEED + n (below 10^9)
GUIDED_CALLS = ("plain", "learned", "greedy", "plain again")


def learned_guide_rows(run: str, count: int, time_limit: float, kinds: Sequence[str] | None = None) -> list[dict]:
    """The planner with and without a policy's rollout as its guide (warm start and branching hint).

    Per scenario: the rollouts of the run folder ``run`` (a learned policy) and of
    ``greedy`` (:func:`training.guidance.rollout_plan`, timed apart), then four planning
    calls in turn: plain, guided by the learned rollout, guided by greedy's, plain again
    (``guide_branching=True`` for the guided ones). ``objects-k`` scenarios are the
    family's of seeds ``LEARNED_GUIDE_SEED + n``, covered ones drawn as in :func:`scale_rows`.
    ``kinds`` keeps the cases named (``objects-6``, ``covered``). Times in seconds.
    """
    import torch  # the learned policy's forward pass: one thread (as the ladder runs it on this 2-core machine)

    torch.set_num_threads(1)
    rows = []
    for kind, size in LEARNED_GUIDE_CASES:
        if kinds is not None and kind not in kinds:
            continue
        for n in range(count):
            if kind == "covered":
                seed, scenario = SCALE_SEED + n, draw_paper_covered(np.random.default_rng(SCALE_SEED + n), size)
            else:
                seed = LEARNED_GUIDE_SEED + n
                scenario = get_family(kind).sample(np.random.default_rng(seed))
            guides = {"learned": rollout_plan(run, scenario), "greedy": rollout_plan("greedy", scenario)}
            row: dict[str, Any] = {"kind": kind, "objects": size, "seed": seed, "scenario": scenario.name}
            row["guides"] = {name: _guide_figures(scenario, g) for name, g in guides.items()}
            for call in GUIDED_CALLS:
                guide = guides.get(call)
                result = expert.plan(scenario, time_limit=time_limit, guide=guide, guide_branching=guide is not None)
                last = (result.stats.get("solves") or [{}])[-1]
                row[call] = {
                    "status": result.status,
                    "objective": result.objective,
                    "phases": len(result.phases),
                    "total_s": result.stats["total_s"],
                    "nodes": last.get("nodes"),
                    "guide_warm_start": last.get("guide_warm_start"),
                    "guide_priorities": last.get("guide_priorities"),
                    "valid": not result.found or validate_plan(scenario, result) == [],
                }
            row["plain_s"] = statistics.fmean(row[c]["total_s"] for c in ("plain", "plain again"))
            reference = row["plain"]
            row["same_optimum"] = {
                name: row[name]["status"] == reference["status"]
                and abs((row[name]["objective"] or 0) - (reference["objective"] or 0)) < 1e-6
                for name in GUIDED_CALLS[1:]
            }
            rows.append(row)
            cells = ", ".join(f"{c} {row[c]['status']} {row[c]['total_s']:.2f} s" for c in GUIDED_CALLS)
            print(f"{kind} seed {seed}: {cells}; guides {row['guides']}", flush=True)
    return rows


def _guide_figures(scenario, guide: Plan) -> dict[str, Any]:
    """A rollout's figures: delivered, phases, its Eq. 1 (when delivered), validity, seconds."""
    return {
        "delivered": guide.stats["delivered"],
        "phases": len(guide.phases),
        "compact_phases": len(compact_phases(guide.phases)),
        "objective": guide.objective,
        "valid": guide.found and validate_plan(scenario, guide) == [],
        "rollout_s": guide.stats["rollout_s"],
    }


def _travel(phases) -> float:
    """The travel term of Eq. 1 (metres)."""
    return sum(travel_cost(a.base, b.base) for a, b in itertools.pairwise(phases))


def main(argv: Sequence[str] | None = None) -> None:
    """``python -m benchmarks.speed.planner extra-phases [--out FILE]``: the table of ``docs/benchmarks/planner.md``."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.speed.planner", description=main.__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    extra = sub.add_parser("extra-phases", help="extra_phases=1 against 0 on the 30 multi-object scenarios")
    extra.add_argument("--seed", type=int, default=DEFAULT_SEED)
    extra.add_argument("--out", help="write the rows as JSON here")
    scale = sub.add_parser("scale", help="8-10 objects and covered goals, seeded here, proven optimal or not")
    scale.add_argument("--objects", type=int, nargs="*", default=[8, 10])
    scale.add_argument("--covered", type=int, nargs="*", default=[3, 4])
    scale.add_argument("--count", type=int, default=4, help="scenarios per size")
    scale.add_argument("--time-limit", type=float, default=30.0, help="seconds per plan() call")
    scale.add_argument("--options", type=json.loads, default=None, help="plan() options as a JSON object")
    scale.add_argument("--out", help="write the rows as JSON here")
    ab = sub.add_parser("ab", help="plan() option variants against each other, interleaved per scenario")
    ab.add_argument("--objects", type=int, nargs="*", default=[8])
    ab.add_argument("--covered", type=int, nargs="*", default=[3, 4])
    ab.add_argument("--count", type=int, default=4, help="scenarios per size")
    ab.add_argument("--time-limit", type=float, default=30.0, help="seconds per plan() call")
    ab.add_argument("--variants", type=json.loads, required=True, help='{"name": {plan() options}, ...}')
    ab.add_argument("--out", help="write the rows as JSON here")
    guide = sub.add_parser("guide", help="the optimal plan as a guide (warm start, branching): the ceiling")
    guide.add_argument("--count", type=int, default=2, help="scenarios per case")
    guide.add_argument("--time-limit", type=float, default=60.0, help="seconds per plan() call")
    guide.add_argument("--out", help="write the rows as JSON here")
    learned = sub.add_parser("learned-guide", help="a learned rollout and greedy's as guides, against none")
    learned.add_argument("--run", help="a run folder of fetchcarry train (the learned policy)")
    learned.add_argument("--report", metavar="FILE", help="print the summary of rows saved by --out, run nothing")
    learned.add_argument("--count", type=int, default=4, help="scenarios per case")
    learned.add_argument("--kinds", nargs="*", default=None, help="cases kept: objects-6 objects-7 objects-8 covered")
    learned.add_argument("--time-limit", type=float, default=30.0, help="seconds per plan() call")
    learned.add_argument("--out", help="write the rows as JSON here")
    args = parser.parse_args(argv)
    if args.command == "ab":
        _print_ab(ab_rows(args.objects, args.covered, args.count, args.time_limit, args.variants), args.out)
        return
    if args.command == "learned-guide":
        if args.report:
            with open(args.report, encoding="utf-8") as f:
                _print_learned_guide(json.load(f), None)
            return
        _print_learned_guide(learned_guide_rows(args.run, args.count, args.time_limit, args.kinds), args.out)
        return
    if args.command == "guide":
        _print_guide(guide_rows(args.count, args.time_limit), args.out)
        return
    if args.command == "scale":
        _print_scale(scale_rows(args.objects, args.covered, args.count, args.time_limit, args.options), args.out)
        return
    rows = extra_phases_rows(args.seed)
    for row in rows:
        print(
            f"{row['group']:<6} {row['scenario']:<28} phases {row['phases']} travel "
            f"{row['travel_m'][0]:.2f} -> {row['travel_m'][1]:.2f} m  gain {row['gain']:.2f}  "
            f"time {row['time_s'][0]:.2f} / {row['time_s'][1]:.2f} s  {row['statuses']}"
        )
    changed = [r for r in rows if r["gain"] > 1e-6]
    print(f"{len(changed)} of {len(rows)} improved: " + ", ".join(f"{r['group']} {r['gain']:.2f}" for r in changed))
    if args.out:
        with open(args.out, "w", encoding="utf-8") as f:
            json.dump(rows, f, indent=1)


def _save(rows: list[dict], out: str | None) -> None:
    """Write the raw ``rows`` as JSON to ``out`` (nothing without one)."""
    if out:
        with open(out, "w", encoding="utf-8") as f:
            json.dump(rows, f, indent=1)


def _by_kind_and_size(rows: list[dict]) -> list[tuple[tuple[str, int], list[dict]]]:
    """``rows`` grouped by ``(kind, objects)``, in the order the groups first appear."""
    keys = dict.fromkeys((r["kind"], r["objects"]) for r in rows)
    return [(key, [r for r in rows if (r["kind"], r["objects"]) == key]) for key in keys]


def _print_guide(rows: list[dict], out: str | None) -> None:
    """Per case: the median ratio of the plain time to the guided times (above 1: the guide helps)."""
    for key, mine in _by_kind_and_size(rows):
        warm = statistics.median(r["plain_s"] / r["warm_s"] for r in mine)
        branching = statistics.median(r["plain_s"] / r["branching_s"] for r in mine)
        plain = statistics.median(r["plain_s"] for r in mine)
        print(
            f"{key[0]:<8} {key[1]:>2} objects  n={len(mine)}  plain median {plain:.2f} s"
            f"  speed-up warm {warm:.2f}x  warm+branching {branching:.2f}x  "
            f"same optimum {sum(r['same_optimum'] for r in mine)}/{len(mine)}"
        )
    _save(rows, out)


def _print_ab(rows: list[dict], out: str | None) -> None:
    """Per kind and size: each variant's median time, its median ratio to the first variant's, proven counts."""
    names = [k for k in rows[0] if isinstance(rows[0][k], dict)] if rows else []
    for key, mine in _by_kind_and_size(rows):
        cells = []
        for name in names:
            median = statistics.median(r[name]["total_s"] for r in mine)
            ratio = statistics.median(r[names[0]]["total_s"] / r[name]["total_s"] for r in mine)
            proven = sum(r[name]["status"] == "optimal" for r in mine)
            cells.append(f"{name} {median:.2f} s ({ratio:.2f}x, proven {proven}/{len(mine)})")
        print(f"{key[0]:<8} {key[1]:>2} objects  n={len(mine)}  " + "  ".join(cells))
    _save(rows, out)


def _print_learned_guide(rows: list[dict], out: str | None) -> None:
    """Per case and over all: the median ratio of the plain time (mean of two calls) to each guided time.

    Ratios over the scenarios every call proved optimal (a call cut at the time limit has
    no time to a proven optimum); "same optimum" over those too.
    """
    for label, mine in [*[(f"{k[0]} {k[1]}", m) for k, m in _by_kind_and_size(rows)], ("all", rows)]:
        proven = [r for r in mine if all(r[c]["status"] == "optimal" for c in GUIDED_CALLS)]
        plain = statistics.median(r["plain_s"] for r in mine)
        head = f"{label:<12} n={len(mine):<3} plain median {plain:.2f} s, all calls proven {len(proven)}/{len(mine)}"
        cells = []
        for name in GUIDED_CALLS[1:3]:
            if not proven:
                continue
            ratio = statistics.median(r["plain_s"] / r[name]["total_s"] for r in proven)
            same = sum(r["same_optimum"][name] for r in proven)
            delivered = sum(r["guides"][name]["delivered"] for r in mine)
            cells.append(f"{name} {ratio:.2f}x (same optimum {same}/{len(proven)}, rollout delivered {delivered})")
        print(head + "  " + "  ".join(cells))
    _save(rows, out)


def _print_scale(rows: list[dict], out: str | None) -> None:
    """Per kind and size: median and p95 of the time, how many were proven optimal."""
    for key, mine in _by_kind_and_size(rows):
        times = [r["total_s"] for r in mine]
        optimal = sum(r["status"] == "optimal" for r in mine)
        print(
            f"{key[0]:<8} {key[1]:>2} objects  n={len(mine)}  median {statistics.median(times):.2f} s  "
            f"p95 {float(np.percentile(times, 95)):.2f} s  proven optimal {optimal}/{len(mine)}  "
            f"invalid {sum(not r['valid'] for r in mine)}"
        )
    _save(rows, out)


if __name__ == "__main__":
    main()
