"""The public planner: :func:`plan` solves the paper's MILP on SCIP by iterative deepening.

``plan(scenario)`` preprocesses the scenario on the action lattice once
(:func:`expert.milp.problem.prepare`), then builds and solves the MILP with ``N``
phases for ``N`` = a proven lower bound (:mod:`expert.milp.bounds`), ``N + 1``, ...
until a plan is found, ``max_phases`` is passed, or time runs out (the paper's V-A:
"starting with N_pha = 3 and increasing this value by 1"). The first ``N`` with a plan
is the answer: ``optimal`` when SCIP proved it optimal for that ``N``.

Units are metres and seconds.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from typing import Any

import pyscipopt

from expert.milp.bounds import (
    Connectivity,
    PairCosts,
    action_windows,
    counting_bound,
    min_objective,
    min_travel,
    skeleton,
)
from expert.milp.build import SolverSettings, build
from expert.milp.collision import Infeasible
from expert.milp.decode import phases_of, plan_objective, read_steps
from expert.milp.problem import Problem, prepare
from expert.milp.reach import unreachable_reason
from expert.plans import Plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.scenario import Scenario

DEFAULT_RESOLUTION = 0.05  # metres: the env's default lattice
EXTRA_PHASES = 8  # phases tried beyond the lower bound when max_phases is not given
RESERVE_S = 0.01  # seconds kept back from each solve for decoding and bookkeeping
_PLANNER_OPTIONS = {"integral", "lower_bound"}


def plan(
    scenario: Scenario,
    *,
    time_limit: float = 10.0,
    max_phases: int | None = None,
    lattice: Lattice | None = None,
    holding: str | None = None,
    **solver_options: Any,
) -> Plan:
    """Plan ``scenario`` (optimal for the fewest phases that admit a plan); never raises for "no plan".

    Args:
        scenario: the problem; its robot starts at ``robot.start`` with ``robot.heading``.
        time_limit: wall-clock seconds for the whole call, model building included.
        max_phases: the largest number of phases (the start included) to try;
            default: the lower bound plus ``EXTRA_PHASES``.
        lattice: the env's action lattice; default ``Lattice.over(scenario.area, 0.05)``.
        holding: id of an object already in the hand at the start.
        **solver_options: ``integral`` (bool, default True: integer lattice bases),
            ``lower_bound`` (bool, default True: start at the proven lower bound, not 3),
            ``separating`` / ``presolving`` / ``heuristics`` (``default``, ``off``,
            ``fast``, ``aggressive``), ``params`` (a dict of SCIP parameters), ``seed``.

    Returns:
        a :class:`~expert.plans.Plan` with ``status`` ``optimal``, ``feasible``,
        ``infeasible`` or ``time_limit`` and ``stats`` (solver, phases tried, seconds).

    Raises:
        KeyboardInterrupt: on Ctrl-C, also when SCIP caught the signal during a solve
            (it does so itself and just stops); an interrupted call returns no plan.
    """
    started = time.perf_counter()
    deadline = started + time_limit
    unknown = set(solver_options) - _PLANNER_OPTIONS - set(SolverSettings.__dataclass_fields__)
    if unknown:
        raise TypeError(f"plan() got unknown solver option(s): {', '.join(sorted(unknown))}")
    integral = bool(solver_options.pop("integral", True))
    use_bound = bool(solver_options.pop("lower_bound", True))
    settings = SolverSettings(**solver_options)
    lattice = lattice or Lattice.over(scenario.area, DEFAULT_RESOLUTION)

    problem = prepare(scenario, lattice, holding=holding, integral=integral)
    stats: dict[str, Any] = {
        "solver": solver_name(),
        "phases_tried": [],
        "prepare_s": time.perf_counter() - started,
        "build_s": 0.0,
        "solve_s": 0.0,
        "options": len(problem.options),
    }

    def finish(status: str, phases=(), objective=None) -> Plan:
        stats["total_s"] = time.perf_counter() - started
        return Plan(scenario.name, status, objective, tuple(phases), stats)

    if problem.infeasible is not None:
        stats["reason"] = problem.infeasible
        return finish("infeasible")
    if not problem.deliver:
        phases = phases_of(problem, [])
        stats["phases_tried"].append(1)
        return finish("optimal", phases, plan_objective(scenario, phases))
    free = Connectivity(problem)
    pairs = PairCosts(problem, free) if use_bound else None
    if use_bound:
        relaxation = skeleton(problem, free)
        problem = dataclasses.replace(problem, earliest=relaxation.earliest, min_travel=min_travel(problem))
        first = max(3, counting_bound(problem), relaxation.phases)
    else:
        first = max(3, counting_bound(problem))
    stats["lower_bound"] = first
    last = max_phases if max_phases is not None else first + EXTRA_PHASES
    stats["lower_bound_s"] = time.perf_counter() - started - stats["prepare_s"]
    for n_phases in range(first, last + 1):
        if time.perf_counter() >= deadline - RESERVE_S:
            return finish("time_limit")
        stats["phases_tried"].append(n_phases)
        outcome = _solve(problem, n_phases, settings, deadline, stats, pairs)
        if outcome == "infeasible":
            if n_phases == first:
                t_reach = time.perf_counter()
                reason = unreachable_reason(problem)
                stats["reach_s"] = time.perf_counter() - t_reach
                if reason is not None:
                    stats["reason"] = reason
                    return finish("infeasible")
            continue
        if outcome == "time_limit":
            return finish("time_limit")
        status, phases = outcome
        return finish(status, phases, plan_objective(scenario, phases))
    if not stats["phases_tried"]:
        stats["reason"] = f"max_phases={max_phases} is below the lower bound {first}"
    return finish("infeasible")


@functools.cache
def solver_name() -> str:
    """``"SCIP <major>.<minor>.<tech>"`` of the SCIP inside pyscipopt."""
    model = pyscipopt.Model()
    return f"SCIP {model.getMajorVersion()}.{model.getMinorVersion()}.{model.getTechVersion()}"


def _solve(
    problem: Problem, n_phases: int, settings: SolverSettings, deadline: float, stats: dict, pairs: PairCosts | None
):
    """Build and solve with ``n_phases``: ``"infeasible"``, ``"time_limit"`` or ``(status, phases)``."""
    record: dict[str, Any] = {"phases": n_phases}
    stats.setdefault("solves", []).append(record)
    bound = windows = None
    if pairs is not None:
        t_bound = time.perf_counter()
        bound = min_objective(problem, n_phases, pairs)
        windows = action_windows(problem, n_phases, pairs)
        record["objective_bound"] = bound
        stats["lower_bound_s"] += time.perf_counter() - t_bound
    t0 = time.perf_counter()
    try:
        milp = build(problem, n_phases, settings, bound, windows)
    except Infeasible:
        record.update(status="infeasible", build_s=time.perf_counter() - t0, solve_s=0.0, nodes=0)
        stats["build_s"] += record["build_s"]
        return "infeasible"
    t1 = time.perf_counter()
    record["build_s"] = t1 - t0
    stats["build_s"] += t1 - t0
    remaining = deadline - t1 - RESERVE_S
    if remaining <= 0:
        record.update(status="time_limit", solve_s=0.0, nodes=0)
        return "time_limit"
    model = milp.model
    model.setParam("limits/time", remaining)
    model.optimize()
    status = model.getStatus()
    if status == "userinterrupt":  # SCIP caught SIGINT itself (misc/catchctrlc): pass the Ctrl-C on
        raise KeyboardInterrupt("planning interrupted during the SCIP solve")
    record.update(status=status, solve_s=time.perf_counter() - t1, nodes=model.getNNodes())
    stats["solve_s"] += record["solve_s"]
    if status in ("infeasible", "inforunbd"):
        return "infeasible"
    if model.getNSols() == 0:
        return "time_limit"
    steps = read_steps(problem, milp, model.getBestSol())
    stats["milp_objective"] = model.getObjVal()
    stats["gap"] = model.getGap()
    return ("optimal" if status == "optimal" else "feasible"), phases_of(problem, steps)
