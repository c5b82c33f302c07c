"""Whether a model of N phases admits a plan: the planner's N-phase model solved once per pick order.

    python -m benchmarks.studies.pick_orders CASE N [--seconds S] [--save DIR] > rows.jsonl
    python -m benchmarks.studies.pick_orders CASE N --relaxation-order

``CASE`` as in ``bounds_ab.py`` (``covered:K:SEED``, ``multi:K:SEED`` or ``FAMILY:SEED``).
The model is the one :func:`expert.planner.plan` builds for N phases (the same bounds,
fewest-phases and conditional cuts), restricted by :func:`expert.milp.order.add_pick_order`
to one order of the objects at a time, ``S`` seconds each (20 by default), in the order of
``itertools.permutations``. One JSON line per order: SCIP's status, seconds, nodes,
solutions (SCIP keeps the earlier orders' plans that also fit this one) and, with a
plan, the best one's Eq. 1 (``objective``). The first plan found is checked by
:func:`expert.validate.validate_plan` and, with ``--save``, written to ``DIR`` with its
scenario (``fetchcarry validate`` reads both).
Every order proven infeasible proves the N-phase model infeasible; a time-limited order
proves nothing. The orders' solves are wall-clock bound, so a rerun can find the plan in
another order, or none. ``--relaxation-order`` prints only the pick order of the N-phase
relaxation's cheapest schedule (``Conditional.order``, the order the planner's ordered
first plan takes when N is its first model).
"""

from __future__ import annotations

import itertools
import json
import sys
import time
from pathlib import Path

from conditional_digest import scenario_of  # this folder's

from expert import planner
from expert.milp.build import SolverSettings, build
from expert.milp.conditional import add_conditional_cuts
from expert.milp.deadline import Deadline
from expert.milp.decode import phases_of, plan_objective, read_steps
from expert.milp.order import add_pick_order
from expert.milp.problem import prepare
from expert.plans import Plan
from expert.validate import validate_plan


def main(argv: list[str]) -> int:
    case, n_phases, *rest = argv
    n_phases, seconds, save = int(n_phases), 20.0, None
    relaxation_only = "--relaxation-order" in rest
    rest = [arg for arg in rest if arg != "--relaxation-order"]
    while rest:
        flag, value, *rest = rest
        if flag == "--seconds":
            seconds = float(value)
        elif flag == "--save":
            save = Path(value)
        else:
            raise SystemExit(f"unknown option {flag!r} (see the module docstring)")
    scenario, lattice = scenario_of(case)
    run = planner._Run(scenario, time.perf_counter(), Deadline.after(86400.0), SolverSettings(), 0)
    problem, pairs, _, _ = run.lower_bound(prepare(scenario, lattice), True)
    bound, windows, cond = run.model_bounds(problem, n_phases, pairs, True, {})
    if relaxation_only:
        print(json.dumps({"case": case, "phases": n_phases, "relaxation_order": cond.order("pick")}))
        return 0
    milp = build(problem, n_phases, run.settings, bound, windows, run.deadline, fewest=True)
    add_conditional_cuts(milp, cond)
    model, found = milp.model, None
    for order in itertools.permutations(sorted(problem.deliver)):
        restriction = add_pick_order(milp, order)
        t0 = time.perf_counter()
        status = planner._optimize(model, seconds)
        row = {
            "case": case,
            "phases": n_phases,
            "order": order,
            "status": status,
            "s": round(time.perf_counter() - t0, 2),
            "nodes": model.getNNodes(),
            "solutions": model.getNSols(),
        }
        if model.getNSols():
            row["objective"] = round(model.getObjVal(), 3)  # the MILP's objective: Eq. 1
            if found is None:  # the first plan: validated, and saved with --save
                phases = phases_of(problem, read_steps(problem, milp, model.getBestSol()))
                objective = plan_objective(scenario, phases)
                found = Plan(scenario.name, "feasible", objective, phases, {"order": list(order)})
                row.update(plan_phases=len(phases), validator=validate_plan(scenario, found) or "valid")
                if save is not None:
                    save.mkdir(parents=True, exist_ok=True)
                    scenario.save(save / "scenario.json")
                    found.save(save / "plan.json")
        print(json.dumps(row), flush=True)
        model.freeTransform()
        for constraint in restriction:
            model.delCons(constraint)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
