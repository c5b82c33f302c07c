"""What one call of :func:`expert.planner.plan` shares between its jobs: the best plan so far and the stats.

The jobs (:mod:`.first_plans`, :mod:`.solving`, :mod:`.deepening`) read the options and
the safety stop from a :class:`Run` and record into it; :meth:`Run.finish` turns it into
the :class:`~expert.plans.Plan` the call returns. Plans are compared by the task cost
(:func:`expert.plans.task_cost`), ties by fewer phases.

Units are metres (costs) and seconds (timings, the safety stop).
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path
from typing import Any

from expert.milp.deadline import Deadline
from expert.milp.decode import SolvedPhase
from expert.planning.options import PlannerOptions
from expert.plans import Phase, Plan, task_cost
from fetchcarry_env.scenario import Scenario

TIMINGS = ("prepare_s", "lower_bound_s", "build_s", "solve_s")
"""The seconds every run reports (with ``total_s``); they are the only stats that vary between identical calls."""


@dataclasses.dataclass
class Run:
    """One call of :func:`expert.planner.plan`: its options, safety stop, stats and best plan so far."""

    scenario: Scenario
    options: PlannerOptions
    deadline: Deadline  # the safety stop: a plan it stopped says so (stats["clock_stopped"])
    extra_phases: int | None = None  # None: the task cost's optimum over every phase count
    export_dir: Path | None = None  # where every solved MILP is written (expert.milp.export)
    started: float = dataclasses.field(default_factory=time.perf_counter)
    stats: dict[str, Any] = dataclasses.field(default_factory=dict)
    best: tuple[str, tuple[Phase, ...]] | None = None  # (status, phases) of the best plan found so far
    warm: list[SolvedPhase] | None = None  # the best first plan as MILP steps, for warm starts
    guides: list[list[SolvedPhase]] = dataclasses.field(default_factory=list)  # plan()'s guide as MILP steps

    def __post_init__(self) -> None:
        self.stats.update(phases_tried=[], clock_stopped=False, stopped_by=None, **dict.fromkeys(TIMINGS, 0.0))

    def cost(self, phases: tuple[Phase, ...]) -> float:
        """The task cost of ``phases`` (:func:`expert.plans.task_cost`)."""
        return task_cost(self.scenario, phases)

    def better(self, phases: tuple[Phase, ...], than: tuple[Phase, ...] | None) -> bool:
        """A lower task cost than ``than`` (None: anything is), or as low and fewer phases."""
        if than is None:
            return True
        mine, theirs = self.cost(phases), self.cost(than)
        if abs(mine - theirs) > 1e-9:
            return mine < theirs
        return len(phases) < len(than)

    def keep_first_plan(self, phases: tuple[Phase, ...], how: str) -> bool:
        """Keep ``phases`` (a plan not proven optimal) as the answer so far when it is better; True if kept."""
        if self.best is not None and not self.better(phases, self.best[1]):
            return False
        self.best = ("feasible", phases)
        self.stats.update(decoupled=how, decoupled_phases=len(phases), decoupled_objective=self.cost(phases))
        return True

    def stopped(self, by: str) -> None:
        """Record what stopped a search short of a proof: ``"node_limit"`` (counted) or ``"clock"`` (safety stop)."""
        if self.stats["stopped_by"] != "clock":
            self.stats["stopped_by"] = by
        self.stats["clock_stopped"] = self.stats["clock_stopped"] or by == "clock"

    def finish(self, status: str, phases: tuple[Phase, ...] = ()) -> Plan:
        """The answer: ``phases`` with ``status``, the stats and what was proven (``stats["optimality"]``)."""
        self.stats["total_s"] = time.perf_counter() - self.started
        self.stats["optimality"] = optimality(self.extra_phases, status, self.stats)
        objective = self.cost(phases) if phases else None
        return Plan(self.scenario.name, status, objective, tuple(phases), self.stats)

    def out_of_budget(self) -> Plan:
        """The answer when a stop (nodes or the clock) came before any solve gave a plan: the best so far."""
        if self.best is not None:
            self.stats["gap"] = self.stats["dual_bound"] = None
            return self.finish("feasible", self.best[1])
        return self.finish("time_limit")


def same_plan(first: Plan, second: Plan) -> bool:
    """Whether two answers are the same, bit for bit, apart from their timings."""
    if (first.status, first.phases) != (second.status, second.phases):
        return False
    if first.objective != second.objective and not (first.objective is None and second.objective is None):
        return False
    return _without_timings(first.stats) == _without_timings(second.stats)


def _without_timings(stats: Any) -> Any:
    """``stats`` without the keys that measure seconds (``*_s``), at every depth."""
    if isinstance(stats, dict):
        return {k: _without_timings(v) for k, v in stats.items() if not (k.endswith("_s") or k == "total_s")}
    if isinstance(stats, list | tuple):
        return [_without_timings(v) for v in stats]
    if isinstance(stats, float) and math.isnan(stats):
        return "nan"
    return stats


def optimality(extra_phases: int | None, status: str = "optimal", stats: dict[str, Any] | None = None) -> str:
    """What a plan of ``status`` is proven to be (the sentence in ``stats["optimality"]``).

    Only what holds: the claim of optimality for ``optimal``; for ``feasible`` that it is not
    proven and what stopped the search (the node budget, or the clock's safety stop); for a
    status without a plan, that there is no claim.
    """
    if extra_phases is None:
        claim = (
            "optimal for the task cost (Eq. 1 counted over the whole task: travel plus W1 for each phase an object "
            "waits) among all plans, whatever their number of phases (no plan of more phases can be cheaper: the "
            "phase bound)"
        )
    elif extra_phases == 0:
        claim = (
            "optimal for the task cost among the plans with the fewest phases that admit one (the paper's deepening)"
        )
    else:
        claim = f"optimal for the task cost among all plans of at most N + {extra_phases} phases (N: the fewest)"
    if status == "optimal":
        return claim
    if status == "feasible":
        by = (stats or {}).get("stopped_by")
        why = {
            "clock": "the safety stop (the wall clock's time limit) came first: this plan may differ from run to run",
            "node_limit": "the node budget ran out first",
        }.get(by, "the search stopped first")
        return f"not proven optimal: {why}; the planner was looking for the plan {claim}"
    return f"no plan (status {status}), so no claim of optimality"
