"""Solving one model: build the MILP of ``N`` phases, add its bounds and warm starts, run SCIP within its budget.

:class:`Solver` keeps what the models of one call share (the conditional bounds per phase
count); :meth:`Solver.solve` answers ``"infeasible"``, ``"no_plan"`` (a stop came first)
or ``(status, steps)``. :func:`optimize` runs SCIP within a node budget (counted: the same
answer at any load) and the safety stop (the clock: recorded when it decides).

Units are seconds (timings) and SCIP nodes (budgets).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable
from typing import Any

import pyscipopt

from expert.milp.bounds import PairCosts, Windows, action_windows, min_objective
from expert.milp.build import build
from expert.milp.collision import Infeasible
from expert.milp.conditional import Conditional, add_conditional_cuts, conditional_bounds, fix_above
from expert.milp.deadline import Deadline, TimeUp
from expert.milp.decode import SolvedPhase, phases_of, read_steps
from expert.milp.export import export_model
from expert.milp.problem import Problem
from expert.milp.variables import Milp
from expert.milp.warm import add_branching_hint, add_warm_start
from expert.planning.run import Run

RESERVE_S = 0.01  # seconds of the safety stop kept back from each solve for decoding and bookkeeping
INFEASIBLE = ("infeasible", "inforunbd")
"""SCIP's statuses that prove a model has no solution (below its objective limit, when it has one)."""
CUTOFF_TOL = 1e-6  # metres of task cost: a plan must beat a cutoff by this much (ties are no improvement)

FirstModelHook = Callable[[Milp, Problem], bool]
"""Called on a model after its cuts, before its warm starts; True: the model is proven infeasible (no solve)."""


def optimize(model: pyscipopt.Model, deadline: Deadline, nodes: int | None = None) -> str:
    """SCIP's solve within ``nodes`` nodes (None: no limit) and the safety stop; its status.

    ``"nodelimit"`` is the counted budget (the same at any load); ``"timelimit"`` means the
    clock stopped it (the caller records it). Raises ``KeyboardInterrupt`` on Ctrl-C: SCIP
    catches SIGINT itself (``misc/catchctrlc``) and just stops (``userinterrupt``), so the
    Ctrl-C is passed on and an interrupted solve never gives a plan.
    """
    left = deadline.left() - RESERVE_S
    if left <= 0:
        raise TimeUp
    model.setParam("limits/time", left)
    model.setParam("limits/nodes", -1 if nodes is None else nodes)
    model.optimize()
    status = model.getStatus()
    if status == "userinterrupt":
        raise KeyboardInterrupt("planning interrupted during the SCIP solve")
    return status


class Solver:
    """Builds and solves the models of one call of :func:`expert.planner.plan` (see the module docstring)."""

    def __init__(self, run: Run) -> None:
        self.run = run
        self.conditionals: dict[tuple[int, bool], Conditional] = {}

    def conditional_bounds(self, problem: Problem, n_phases: int, pairs: PairCosts, fewest: bool) -> Conditional:
        """:func:`expert.milp.conditional.conditional_bounds`, once per phase count and ``fewest``."""
        key = (n_phases, fewest)
        if key not in self.conditionals:
            self.conditionals[key] = conditional_bounds(problem, n_phases, pairs, self.run.deadline, last_at_end=fewest)
        return self.conditionals[key]

    def solve(
        self,
        problem: Problem,
        n_phases: int,
        pairs: PairCosts | None,
        warm: list[SolvedPhase] | None = None,
        fewest: bool = False,
        first_model: FirstModelHook | None = None,
        cutoff: float | None = None,
        cap_at_best: bool = False,
    ) -> str | tuple[str, list[SolvedPhase]]:
        """Build and solve with ``n_phases``: ``"infeasible"``, ``"no_plan"`` or ``(status, steps)``.

        ``fewest``: the model holds only plans of exactly ``n_phases`` phases, none idle and the
        last a place (:mod:`expert.milp.fewest`'s cuts): every other plan of the model is a
        plan of fewer phases that costs no more. ``cutoff``: only plans of a task cost below it
        (SCIP's objective limit, and the options whose conditional bound reaches it fixed to
        0); ``"infeasible"`` then means none. ``cap_at_best`` (without ``cutoff``): once the warm
        starts are in, only plans costing no more than the best plan so far, whatever its
        phases (``"infeasible"`` then means none). ``first_model``: run on the model before its warm
        starts (the first plan in the relaxation's order, on the model built once). Recorded
        in ``stats["solves"]``.
        """
        run, stats = self.run, self.run.stats
        record: dict[str, Any] = {"phases": n_phases, "fewest_cuts": fewest}
        stats.setdefault("solves", []).append(record)
        bound, windows, cond = self.model_bounds(problem, n_phases, pairs, fewest, record)
        t0 = time.perf_counter()
        try:
            milp = build(problem, n_phases, run.options.settings, bound, windows, run.deadline, fewest=fewest)
        except Infeasible:
            record.update(status="infeasible", build_s=time.perf_counter() - t0, nodes=0)
            stats["build_s"] += record["build_s"]
            return "infeasible"
        record["build_s"] = time.perf_counter() - t0
        stats["build_s"] += record["build_s"]
        if cond is not None:
            record["conditional_fixed"] = add_conditional_cuts(milp, cond)
        if cutoff is not None:
            record["cutoff"] = cutoff
            milp.model.setObjlimit(cutoff - CUTOFF_TOL)
            if cond is not None:
                record["conditional_fixed"] += fix_above(milp, cond, cutoff, keep_ties=False)
        if first_model is not None and first_model(milp, problem):  # proven infeasible at the root
            record.update(status="infeasible", nodes=stats["ordered"]["root_nodes"], root_proof=True)
            return "infeasible"
        self.add_warm_starts(milp, problem, n_phases, cond, [warm] if warm is not None else None, record)
        if cap_at_best and cutoff is None and run.best is not None:
            record["cap"] = cap = run.cost(run.best[1])
            milp.model.setObjlimit(cap + CUTOFF_TOL)
            if cond is not None:
                record["conditional_fixed"] += fix_above(milp, cond, cap)
        if run.guides and run.options.guide_branching:
            fitting = [steps for steps in run.guides if len(steps) <= n_phases - 1]
            record["guide_priorities"] = add_branching_hint(milp, (fitting or run.guides)[-1])
        t1 = time.perf_counter()
        status = optimize(milp.model, run.deadline, run.options.node_limit)
        record.update(status=status, solve_s=time.perf_counter() - t1, nodes=milp.model.getNNodes())
        stats["solve_s"] += record["solve_s"]
        if run.export_dir is not None:
            mps, _ = export_model(milp, run.export_dir, {**record, "solver": solver_name()})
            record["exported"] = mps.name
        if status in INFEASIBLE:
            return "infeasible"
        if status != "optimal":
            run.stopped("clock" if status == "timelimit" else "node_limit")
        if milp.model.getNSols() == 0:
            return "no_plan"
        return ("optimal" if status == "optimal" else "feasible"), self.read_solution(problem, milp)

    def model_bounds(
        self, problem: Problem, n_phases: int, pairs: PairCosts | None, fewest: bool, record: dict[str, Any]
    ) -> tuple[float | None, Windows | None, Conditional | None]:
        """Eq. 1's lower bound, the action windows and the conditional bounds of the model (None without ``pairs``)."""
        if pairs is None:
            return None, None, None
        run = self.run
        cond = None
        t_bound = time.perf_counter()
        if run.options.conditional:  # its least value is min_objective's
            cond = self.conditional_bounds(problem, n_phases, pairs, fewest)
            bound = cond.least if math.isfinite(cond.least) else -math.inf  # no path: no cut, as min_objective
        else:
            bound = min_objective(problem, n_phases, pairs, run.deadline, last_at_end=fewest)
        windows = action_windows(problem, n_phases, pairs, run.deadline, last_at_end=fewest)
        record["objective_bound"] = bound if math.isfinite(bound) else None
        run.stats["lower_bound_s"] += time.perf_counter() - t_bound
        return bound, windows, cond

    def add_warm_starts(
        self,
        milp: Milp,
        problem: Problem,
        n_phases: int,
        cond: Conditional | None,
        warms: list[list[SolvedPhase]] | None,
        record: dict[str, Any],
    ) -> None:
        """The warm starts SCIP accepts (each checked: the guide, the first plan, or ``warms``), and
        the options the best of those beats (its task cost is the model's objective)."""
        run = self.run
        if warms is None:
            known = [*run.guides, *([run.warm] if run.warm is not None else [])]
            warms = [steps for steps in known if len(steps) <= n_phases - 1]
        if not warms:
            return
        accepted = [steps for steps in warms if add_warm_start(milp, steps)]
        record["warm_start"] = bool(accepted)
        if run.guides:  # whether SCIP took the guide itself (as it is or compact) as a first solution
            record["guide_warm_start"] = any(steps is guide for steps in accepted for guide in run.guides)
        values = [run.cost(phases_of(problem, steps)) for steps in accepted]  # a shorter plan pads at no cost
        if cond is not None and values:
            record["conditional_fixed"] += fix_above(milp, cond, min(values))

    def read_solution(self, problem: Problem, milp: Milp) -> list[SolvedPhase]:
        """The best solution's steps; its objective (the task cost), dual bound and gap go to the stats."""
        stats, model = self.run.stats, milp.model
        steps = read_steps(problem, milp, model.getBestSol())
        stats["milp_objective"] = model.getObjVal()
        dual = model.getDualbound()
        stats["dual_bound"] = dual if abs(dual) < model.infinity() else None
        gap = model.getGap()
        stats["gap"] = gap if stats["dual_bound"] is not None and abs(gap) < model.infinity() else None
        return steps


@functools.cache
def solver_name() -> str:
    """``"SCIP <major>.<minor>.<tech>"`` of the SCIP inside pyscipopt."""
    model = pyscipopt.Model()
    return f"SCIP {model.getMajorVersion()}.{model.getMinorVersion()}.{model.getTechVersion()}"
