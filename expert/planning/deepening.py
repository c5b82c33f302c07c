"""The planner's search over phase counts, from the proven fewest to the phase bound.

:func:`search` preprocesses the scenario on the action lattice once
(:func:`expert.milp.problem.prepare`), proves a lower bound ``N0`` on the phases
(:mod:`expert.milp.bounds`), then solves the MILP with ``N0``, ``N0 + 1``, ... phases until
one admits a plan (the paper's iterative deepening, Section V-A). That plan is optimal for
the task cost among the plans with the fewest phases. A plan with more phases can still
cost less (shorter travel for later deliveries), so :meth:`Deepening.cheaper_counts` lists
the phase counts that may hold a cheaper plan (each phase before the last delivery costs
at least ``W1``, and the skeleton bounds the cost of a plan by where its last place is),
and :meth:`Deepening.longer` solves each as a model of exactly that many phases, cut off at
the best plan's cost: the best found is the task cost's optimum over every phase count.

Units are metres (costs) and seconds (timings).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from expert.guide import guide_steps
from expert.milp.bounds import PairCosts, counting_bound, min_travel, skeleton
from expert.milp.conditional import least_by_last_phase
from expert.milp.deadline import TimeUp
from expert.milp.decode import phases_of
from expert.milp.problem import Problem, prepare
from expert.milp.reach import unreachable_reason
from expert.milp.skeleton_graph import GraphTooLarge
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
        self.by_last: np.ndarray | None = None  # least task cost of the plans whose last place is at phase t
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
            pairs = PairCosts(problem, run.deadline, run.options.skeleton_edges)
            try:
                relaxation = skeleton(problem, pairs, run.deadline)
            except GraphTooLarge as error:  # the counting bound only, as with lower_bound=False
                run.stats["skeleton"] = f"not built: {error}"
                pairs = None
            else:
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
        capped = run.extra_phases is None  # the task cost over every phase count: nothing dearer than the best
        for n_phases in range(first, last + 1):
            stats["phases_tried"].append(n_phases)
            hook = self.first_plans.hook(pairs, fewer_infeasible and fewest_cuts)
            fewest = fewer_infeasible and fewest_cuts
            outcome = self.solver.solve(problem, n_phases, pairs, fewest=fewest, first_model=hook, cap_at_best=capped)
            if outcome == "infeasible":
                fewer_infeasible = True  # no plan, or (capped) none costing no more than the best: the same cuts hold
                if capped and run.best is not None and not self.may_match(problem, pairs, n_phases):
                    return run.finish("optimal", run.best[1])
                continue
            if outcome == "no_plan":
                return run.out_of_budget()
            status, steps = outcome
            self.found(problem, pairs, n_phases, status, phases_of(problem, steps))
            return run.finish(*run.best)
        if run.best is not None:  # a first plan, and counts left open up to ``last``
            return run.finish("feasible", run.best[1])
        if not stats["phases_tried"]:
            stats["reason"] = f"max_phases={self.max_phases} is below the lower bound {first}"
        else:
            stats["reason"] = f"no plan with {first} to {last} phases (every model was infeasible)"
        return run.finish("infeasible")

    def may_match(self, problem: Problem, pairs: PairCosts | None, n_phases: int) -> bool:
        """Whether a count above ``n_phases`` (up to ``max_phases``, when given) may hold a plan costing no more
        than the best so far (the bounds of :meth:`cheaper_counts`)."""
        cost = self.run.cost(self.run.best[1])
        return bool(self.cheaper_counts(problem, pairs, n_phases, cost + 2e-9, self.max_phases))

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
        """Look for a cheaper plan among the plans of more than ``n_phases`` phases, one phase count at a time.

        Each count ``N`` that may hold a plan cheaper than the best (:meth:`cheaper_counts`) is
        solved as a model of exactly ``N`` phases (the last a place, none idle: the fewest-phase
        cuts), asked only for plans cheaper than the best (an objective cutoff); every cheaper
        plan found lowers the cutoff and can rule out the counts left. The best plan stays
        ``optimal`` when every count was settled (solved, or proven to hold nothing cheaper),
        ``feasible`` when a stop left one open.
        """
        run, stats = self.run, self.run.stats
        best = run.best[1]
        stats["fewest_phases"] = n_phases
        stats["fewest_phases_objective"] = run.cost(best)
        cap = n_phases + run.extra_phases if run.extra_phases is not None else None
        if self.max_phases is not None:
            cap = self.max_phases if cap is None else min(cap, self.max_phases)
        counts = self.cheaper_counts(problem, pairs, n_phases, run.cost(best), cap)
        stats["phase_cap"] = max(counts, default=n_phases)
        settled = True
        while counts:
            count = counts[0]
            stats["phases_tried"].append(count)
            hook = self.first_plans.longer_hook(problem, pairs, count)
            outcome = self.solver.solve(problem, count, pairs, fewest=True, first_model=hook, cutoff=run.cost(best))
            if isinstance(outcome, tuple):
                status, steps = outcome
                found = phases_of(problem, steps)
                if run.better(found, best):
                    best = found
                settled = settled and status == "optimal"
            elif outcome == "no_plan":  # a stop before this count was settled
                settled = False
            if run.better(run.best[1], best):  # the count's ordered plan, when its solve was stopped before SCIP's
                best = run.best[1]
            counts = [n for n in self.cheaper_counts(problem, pairs, n_phases, run.cost(best), cap) if n > count]
        run.best = ("optimal" if settled else "feasible", best)

    def cheaper_counts(
        self, problem: Problem, pairs: PairCosts | None, n_phases: int, cost: float, cap: int | None
    ) -> list[int]:
        """The phase counts above ``n_phases`` (up to ``cap``, None: no cap) whose plans may cost less than ``cost``.

        A plan's phases end with its last delivery (anything after it only adds cost), so a
        plan of ``N`` phases leaves one object waiting ``N - 2`` phases, and the others at
        least ``1, 3, 5, ...`` (a pick and a place each): with the relaxation's travel bound
        that grows with ``N`` (:func:`_simple_bound`), and from the first ``N`` where it reaches
        ``cost`` on no plan is cheaper. Below it, the skeleton's bound on the task cost of the
        plans whose last place is at phase ``N - 1`` (:func:`expert.milp.conditional.least_by_last_phase`,
        one forward search for every ``N``, kept for the call) rules out more counts.
        """
        beyond = n_phases + 1
        while _simple_bound(problem, beyond) < cost - 1e-9 and (cap is None or beyond <= cap):
            beyond += 1
        counts = range(n_phases + 1, beyond)
        if pairs is None or not counts:
            return list(counts)
        if self.by_last is None or len(self.by_last) < beyond - 1:
            self.by_last = least_by_last_phase(problem, beyond - 1, pairs, self.run.deadline)  # [t]: last place at t
        return [n for n in counts if self.by_last[n - 1] < cost - 1e-9]


def _simple_bound(problem: Problem, n_phases: int) -> float:
    """A lower bound on the task cost of a plan of exactly ``n_phases`` phases (its last one a place): see
    :meth:`Deepening.cheaper_counts`; it grows by ``W1`` per phase."""
    todo = len(problem.deliver)
    held = 1 if problem.holding is not None else 0
    others = max(todo - 1, 0) ** 2 - (held if todo > 1 else 0)  # 1 + 3 + ... + (2m - 1), one phase less if held
    return problem.min_travel + WAIT_COST * (n_phases - 2 + others)
