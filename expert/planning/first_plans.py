"""First plans: valid plans made quickly, as SCIP's warm starts and as the answer should a stop come first.

From ``options.decoupled_from`` objects to deliver (one fewer with pushes) :class:`FirstPlans`
makes, before the main search:

- the first model's own MILP restricted to the relaxation's order of deliveries
  (:meth:`FirstPlans.ordered_plan`, within ``options.ordered_nodes`` nodes): where that order
  is the optimum's, the plan is the optimum itself, and as warm start it lets SCIP fix every
  option whose conditional bound it beats;
- when that gives no plan of the model's phases, the decoupled plans
  (:mod:`expert.decoupled`), one pass per entry of ``options.lookaheads``, each sub-plan
  within ``options.sub_plan_nodes`` nodes.

Every budget is counted, so the first plans, and the search they warm-start, are the same at
any load. Units are seconds (timings) and SCIP nodes (budgets).
"""

from __future__ import annotations

import time
from collections.abc import Callable

from expert.decoupled import decoupled_plan, steps_of
from expert.milp.bounds import PairCosts, cheapest_schedule
from expert.milp.conditional import conditional_bounds, fix_unreached
from expert.milp.decode import SolvedPhase, phases_of, read_steps
from expert.milp.order import add_pick_order
from expert.milp.problem import Problem
from expert.milp.variables import Milp
from expert.planning.run import Run
from expert.planning.solving import INFEASIBLE, FirstModelHook, Solver, optimize
from expert.plans import Plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.scenario import Scenario

SubPlanner = Callable[..., Plan]
"""``sub_planner(scenario, holding=None, lower_bound=True, optimal=False) -> Plan``: see :mod:`expert.decoupled`."""


class FirstPlans:
    """The first plans of one call (see the module docstring); they record into ``run``."""

    def __init__(self, run: Run, solver: Solver, lattice: Lattice, sub_planner: SubPlanner) -> None:
        self.run, self.solver, self.lattice, self.sub_planner = run, solver, lattice, sub_planner
        self.order: list[str] | None = None  # the relaxation's order of deliveries, for the first model built

    def wanted(self, problem: Problem) -> bool:
        """Whether this problem gets first plans: enough objects to deliver (the one in the hand counted)."""
        pushes = 1 if problem.pushes.pushable else 0
        return len(problem.deliver) >= self.run.options.decoupled_from - pushes

    @staticmethod
    def with_held_first(problem: Problem, picks: list[str]) -> list[str]:
        """An order of deliveries: the object in the hand (placed before any pick), ``picks``, then the rest."""
        head = [problem.holding] if problem.holding is not None else []
        return head + picks + [i for i in problem.deliver if i not in picks and i not in head]

    def nearest(self, problem: Problem) -> None:
        """The decoupled plan, nearest object first, before any bound (``options.nearest_first_plan``)."""
        t0 = time.perf_counter()
        deliver, held = list(problem.deliver), problem.holding
        found = decoupled_plan(self.run.scenario, deliver, self.lattice, self.sub_planner, nearest=True, holding=held)
        self.run.stats["decoupled_s"] = time.perf_counter() - t0
        if found is not None:
            self.run.keep_first_plan(found, "nearest")

    def choose_order(self, problem: Problem, pairs: PairCosts | None, n_phases: int, fewest: bool) -> None:
        """The relaxation's cheapest order of deliveries: for the first model's ordered plan, or the decoupled
        plans now (without the ordered plan).

        ``fewest``: the model with ``n_phases`` will get the fewest-phases cuts; the conditional
        bounds that give the order are then the ones that model uses (computed once).
        """
        run = self.run
        order = list(problem.deliver)
        if pairs is not None:
            if run.options.conditional:
                t_bound = time.perf_counter()
                picks = self.solver.conditional_bounds(problem, n_phases, pairs, fewest).order("pick")
                run.stats["lower_bound_s"] += time.perf_counter() - t_bound
            else:
                _, schedule = cheapest_schedule(problem, n_phases, pairs, run.deadline)
                picks = [key[1] for key, _ in schedule if key[0] == "pick"]
            order = self.with_held_first(problem, picks)
            if run.options.ordered_first_plan:
                self.order = order
                return
        self.decoupled_plans(problem, n_phases, order)

    def hook(self, pairs: PairCosts | None, fewest: bool) -> Callable[[Milp, Problem], bool] | None:
        """The first model's hook (:meth:`ordered_plan` in the chosen order), once; None when there is none."""
        if self.order is None:
            return None
        order, self.order = self.order, None
        return lambda milp, problem: self.ordered_plan(milp, problem, order, pairs, fewest)

    def decoupled_plans(self, problem: Problem, n_phases: int, order: list[str]) -> None:
        """The decoupled plan in ``order`` with optimal sub-plans, then two and three objects at a time
        (``options.lookaheads``, while the best has more than ``n_phases`` phases or is still the nearest
        plan; never all the objects at once); the better plan is kept and warm-starts SCIP.
        """
        run = self.run
        t0 = time.perf_counter()
        optimal_sub_plans = _optimal(self.sub_planner)
        for lookahead in (n for n in run.options.lookaheads if n == 1 or n < len(order)):
            phases = run.best[1] if run.best is not None else None
            good = phases is not None and len(phases) <= n_phases and run.stats.get("decoupled") != "nearest"
            if lookahead > 1 and good:
                break
            found = decoupled_plan(
                run.scenario, order, self.lattice, optimal_sub_plans, lookahead, holding=problem.holding
            )
            if found is not None:
                run.keep_first_plan(found, f"schedule, lookahead {lookahead}")
        run.stats["decoupled_s"] = run.stats.get("decoupled_s", 0.0) + time.perf_counter() - t0
        if run.best is not None:
            run.warm = steps_of(problem, run.best[1])

    def ordered_plan(
        self, milp: Milp, problem: Problem, order: list[str], pairs: PairCosts | None, fewest: bool
    ) -> bool:
        """The best plan of the model that delivers the objects in ``order``, as the first plan.

        The model restricted to that order (:func:`expert.milp.order.add_pick_order`) is
        solved within ``options.ordered_nodes`` nodes (:meth:`solve_in_order`), then freed of
        the restriction: the model is built once. The plan is kept when
        better than the best so far; without a plan of the model's phases the decoupled plans
        follow (:meth:`decoupled_plans`). Recorded in ``stats["ordered"]`` and ``stats["ordered_s"]``.

        When the order's model is infeasible at its root, the whole model is solved at its root
        too (:meth:`root_proof`) before any decoupled plan; where that proves it infeasible, the
        decoupled plans aim at one phase more and True is returned: the model needs no further solve.
        """
        run, t0 = self.run, time.perf_counter()
        steps, record, at_root = self.solve_in_order(milp, problem, order, pairs, fewest, run.options.ordered_nodes)
        run.stats["ordered"] = record
        run.stats["ordered_s"] = time.perf_counter() - t0
        proven_infeasible = False
        if at_root:
            steps = self.root_proof(milp, problem)
            proven_infeasible = steps == "infeasible"
            if proven_infeasible:
                steps = None
        fits = False
        if steps is not None:
            phases = phases_of(problem, steps)
            fits = len(phases) <= milp.n_phases
            if run.keep_first_plan(phases, "pick order of the relaxation"):
                run.warm = steps
        if not fits:
            self.decoupled_plans(problem, milp.n_phases + 1 if proven_infeasible else milp.n_phases, order)
        return proven_infeasible

    def solve_in_order(
        self, milp: Milp, problem: Problem, order: list[str], pairs: PairCosts | None, fewest: bool, nodes: int
    ) -> tuple[list[SolvedPhase] | None, dict, bool]:
        """``milp`` restricted to delivering in ``order``, solved within ``nodes`` SCIP nodes.

        :func:`expert.milp.order.add_pick_order` restricts it, and the options no plan in that
        order does are fixed to 0 (:meth:`fix_outside_order`) while it is solved; then the
        restriction and those fixings are removed (SCIP back to its problem stage). Returns
        the best plan's steps (None: none found), a record of SCIP's status, nodes, the order
        and the fixings, and whether the restricted model was proven infeasible at its root.
        """
        run, model = self.run, milp.model
        restriction = add_pick_order(milp, order)
        outside = self.fix_outside_order(milp, problem, order, pairs, fewest)
        status = optimize(model, run.deadline, nodes)
        if status == "timelimit":
            run.stopped("clock")
        steps = read_steps(problem, milp, model.getBestSol()) if model.getNSols() else None
        searched = model.getNNodes()
        at_root = status in INFEASIBLE and searched <= 1
        record = {"status": status, "nodes": searched, "order": list(order), "fixed": len(outside)}
        model.freeTransform()
        for constraint in restriction:
            model.delCons(constraint)
        for z in outside:
            model.chgVarUb(z, 1.0)
        return steps, record, at_root

    def longer_hook(self, problem: Problem, pairs: PairCosts | None, n_phases: int) -> FirstModelHook | None:
        """For a model of a longer phase count (cut off at the best plan's cost): its ordered plan first.

        The relaxation's cheapest order of deliveries at ``n_phases`` (the conditional bounds
        the model itself uses) restricts the model, solved within
        ``options.longer_ordered_nodes`` nodes (:meth:`solve_in_order`). A plan found costs
        less than the best (the model's cutoff holds): it becomes the best plan and SCIP's
        warm start, so the whole model starts from it and fixes every option whose
        conditional bound it beats. None when the planner makes no ordered plans. Recorded
        in ``stats["longer_ordered"]``.
        """
        run = self.run
        if pairs is None or not (self.wanted(problem) and run.options.ordered_first_plan and run.options.conditional):
            return None

        def hook(milp: Milp, problem: Problem) -> bool:
            t0 = time.perf_counter()
            picks = self.solver.conditional_bounds(problem, n_phases, pairs, True).order("pick")  # the model's own
            order = self.with_held_first(problem, picks)
            steps, record, _ = self.solve_in_order(milp, problem, order, pairs, True, run.options.longer_ordered_nodes)
            if steps is not None:
                phases = phases_of(problem, steps)
                record["cost"] = run.cost(phases)
                if run.best is None or run.better(phases, run.best[1]):
                    run.best, run.warm = ("feasible", phases), steps
            run.stats.setdefault("longer_ordered", []).append({"phases": n_phases, **record})
            run.stats["ordered_s"] = run.stats.get("ordered_s", 0.0) + time.perf_counter() - t0
            return False

        return hook

    def fix_outside_order(
        self, milp: Milp, problem: Problem, order: list[str], pairs: PairCosts | None, fewest: bool
    ) -> list:
        """Fix to 0 the options that no plan in ``order`` does, by the conditional bounds of those plans
        (:func:`expert.milp.conditional.fix_unreached`); returns them, to be freed with the order's restriction.

        Only with ``options.order_fixings`` and the conditional bounds on; counted in ``stats["ordered"]["fixed"]``.
        """
        run = self.run
        if pairs is None or not (run.options.order_fixings and run.options.conditional):
            return []
        in_order = conditional_bounds(problem, milp.n_phases, pairs, run.deadline, last_at_end=fewest, order=order)
        return fix_unreached(milp, in_order)

    def root_proof(self, milp: Milp, problem: Problem) -> str | list[SolvedPhase] | None:
        """The whole model solved at its root node only: ``"infeasible"``, the steps of a plan found, or None.

        A node limit, so the outcome is the same at any load. The model is back in its problem
        stage afterwards unless it was proven infeasible. Counted in ``stats["ordered_s"]``;
        SCIP's status and nodes in ``stats["ordered"]["root"]`` and ``["root_nodes"]``.
        """
        run, model, t0 = self.run, milp.model, time.perf_counter()
        status = optimize(model, run.deadline, 1)
        if status == "timelimit":
            run.stopped("clock")
        run.stats["ordered"].update(root=status, root_nodes=model.getNNodes())
        infeasible = status in INFEASIBLE
        steps = read_steps(problem, milp, model.getBestSol()) if not infeasible and model.getNSols() else None
        if not infeasible:
            model.freeTransform()
        run.stats["ordered_s"] += time.perf_counter() - t0
        return "infeasible" if infeasible else steps


def _optimal(sub_planner: SubPlanner) -> SubPlanner:
    """``sub_planner`` asking for optimal sub-plans (within its node budget) unless told otherwise."""

    def planner(scenario: Scenario, **kwargs) -> Plan:
        return sub_planner(scenario, **{"optimal": True, **kwargs})

    return planner
