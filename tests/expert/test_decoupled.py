"""The decoupled first plan: valid, quick to find, the answer of last resort and SCIP's first incumbent."""

from __future__ import annotations

import math

import numpy as np
import pytest

from expert.decoupled import decoupled_plan, steps_of
from expert.milp.deadline import Deadline
from expert.milp.problem import prepare
from expert.milp.warm import solution_values
from expert.planner import PlannerOptions, SubPlanner, plan
from expert.planning.first_plans import FirstPlans
from expert.planning.run import Run, same_plan
from expert.planning.solving import Solver
from expert.plans import Plan, task_cost
from expert.validate import validate_plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_covered, draw_paper_multi


def sub_planner(scenario, seconds: float = 120.0) -> SubPlanner:
    """The planner's own sub-planner for ``scenario``'s first plans (default options; a generous safety stop)."""
    return SubPlanner(PlannerOptions(), Deadline.after(seconds), Lattice.over(scenario.area, 0.05))


def optimal(planner: SubPlanner):
    """``planner`` asking for optimal sub-plans (within their node budget)."""
    return lambda scenario, **kwargs: planner(scenario, **{"optimal": True, **kwargs})


def first_plans(scenario) -> tuple[Run, FirstPlans]:
    """A run of the planner on ``scenario`` and its first plans' job, as :func:`expert.planner.plan` makes them."""
    run = Run(scenario, PlannerOptions(), Deadline.after(300.0))
    lattice = Lattice.over(scenario.area, 0.05)
    return run, FirstPlans(run, Solver(run), lattice, sub_planner(scenario, 300.0))


@pytest.mark.parametrize(("family", "count"), [("multi", 3), ("multi", 5), ("covered", 2)])
def test_decoupled_plan_is_valid(family, count):
    scenario = {"multi": draw_paper_multi, "covered": draw_paper_covered}[family](np.random.default_rng(7), count)
    lattice = Lattice.over(scenario.area, 0.05)
    order = [o.id for o in scenario.objects]
    phases = decoupled_plan(scenario, order, lattice, optimal(sub_planner(scenario)))
    assert phases is not None
    result = Plan(scenario.name, "feasible", task_cost(scenario, phases), phases, {})
    assert validate_plan(scenario, result) == []
    problem = prepare(scenario, lattice)
    steps = steps_of(problem, phases)
    assert steps is not None and len(steps) == len(phases) - 1
    assert all(s.option is not None for s, p in zip(steps, phases[1:], strict=True) if p.action != "move")


def test_a_small_node_budget_returns_the_first_plan_or_better_and_the_same_plan_twice():
    """Five objects, 20 nodes a solve: a valid plan with its provenance, no dearer than the first plan, twice alike.

    Before the budgets were counted, a 1 s limit made this call's answer (and even whether its
    lower bound was recorded: a KeyError) depend on the machine's load.
    """
    scenario = draw_paper_multi(np.random.default_rng(2024), 5)
    result = plan(scenario, time_limit=300.0, node_limit=20, ordered_nodes=20)
    assert result.status in ("feasible", "optimal"), result.stats
    assert not result.stats["clock_stopped"] and validate_plan(scenario, result) == []
    assert result.stats["lower_bound"] <= len(result.phases)
    if "decoupled_objective" in result.stats:
        assert result.objective <= result.stats["decoupled_objective"] + 1e-6
    assert same_plan(result, plan(scenario, time_limit=300.0, node_limit=20, ordered_nodes=20))


def test_decoupled_plan_warm_starts_a_model_with_as_many_phases():
    scenario = draw_paper_multi(np.random.default_rng(2024), 4)
    result = plan(scenario, time_limit=30.0)
    assert result.status == "optimal"
    solve = result.stats["solves"][0]
    if result.stats.get("decoupled_phases", math.inf) <= solve["phases"]:
        assert solve["warm_start"] is True
    assert result.objective <= result.stats.get("decoupled_objective", math.inf) + 1e-6


def test_warm_start_values_refuse_a_plan_longer_than_the_model():
    from expert.milp.build import build

    scenario = draw_paper_multi(np.random.default_rng(1), 3)
    lattice = Lattice.over(scenario.area, 0.05)
    phases = decoupled_plan(scenario, [o.id for o in scenario.objects], lattice, optimal(sub_planner(scenario)))
    problem = prepare(scenario, lattice)
    steps = steps_of(problem, phases)
    assert solution_values(build(problem, len(phases) - 1), steps) is None
    assert solution_values(build(problem, len(phases)), steps) is not None


def test_lookahead_keeps_phases_through_the_first_place_and_stays_valid():
    """Two objects at a time: each step keeps the sub-plan up to its first place; the whole plan is valid."""
    scenario = draw_paper_multi(np.random.default_rng(3), 4)
    lattice = Lattice.over(scenario.area, 0.05)
    order = [o.id for o in scenario.objects]
    phases = decoupled_plan(scenario, order, lattice, optimal(sub_planner(scenario)), lookahead=2)
    assert phases is not None
    assert sum(p.action == "place" for p in phases) == len(scenario.objects)
    assert validate_plan(scenario, Plan(scenario.name, "feasible", task_cost(scenario, phases), phases, {})) == []


@pytest.mark.parametrize(("family", "count"), [("multi", 6), ("covered", 3)])
def test_nearest_first_plan_with_first_solutions_is_valid(family, count):
    """The nearest first plan: nearest object first, each sub-plan SCIP's first solution at the fewest phases."""
    scenario = {"multi": draw_paper_multi, "covered": draw_paper_covered}[family](np.random.default_rng(2024), count)
    lattice = Lattice.over(scenario.area, 0.05)
    order = [o.id for o in scenario.objects]
    phases = decoupled_plan(scenario, order, lattice, sub_planner(scenario), nearest=True)
    assert phases is not None
    assert sum(p.action == "place" for p in phases) == count
    assert validate_plan(scenario, Plan(scenario.name, "feasible", task_cost(scenario, phases), phases, {})) == []


def test_the_nearest_first_plan_answers_when_the_safety_stop_comes_in_the_bounds(monkeypatch):
    """The clock running out in the lower bounds (simulated) answers with the nearest first plan, and says so."""
    import expert.planning.deepening as deepening
    from expert.milp.deadline import TimeUp

    pair_costs = deepening.PairCosts

    def out_of_time(problem, *args, **kwargs):
        if len(problem.deliver) > 1:  # the whole problem, not the decoupled plan's single-object sub-plans
            raise TimeUp
        return pair_costs(problem, *args, **kwargs)

    monkeypatch.setattr(deepening, "PairCosts", out_of_time)
    scenario = draw_paper_covered(np.random.default_rng(2024), 3)
    result = plan(scenario, time_limit=300.0, nearest_first_plan=True)
    assert result.status == "feasible"
    assert result.stats["clock_stopped"] and result.stats["stopped_by"] == "clock" and result.stats["gap"] is None
    assert result.stats["decoupled"] == "nearest" and "safety stop" in result.stats["optimality"]
    assert validate_plan(scenario, result) == []


@pytest.mark.parametrize(("count", "passes"), [(3, [1, 2]), (4, [1, 2, 3])])
def test_the_passes_never_plan_every_object_at_once(monkeypatch, count, passes):
    """One pass per lookahead while none gives the model's phases, but never all the objects together.

    A pass of all the objects would be the whole problem again (a plan() inside plan(), without end).
    """
    import expert.planning.first_plans as module

    tried = []

    def no_plan(scenario, order, lattice, sub_planner, lookahead=1, **kwargs):
        tried.append(lookahead)
        return None

    monkeypatch.setattr(module, "decoupled_plan", no_plan)
    scenario = draw_paper_covered(np.random.default_rng(7001), count)
    _, jobs = first_plans(scenario)
    jobs.decoupled_plans(prepare(scenario, Lattice.over(scenario.area, 0.05)), 3, [o.id for o in scenario.objects])
    assert tried == passes


def test_three_at_a_time_finds_the_fewest_phases_where_two_at_a_time_does_not():
    """Four objects, every goal covered (seed 7002): two at a time gives 19 phases, three at a time 18.

    The 18-phase plan pushes clutter while carrying another object, which no step of
    one or two objects sees; 17 phases admit no plan (the skeleton's bound), so 18 is the fewest.
    """
    scenario = draw_paper_covered(np.random.default_rng(7002), 4)
    lattice = Lattice.over(scenario.area, 0.05)
    order = [o.id for o in scenario.objects]
    two = decoupled_plan(scenario, order, lattice, optimal(sub_planner(scenario)), lookahead=2)
    assert two is not None and len(two) == 19
    run, jobs = first_plans(scenario)
    problem = prepare(scenario, lattice)
    jobs.decoupled_plans(problem, 17, order)
    status, phases = run.best
    assert run.stats["decoupled"] == "schedule, lookahead 3"
    assert len(phases) == 18 and run.warm is not None
    assert validate_plan(scenario, Plan(scenario.name, status, task_cost(scenario, phases), phases, {})) == []
