"""The oracle at home scale: fresh seeds, in-process on this machine, each planning call proven optimal or not.

    python -m benchmarks.speed.oracle --seeds 10 --compare 4 --filed FILED_CHECKOUT \\
        --out docs/benchmarks/raw/oracle-home-scale.jsonl

**Cases** (scenario ``n`` of a case is drawn from seed ``SEED_BASE + n``, or ``--first-seed`` + n
for a fresh set, which no other measurement uses): the graded worlds ``objects-8``, ``objects-10``, ``objects-12`` and
``apartment`` as the env draws them (its lattice, its seed); every goal covered with 3
and 4 objects (``draw_paper_covered``); and ``dagger-8``: the state an ``objects-8``
episode reaches after ``2 + n % 5`` random candidate phases (the masked random policy
of ``FetchCarryPushPhases-v0``), planned from there as DAgger's expert labels it
(the held object in the hand, the base where it stands).

**Rows** (one JSON object per line, ``case``, ``seed``, ``solver``): ``planner`` is
:func:`expert.plan` with its defaults (no node budget: until SCIP proves the optimum;
``--safety`` seconds as the safety stop, recorded as ``stopped_by``), timed in-process
(``wall_s``, and ``cpu_s``, which a loaded machine changes less). On the first
``--compare`` seeds of each case also: ``scip-defaults``, the same planner with SCIP's
default settings (separating, heuristics on); ``filed``, the planner of ``--filed``
(another checkout, the planner as filed) in a worker process of its own, timed there
in-process with its defaults and the same safety stop (it answers its own objective,
Eq. 1 among the fewest phases); ``highs`` and ``cp-sat`` (when ``ortools`` is
installed), each MILP the planner solved, exported as MPS (the cutoff of a longer
count is not in the file: it is solved without), solved one thread each, summed and
set beside the sum of SCIP's own solve times of the same models (``scip_solve_s``).
Ratios are taken within a seed (interleaved: every solver on one scenario before the
next scenario), so the machine's load falls on all alike.

The summary prints, per case, the planner's median and 95th percentile seconds and
how many were proven, and the median ratio of each other solver's seconds to the
planner's on the compared seeds.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import fetchcarry_env  # noqa: F401  (registers the envs)
from expert import plan
from expert.plans import Plan
from expert.tracking import on_lattice
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_covered
from fetchcarry_env.observation import decode
from fetchcarry_env.scenario import Scenario
from training.policies.random import RandomPhasePolicy

SEED_BASE = 5_300_000  # scenario n of every case: seed SEED_BASE + n (no doc reports these seeds)
SAFETY_S = 300.0  # seconds: the safety stop of every planning call (the goals are far below it)
SCIP_DEFAULTS = {"separating": "default", "heuristics": "default"}  # presolving is SCIP's default already


@dataclass(frozen=True)
class Query:
    """One planning question: the scenario, the object in the hand, the lattice the env acts on."""

    case: str
    seed: int
    scenario: Scenario
    lattice: Lattice | None = None
    holding: str | None = None


def _env_query(case: str, family: str, seed: int) -> Query:
    env = gym.make("FetchCarryPush-v0", family=family)
    env.reset(seed=seed)
    base = env.unwrapped
    return Query(case, seed, base.scenario, base.lattice)


def _covered_query(case: str, objects: int, seed: int) -> Query:
    return Query(case, seed, draw_paper_covered(np.random.default_rng(seed), objects))


def _dagger_query(case: str, family: str, seed: int) -> Query:
    """The state after ``2 + seed % 5`` random candidate phases of an episode of ``family``."""
    env = gym.make("FetchCarryPushPhases-v0", family=family)
    observation, _ = env.reset(seed=seed)
    policy = RandomPhasePolicy(env, seed=seed)
    for _ in range(2 + seed % 5):
        action, _ = policy.predict(observation, deterministic=False)
        observation, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    base = env.unwrapped
    scenario, world = on_lattice(*decode(observation, base.capacity), base.lattice)
    return Query(case, seed, scenario, base.lattice, world.holding)


CASES: dict[str, Callable[[int], Query]] = {
    "objects-8": lambda seed: _env_query("objects-8", "objects-8", seed),
    "objects-10": lambda seed: _env_query("objects-10", "objects-10", seed),
    "objects-12": lambda seed: _env_query("objects-12", "objects-12", seed),
    "apartment": lambda seed: _env_query("apartment", "apartment", seed),
    "covered-3": lambda seed: _covered_query("covered-3", 3, seed),
    "covered-4": lambda seed: _covered_query("covered-4", 4, seed),
    "dagger-8": lambda seed: _dagger_query("dagger-8", "objects-8", seed),
}
GOALS = {  # the filed goals, seconds: (median, 95th percentile or None, every one proven within)
    "objects-8": (1.0, 5.0, None),
    "objects-10": (5.0, None, 60.0),
    "objects-12": (5.0, None, 60.0),
    "apartment": (2.0, 10.0, None),
    "dagger-8": (0.5, None, None),
    "covered-3": (0.5, None, None),
    "covered-4": (2.0, None, None),
}


def timed_plan(query: Query, safety: float, export: Path | None = None, **options: Any) -> tuple[Plan, float, float]:
    """:func:`expert.plan` on ``query`` in this process; the plan, wall and CPU seconds."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = plan(
        query.scenario,
        time_limit=safety,
        lattice=query.lattice,
        holding=query.holding,
        export_models=export,
        **options,
    )
    return result, time.perf_counter() - wall, time.process_time() - cpu


def plan_row(query: Query, solver: str, result: Plan, wall: float, cpu: float) -> dict[str, Any]:
    """The row of one planning call."""
    return {
        "case": query.case,
        "seed": query.seed,
        "solver": solver,
        "status": result.status,
        "stopped_by": result.stats.get("stopped_by"),
        "phases": len(result.phases),
        "cost": result.objective,
        "lower_bound": result.stats.get("lower_bound"),
        "phases_tried": result.stats.get("phases_tried"),
        "wall_s": wall,
        "cpu_s": cpu,
    }


class FiledPlanner:
    """The planner of another checkout, in a worker process of its own (:mod:`benchmarks.speed.filed_planner`)."""

    def __init__(self, checkout: Path) -> None:
        worker = Path(__file__).with_name("filed_planner.py")
        environment = {**os.environ, "PYTHONPATH": str(checkout.resolve())}
        self.process = subprocess.Popen(
            [sys.executable, str(worker)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=environment
        )

    def ask(self, query: Query, safety: float) -> dict[str, Any]:
        """The worker's answer for ``query`` (its own status, phases, objective and seconds)."""
        lattice = query.lattice
        request = {
            "scenario": query.scenario.to_dict(),
            "holding": query.holding,
            "lattice": None if lattice is None else [*lattice.origin, lattice.resolution, *lattice.shape],
            "time_limit": safety,
        }
        assert self.process.stdin is not None and self.process.stdout is not None
        self.process.stdin.write(json.dumps(request) + "\n")
        self.process.stdin.flush()
        line = self.process.stdout.readline()
        if not line:
            raise RuntimeError("the filed planner's worker ended without an answer")
        return json.loads(line)

    def close(self) -> None:
        if self.process.stdin is not None:
            self.process.stdin.close()
        self.process.wait()


def highs_seconds(mps: Path, safety: float) -> tuple[str, float | None, float]:
    """HiGHS on one MPS file, one thread: its status, objective and wall seconds."""
    import highspy

    highs = highspy.Highs()
    highs.setOptionValue("output_flag", False)
    highs.setOptionValue("threads", 1)
    highs.setOptionValue("time_limit", safety)
    highs.readModel(str(mps))
    wall = time.perf_counter()
    highs.run()
    seconds = time.perf_counter() - wall
    status = highs.modelStatusToString(highs.getModelStatus())
    objective = highs.getInfo().objective_function_value if status == "Optimal" else None
    return status, objective, seconds


def cp_sat_seconds(mps: Path, safety: float) -> tuple[str, float | None, float] | None:
    """CP-SAT (OR-Tools' model builder, one worker) on one MPS file; None when OR-Tools is not installed."""
    try:
        from ortools.linear_solver.python import model_builder
    except ImportError:
        return None
    model = model_builder.Model()
    model.import_from_mps_file(str(mps))
    solver = model_builder.Solver("sat")
    solver.set_time_limit_in_seconds(safety)
    solver.set_solver_specific_parameters("num_workers:1")
    wall = time.perf_counter()
    status = solver.solve(model)
    seconds = time.perf_counter() - wall
    name = status.name.lower()
    return name, (solver.objective_value if name == "optimal" else None), seconds


def model_rows(query: Query, result: Plan, folder: Path, safety: float) -> Iterator[dict[str, Any]]:
    """HiGHS's and CP-SAT's rows: every exported model of ``result`` solved, beside SCIP's own seconds."""
    solves = [s for s in result.stats.get("solves", []) if s.get("exported")]
    scip_s = sum(s.get("solve_s", 0.0) for s in solves)
    for solver, solve in (("highs", highs_seconds), ("cp-sat", cp_sat_seconds)):
        answers = [solve(folder / s["exported"], safety) for s in solves]
        if any(a is None for a in answers):
            continue
        yield {
            "case": query.case,
            "seed": query.seed,
            "solver": solver,
            "models": len(answers),
            "statuses": [a[0] for a in answers],
            "objectives": [a[1] for a in answers],
            "scip_objectives": [_optimum(folder / s["exported"]) for s in solves],
            "wall_s": sum(a[2] for a in answers),
            "scip_solve_s": scip_s,
        }


def _optimum(mps: Path) -> float | None:
    """SCIP's optimum of an exported model (its JSON beside the MPS)."""
    return json.loads(mps.with_suffix(".json").read_text())["optimum"]


def rows(
    cases: Sequence[str], seeds: int, compare: int, filed: Path | None, safety: float, first_seed: int = SEED_BASE
) -> Iterator[dict]:
    """Every row of the table, scenario after scenario (every solver on one before the next)."""
    worker = FiledPlanner(filed) if filed is not None and compare else None
    try:
        for n in range(seeds):
            for case in cases:
                query = CASES[case](first_seed + n)
                with tempfile.TemporaryDirectory() as folder:
                    export = Path(folder) if n < compare else None
                    result, wall, cpu = timed_plan(query, safety, export)
                    yield plan_row(query, "planner", result, wall, cpu)
                    if export is None:
                        continue
                    yield from model_rows(query, result, export, safety)
                yield plan_row(query, "scip-defaults", *timed_plan(query, safety, **SCIP_DEFAULTS))
                if worker is not None:
                    yield {"case": case, "seed": query.seed, "solver": "filed", **worker.ask(query, safety)}
    finally:
        if worker is not None:
            worker.close()


def _solved(row: dict) -> bool:
    """Whether a row's solve(s) ended proven optimal (a planner's status, or every model's)."""
    if "statuses" in row:
        return all(status.lower() == "optimal" for status in row["statuses"])
    return row["status"] == "optimal"


def summary(all_rows: Sequence[dict]) -> list[str]:
    """Per case: the planner's median, p95 and proven count against the goals; the other solvers' median ratios."""
    lines = []
    for case in dict.fromkeys(r["case"] for r in all_rows):
        mine = [r for r in all_rows if r["case"] == case and r["solver"] == "planner"]
        seconds = sorted(r["wall_s"] for r in mine)
        proven = sum(r["status"] == "optimal" for r in mine)
        p95 = float(np.percentile(seconds, 95)) if seconds else float("nan")
        median, p95_goal, within = GOALS.get(case, (None, None, None))
        goal = f"goal median {median} s" + (f", p95 {p95_goal} s" if p95_goal else "")
        goal += f", all proven within {within} s" if within else ""
        lines.append(
            f"{case}: {len(mine)} scenarios, {proven} proven; median {statistics.median(seconds):.2f} s, "
            f"p95 {p95:.2f} s, max {seconds[-1]:.2f} s ({goal})"
        )
        by_seed = {r["seed"]: r for r in mine}
        for solver in ("scip-defaults", "filed", "highs", "cp-sat"):
            others = [r for r in all_rows if r["case"] == case and r["solver"] == solver]
            if not others:
                continue
            if solver in ("highs", "cp-sat"):
                ratios = [r["wall_s"] / r["scip_solve_s"] for r in others if r["scip_solve_s"] > 0]
                against = "SCIP's solve seconds on the same models"
            else:
                ratios = [r["wall_s"] / by_seed[r["seed"]]["wall_s"] for r in others]
                against = "the planner's seconds"
            done = sum(_solved(r) for r in others)
            if ratios:
                lines.append(
                    f"  {solver}: median {statistics.median(ratios):.2f}x {against} "
                    f"(range {min(ratios):.2f}-{max(ratios):.2f}x, {len(others)} scenarios, {done} proven optimal)"
                )
    return lines


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.speed.oracle",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES), help="the cases (default all)")
    parser.add_argument("--seeds", type=int, default=10, help="scenarios per case (default 10)")
    parser.add_argument("--compare", type=int, default=4, help="of those, how many the other solvers plan too")
    parser.add_argument("--filed", type=Path, help="a checkout of the planner as filed, for the 'filed' rows")
    parser.add_argument("--safety", type=float, default=SAFETY_S, help="safety stop of every call, seconds")
    parser.add_argument(
        "--first-seed", type=int, default=SEED_BASE, help=f"scenario n of a case: this seed + n (default {SEED_BASE})"
    )
    parser.add_argument("--out", type=Path, help="append the rows here as JSON lines (the rows so far are kept)")
    parser.add_argument("--summarize", type=Path, help="only print the summary of a rows file")
    args = parser.parse_args(argv)
    if args.summarize is not None:
        print("\n".join(summary([json.loads(line) for line in args.summarize.read_text().splitlines() if line])))
        return
    done: list[dict] = []
    with open(args.out, "a") if args.out else contextlib.nullcontext() as out:
        for row in rows(args.cases, args.seeds, args.compare, args.filed, args.safety, args.first_seed):
            done.append(row)
            line = json.dumps(row)
            print(line, flush=True)
            if out is not None:
                out.write(line + "\n")
                out.flush()
    print("\n".join(summary(done)))


if __name__ == "__main__":
    main()
