"""The public planner: :func:`plan` solves the paper's MILP on SCIP, optimal for the task cost.

The task cost is the paper's Eq. 1 counted over the whole task: the travel, plus ``W1``
for every phase an object waits before it is delivered (``docs/formulation.md``, "The task
cost"); the env's return is minus it, and a plan's ``objective`` is it. :func:`plan`
searches the phase counts from a proven lower bound (the paper's iterative deepening)
and then up to a proven bound on the phases of any cheaper plan
(:mod:`expert.planning.deepening`).

Every choice is one :class:`~expert.planning.options.PlannerOptions`; every pass is
budgeted by counted work (SCIP nodes), so the same scenario and options give the same
plan at any load. ``time_limit`` is only a safety stop: a plan it stopped says so
(``stats["clock_stopped"]``, ``stats["optimality"]``).

Units are metres and seconds.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from expert.milp.deadline import Deadline, TimeUp
from expert.planning.deepening import Deepening
from expert.planning.options import PlannerOptions
from expert.planning.run import Run, optimality
from expert.planning.solving import solver_name
from expert.plans import Plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.scenario import Scenario

DEFAULT_RESOLUTION = 0.05  # metres: the env's default lattice
DEFAULT_TIME_LIMIT = 10.0  # seconds: the safety stop of a call that names none

__all__ = ["DEFAULT_RESOLUTION", "PlannerOptions", "optimality", "plan", "solver_name"]


def plan(
    scenario: Scenario,
    *,
    time_limit: float = DEFAULT_TIME_LIMIT,
    max_phases: int | None = None,
    lattice: Lattice | None = None,
    holding: str | None = None,
    extra_phases: int | None = None,
    export_models: str | os.PathLike | None = None,
    guide: Plan | None = None,
    options: PlannerOptions | None = None,
    **option_fields: Any,
) -> Plan:
    """Plan ``scenario``: the plan of least task cost; never raises for "no plan" (see ``Plan.status``).

    Args:
        scenario: the problem; its robot starts at ``robot.start`` with ``robot.heading``.
        time_limit: seconds of wall clock for the whole call (preprocessing, bounds, building
            and every solve): a safety stop only. The search itself is budgeted by counted
            work (``options.node_limit``, the first plans' budgets), so the answer is the same
            at any load unless this stop comes first, which the answer then says
            (``stats["clock_stopped"]`` True, ``stats["stopped_by"] == "clock"``).
        max_phases: the largest number of phases (the start included) to consider.
        lattice: the env's action lattice; default ``Lattice.over(scenario.area, 0.05)``.
        holding: id of an object already in the hand at the start.
        extra_phases: None (default): optimal over every phase count (each count that may
            hold a cheaper plan is solved, cut off at the best plan's cost; the others are
            proven to hold none); ``0``: the paper's rule, optimal among the plans with the
            fewest phases that admit one; ``k > 0``: among the plans of at most ``N + k``
            phases (``N``: the fewest).
        export_models: an existing folder: every MILP solved is written there as MPS with a
            JSON of its variables' meanings and its optimum (:mod:`expert.milp.export`).
        guide: a plan for this scenario from elsewhere (a learned policy's rollout, an earlier
            answer): SCIP's warm start in every model whose phases it fits (checked feasible
            first) and, with ``guide_branching=True``, a branching hint. Only the search changes:
            the answer and its proof are the same with any guide or none.
        options: every choice of the planner (:class:`~expert.planning.options.PlannerOptions`);
            ``option_fields`` change single fields of it (``plan(s, node_limit=20_000)``).

    Returns:
        a :class:`~expert.plans.Plan` with ``status`` ``optimal`` (proven, in the sense of
        ``stats["optimality"]``), ``feasible`` (a plan, not proven: a budget or the safety
        stop came first; ``stats["gap"]`` is the proven relative gap when a bound covers it),
        ``infeasible`` (``stats["reason"]`` says why when known) or ``time_limit`` (no plan
        before a stop). Its ``objective`` is the task cost.

    Raises:
        TypeError: an unknown option. ValueError: an option out of range.
        KeyboardInterrupt: on Ctrl-C, also when SCIP caught the signal during a solve.
    """
    if extra_phases is not None and (not isinstance(extra_phases, int) or extra_phases < 0):
        raise ValueError(f"extra_phases must be None or a whole number >= 0, got {extra_phases!r}")
    options = (options or PlannerOptions()).with_fields(**option_fields)
    return run_plan(
        scenario,
        options,
        Deadline.after(time_limit),
        lattice=lattice or Lattice.over(scenario.area, DEFAULT_RESOLUTION),
        holding=holding,
        extra_phases=extra_phases,
        max_phases=max_phases,
        export_models=export_models,
        guide=guide,
    )


def run_plan(
    scenario: Scenario,
    options: PlannerOptions,
    deadline: Deadline,
    *,
    lattice: Lattice,
    holding: str | None = None,
    extra_phases: int | None = None,
    max_phases: int | None = None,
    export_models: str | os.PathLike | None = None,
    guide: Plan | None = None,
) -> Plan:
    """:func:`plan` with its options checked and its safety stop set (the sub-plans of a call share it)."""
    run = Run(
        scenario,
        options,
        deadline,
        extra_phases=extra_phases,
        export_dir=None if export_models is None else Path(export_models),
    )
    run.stats["solver"] = solver_name()
    deepening = Deepening(run, lattice, SubPlanner(options, deadline, lattice), holding, max_phases, guide)
    return deepening.search()


class SubPlanner:
    """The planning call of a first plan's sub-plans: fewest phases, within ``options.sub_plan_nodes`` nodes.

    ``optimal=False`` stops at SCIP's first solution (fast presolving and heuristics). A
    sub-plan makes no first plans of its own. It shares the caller's safety stop, and raises
    :class:`~expert.milp.deadline.TimeUp` when that stop cut it short.
    """

    def __init__(self, options: PlannerOptions, deadline: Deadline, lattice: Lattice) -> None:
        budget = options.sub_plan_nodes
        self.optimal = options.with_fields(node_limit=budget, decoupled_from=10**6, nearest_first_plan=False)
        first_solution = {**options.params, "limits/solutions": 1}
        self.first = self.optimal.with_fields(presolving="fast", heuristics="fast", params=first_solution)
        self.deadline, self.lattice = deadline, lattice

    def __call__(
        self, scenario: Scenario, holding: str | None = None, lower_bound: bool = True, optimal: bool = False
    ) -> Plan:
        options = (self.optimal if optimal else self.first).with_fields(lower_bound=lower_bound)
        result = run_plan(scenario, options, self.deadline, lattice=self.lattice, holding=holding, extra_phases=0)
        if result.stats.get("clock_stopped"):
            raise TimeUp
        return result
