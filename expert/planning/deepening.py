"""The planner's search over phase counts, from the proven fewest to the phase bound.

:func:`search` preprocesses the scenario on the action lattice once
(:func:`expert.milp.problem.prepare`), proves a lower bound ``N0`` on the phases
(:mod:`expert.milp.bounds`), then solves the MILP with ``N0``, ``N0 + 1``, ... phases until
one admits a plan (the paper's iterative deepening, Section V-A). That plan is optimal for
the task cost among the plans with the fewest phases. A plan with more phases can still
cost less (shorter travel for later deliveries), so :meth:`Deepening.phase_cap` bounds the
phases of any cheaper plan (each phase before the last delivery costs at least ``W1``) and,
when that bound exceeds the phases found, one model with that many phases (shorter plans
are in it, followed by idle phases that cost nothing) is solved, warm-started from the
best plan: its optimum is the task cost's optimum over every phase count.

Units are metres (costs) and seconds (timings).
"""

from __future__ import annotations

import dataclasses
import time

from expert.decoupled import steps_of
from expert.guide import guide_steps
from expert.milp.bounds import Connectivity, PairCosts, counting_bound, min_travel, skeleton
from expert.milp.conditional import least_by_last_phase
from expert.milp.deadline import TimeUp
from expert.milp.decode import SolvedPhase, phases_of
from expert.milp.problem import Problem, prepare
from expert.milp.reach import unreachable_reason
from expert.planning.first_plans import FirstPlans, SubPlanner
from expert.planning.run import Run
from expert.planning.solving import Solver
from expert.plans import Plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.kinematics import WAIT_COST

EXTRA_PHASES = 8  # phase counts tried beyond the lower bound for the fewest, when max_phases is not given


@dataclasses.dataclass
class Deepening:
    """One call's search over phase counts (see the module docstring); it records into ``run``."""

    run: Run
    lattice: Lattice
    sub_planner: SubPlanner
    holding: str | None = None
    max_phases: int | None = None
    guide: Plan | None = None

    def __post_init__(self) -> None:
        self.solver = Solver(self.run)
        self.first_plans = FirstPlans(self.run, self.solver, self.lattice, self.sub_planner)

    def search(self) -> Plan:
        """The answer (see the module docstring); a stop (nodes, clock) answers with the best plan so far."""
        try:
            return self._search()
        except TimeUp:
            self.run.stopped("clock")
            return self.run.out_of_budget()

    def _search(self) -> Plan:
        run, stats = self.run, self.run.stats
        options = run.options
        problem = prepare(
            run.scenario,
            self.lattice,
            holding=self.holding,
            integral=options.integral,
            deadline=run.deadline,
            corner_detail=options.corner_detail,
            first_move_tangents=options.first_move_tangents,
            corner_poses=options.corner_poses,
            pose_tangents=options.pose_tangents,
        )
        stats["prepare_s"] = time.perf_counter() - run.started
        stats["options"] = len(problem.options)
        run.deadline.check()
        if problem.infeasible is not None:
            stats["reason"] = problem.infeasible
            return run.finish("infeasible")
        if self.guide is not None:
            run.guides = guide_steps(problem, self.guide.phases)
            stats["guide"] = "mapped" if run.guides else "not mappable (ignored)"
            stats["guide_phases"] = [len(steps) + 1 for steps in run.guides]
        if not problem.deliver:
            stats["phases_tried"].append(1)
            return run.finish("optimal", phases_of(problem, []))
        reason = self.unreachable(problem)  # before any MILP: a few milliseconds at any size
        if reason is not None:
            stats["reason"] = reason
            return run.finish("infeasible")
        wanted = self.first_plans.wanted(problem)
        if wanted and options.nearest_first_plan:
            self.first_plans.nearest(problem)
        problem, pairs, first, fewer_infeasible = self.lower_bound(problem)
        if wanted:
            self.first_plans.choose_order(problem, pairs, first, fewer_infeasible and options.fewest_cuts)
        last = self.max_phases if self.max_phases is not None else first + EXTRA_PHASES
        return self.deepen(problem, pairs, first, last, fewer_infeasible)

    def unreachable(self, problem: Problem) -> str | None:
        """:func:`expert.milp.reach.unreachable_reason`, timed in ``stats["reach_s"]``."""
        t_reach = time.perf_counter()
        reason = unreachable_reason(problem, self.run.deadline)
        self.run.stats["reach_s"] = time.perf_counter() - t_reach
        return reason

    def lower_bound(self, problem: Problem) -> tuple[Problem, PairCosts | None, int, bool]:
        """The phases to start deepening at (at least 3); with ``options.lower_bound`` the relaxation's bounds too.

        Returns the problem (with the relaxation's ``earliest`` and ``min_travel``), the pair
        costs (None without the bound), the first phase count and whether one phase fewer is
        proven to admit no plan.
        """
        run = self.run
        t_bound = time.perf_counter()
        pairs = None
        proven = counting_bound(problem)
        if run.options.lower_bound:
            pairs = PairCosts(problem, Connectivity(problem, run.deadline), run.deadline)
            relaxation = skeleton(problem, pairs, run.deadline)
            problem = dataclasses.replace(
                problem, earliest=relaxation.earliest, min_travel=min_travel(problem, pairs, run.deadline)
            )
            proven = max(proven, relaxation.phases)
        first = max(3, proven)
        run.stats["lower_bound"] = first
        run.stats["lower_bound_s"] += time.perf_counter() - t_bound
        return problem, pairs, first, first == proven  # N - 1 phases proven to admit no plan

    def deepen(self, problem: Problem, pairs: PairCosts | None, first: int, last: int, fewer_infeasible: bool) -> Plan:
        """Solve with ``first``, ``first + 1``, ... ``last`` phases until one admits a plan; then the phase bound."""
        run, stats = self.run, self.run.stats
        fewest_cuts = run.options.fewest_cuts
        for n_phases in range(first, last + 1):
            stats["phases_tried"].append(n_phases)
            hook = self.first_plans.hook(pairs, fewer_infeasible and fewest_cuts)
            fewest = fewer_infeasible and fewest_cuts
            outcome = self.solver.solve(problem, n_phases, pairs, fewest=fewest, first_model=hook)
            if outcome == "infeasible":
                fewer_infeasible = True
                continue
            if outcome == "no_plan":
                return run.out_of_budget()
            status, steps = outcome
            self.found(problem, pairs, n_phases, status, phases_of(problem, steps))
            return run.finish(*run.best)
        if not stats["phases_tried"]:
            stats["reason"] = f"max_phases={self.max_phases} is below the lower bound {first}"
        else:
            stats["reason"] = f"no plan with {first} to {last} phases (every model was infeasible)"
        return run.finish("infeasible")

    def found(self, problem: Problem, pairs: PairCosts | None, n_phases: int, status: str, found) -> None:
        """Keep the plan the model of ``n_phases`` (the fewest) gave, or a cheaper first plan; then the phase bound.

        With ``extra_phases=0`` (the paper's rule) the answer has the fewest phases: a first
        plan is kept instead only when it has no more phases and costs less (then ``feasible``).
        """
        run = self.run
        first = run.best[1] if run.best is not None else None
        if run.extra_phases == 0:
            fits = first is not None and len(first) <= n_phases
            keep_first = status != "optimal" and fits and run.better(first, found)
            run.best = ("feasible", first) if keep_first else (status, found)
            return
        run.best = (status, found) if first is None or run.better(found, first) else ("feasible", first)
        if status == "optimal":
            self.longer(problem, pairs, n_phases)

    def longer(self, problem: Problem, pairs: PairCosts | None, n_phases: int) -> None:
        """The model of more phases that holds every plan cheaper than the best (:meth:`phase_cap`), solved.

        Its shorter plans end in idle phases, which are dropped from the answer. The best
        plan stays ``optimal`` when no cheaper plan has more phases, or when the longer model
        is solved to its optimum; ``feasible`` when a stop came first.
        """
        run, stats = self.run, self.run.stats
        best = run.best[1]
        stats["fewest_phases"] = n_phases
        stats["fewest_phases_objective"] = run.cost(best)
        if run.extra_phases is not None:
            cap = n_phases + run.extra_phases
        else:
            cap = self.phase_cap(problem, pairs, n_phases, run.cost(best))
        if self.max_phases is not None:
            cap = min(cap, self.max_phases)
        stats["phase_cap"] = cap
        if cap <= n_phases:  # no plan of more phases is cheaper than the best, the fewest phases' optimum or better
            run.best = ("optimal", best)
            return
        stats["phases_tried"].append(cap)
        warm = steps_of(problem, best) if len(best) <= cap else None
        outcome = self.solver.solve(problem, cap, pairs, warm=warm)
        if isinstance(outcome, tuple):
            longer_status, steps = outcome
            found = phases_of(problem, _without_trailing_idle(steps))
            if run.better(found, best):
                best = found
            run.best = (longer_status, best)
        else:  # a stop before any plan of the longer model, or none cheaper in it
            run.best = ("optimal" if outcome == "infeasible" else "feasible", best)

    def phase_cap(self, problem: Problem, pairs: PairCosts | None, n_phases: int, cost: float) -> int:
        """The most phases a plan costing less than ``cost`` can have (at least ``n_phases``).

        A plan's phases end with its last delivery (anything after it only adds cost), so a
        plan of ``N`` phases leaves one object waiting ``N - 2`` phases, and the others at
        least ``1, 3, 5, ...`` (a pick and a place each): with the relaxation's travel bound
        that grows with ``N`` (:func:`_simple_bound`), and past the first ``N`` where it reaches
        ``cost`` no plan helps. Below it, the skeleton's bound on the task cost of the plans whose last
        place is at phase ``N - 1`` (:func:`expert.milp.conditional.least_by_last_phase`, one forward
        search for every ``N``) rules out more counts.
        """
        beyond = n_phases + 1
        while _simple_bound(problem, beyond) < cost - 1e-9:  # every plan of `beyond` or more phases costs more
            beyond += 1
        if beyond == n_phases + 1:
            return n_phases
        if pairs is None:
            return beyond - 1
        by_last = least_by_last_phase(problem, beyond - 1, pairs, self.run.deadline)  # [t]: last place at t
        cheaper = [n for n in range(n_phases + 1, beyond) if by_last[n - 1] < cost - 1e-9]
        return max(cheaper, default=n_phases)


def _simple_bound(problem: Problem, n_phases: int) -> float:
    """A lower bound on the task cost of a plan of exactly ``n_phases`` phases (its last one a place): see
    :meth:`Deepening.phase_cap`; it grows by ``W1`` per phase."""
    todo = len(problem.deliver)
    held = 1 if problem.holding is not None else 0
    others = max(todo - 1, 0) ** 2 - (held if todo > 1 else 0)  # 1 + 3 + ... + (2m - 1), one phase less if held
    return problem.min_travel + WAIT_COST * (n_phases - 2 + others)


def _without_trailing_idle(steps: list[SolvedPhase]) -> list[SolvedPhase]:
    """``steps`` without the idle phases at the end (no action, no move): the padding of a shorter plan."""
    out = list(steps)
    while len(out) > 1 and out[-1].option is None and out[-1].cell == out[-2].cell:
        out.pop()
    return out
