"""The decoupled first plan: valid, quick to find, the answer of last resort and SCIP's first incumbent."""

from __future__ import annotations

import numpy as np
import pytest

from expert.decoupled import decoupled_plan, steps_of
from expert.milp.deadline import Deadline
from expert.milp.decode import plan_objective
from expert.milp.problem import prepare
from expert.milp.warm import solution_values
from expert.planner import plan
from expert.plans import Plan
from expert.validate import validate_plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_covered, draw_paper_multi


@pytest.mark.parametrize(("family", "count"), [("multi", 3), ("multi", 5), ("covered", 2)])
def test_decoupled_plan_is_valid(family, count):
    scenario = {"multi": draw_paper_multi, "covered": draw_paper_covered}[family](np.random.default_rng(7), count)
    lattice = Lattice.over(scenario.area, 0.05)
    order = [o.id for o in scenario.objects]
    phases = decoupled_plan(scenario, order, lattice, Deadline.after(60.0), plan)
    assert phases is not None
    result = Plan(scenario.name, "feasible", plan_objective(scenario, phases), phases, {})
    assert validate_plan(scenario, result) == []
    problem = prepare(scenario, lattice)
    steps = steps_of(problem, phases)
    assert steps is not None and len(steps) == len(phases) - 1
    assert all(s.option is not None for s, p in zip(steps, phases[1:], strict=True) if p.action != "move")


def test_short_time_limit_returns_the_decoupled_plan_or_better():
    """Five objects at a 1 s limit: a valid plan with its provenance, the decoupled plan or better.

    Better: fewer phases (Eq. 1 is not comparable across phase counts), or as many and Eq. 1 no higher.
    """
    scenario = draw_paper_multi(np.random.default_rng(2024), 5)
    result = plan(scenario, time_limit=1.0)
    assert result.status in ("feasible", "optimal"), result.stats
    assert validate_plan(scenario, result) == []
    assert result.stats["decoupled_phases"] >= result.stats["lower_bound"]
    assert len(result.phases) <= result.stats["decoupled_phases"]
    if len(result.phases) == result.stats["decoupled_phases"]:
        assert result.objective <= result.stats["decoupled_objective"] + 1e-6


def test_decoupled_plan_warm_starts_a_model_with_as_many_phases():
    scenario = draw_paper_multi(np.random.default_rng(2024), 4)
    result = plan(scenario, time_limit=30.0)
    assert result.status == "optimal"
    solve = result.stats["solves"][-1]
    if result.stats["decoupled_phases"] <= solve["phases"]:
        assert solve["warm_start"] is True
    assert result.objective <= result.stats["decoupled_objective"] + 1e-6


def test_warm_start_values_refuse_a_plan_longer_than_the_model():
    from expert.milp.build import build

    scenario = draw_paper_multi(np.random.default_rng(1), 3)
    lattice = Lattice.over(scenario.area, 0.05)
    phases = decoupled_plan(scenario, [o.id for o in scenario.objects], lattice, Deadline.after(60.0), plan)
    problem = prepare(scenario, lattice)
    steps = steps_of(problem, phases)
    assert solution_values(build(problem, len(phases) - 1), steps) is None
    assert solution_values(build(problem, len(phases)), steps) is not None


def test_lookahead_keeps_phases_through_the_first_place_and_stays_valid():
    """Two objects at a time: each step keeps the sub-plan up to its first place; the whole plan is valid."""
    scenario = draw_paper_multi(np.random.default_rng(3), 4)
    lattice = Lattice.over(scenario.area, 0.05)
    order = [o.id for o in scenario.objects]
    phases = decoupled_plan(scenario, order, lattice, Deadline.after(60.0), plan, lookahead=2)
    assert phases is not None
    assert sum(p.action == "place" for p in phases) == len(scenario.objects)
    assert validate_plan(scenario, Plan(scenario.name, "feasible", plan_objective(scenario, phases), phases, {})) == []


@pytest.mark.parametrize(("family", "count"), [("multi", 6), ("covered", 3)])
def test_nearest_first_plan_with_first_solutions_is_valid(family, count):
    """The planner's first plan: nearest object first, each sub-plan SCIP's first solution at the fewest phases."""
    from expert.planner import _first_solution_planner

    scenario = {"multi": draw_paper_multi, "covered": draw_paper_covered}[family](np.random.default_rng(2024), count)
    lattice = Lattice.over(scenario.area, 0.05)
    order = [o.id for o in scenario.objects]
    phases = decoupled_plan(scenario, order, lattice, Deadline.after(60.0), _first_solution_planner, nearest=True)
    assert phases is not None
    assert sum(p.action == "place" for p in phases) == count
    assert validate_plan(scenario, Plan(scenario.name, "feasible", plan_objective(scenario, phases), phases, {})) == []


def test_first_plan_comes_before_the_bounds(monkeypatch):
    """Time running out in the lower bounds (simulated) still answers with the valid first plan, no gap claimed."""
    import expert.planner as planner
    from expert.milp.deadline import TimeUp

    connectivity = planner.Connectivity

    def out_of_time(problem, *args, **kwargs):
        if len(problem.deliver) > 1:  # the whole problem, not the decoupled plan's single-object sub-plans
            raise TimeUp
        return connectivity(problem, *args, **kwargs)

    monkeypatch.setattr(planner, "Connectivity", out_of_time)
    monkeypatch.setattr(planner, "FIRST_PLAN_BELOW_S", float("inf"))  # the first plan also with a long limit
    scenario = draw_paper_covered(np.random.default_rng(2024), 3)
    result = plan(scenario, time_limit=30.0)
    assert result.status == "feasible"
    assert result.stats["timed_out"] and result.stats["gap"] is None
    assert result.stats["decoupled"] == "nearest"
    assert validate_plan(scenario, result) == []


@pytest.mark.parametrize(("count", "passes"), [(3, [1, 2]), (4, [1, 2, 3])])
def test_the_passes_never_plan_every_object_at_once(monkeypatch, count, passes):
    """One pass per lookahead while none gives the model's phases, but never all the objects together.

    A pass of all the objects would be the whole problem again (a plan() inside plan(), without end).
    """
    import expert.planner as planner

    tried = []

    def no_plan(scenario, order, lattice, budget, sub_planner, lookahead=1, **kwargs):
        tried.append(lookahead)
        return None

    monkeypatch.setattr(planner, "decoupled_plan", no_plan)
    scenario = draw_paper_covered(np.random.default_rng(7001), count)
    lattice = Lattice.over(scenario.area, 0.05)
    run = planner._Run(scenario, 0.0, Deadline.after(60.0), planner.SolverSettings(), 0)
    run.decoupled_plans(prepare(scenario, lattice), lattice, 3, [o.id for o in scenario.objects])
    assert tried == passes


def test_three_at_a_time_finds_the_fewest_phases_where_two_at_a_time_does_not():
    """Four objects, every goal covered (seed 7002): two at a time gives 19 phases, three at a time 18.

    The 18-phase plan pushes clutter while carrying another object, which no step of
    one or two objects sees; 17 phases admit no plan (the skeleton's bound), so 18 is the fewest.
    """
    import expert.planner as planner

    scenario = draw_paper_covered(np.random.default_rng(7002), 4)
    lattice = Lattice.over(scenario.area, 0.05)
    order = [o.id for o in scenario.objects]
    two = decoupled_plan(scenario, order, lattice, Deadline.after(120.0), plan, lookahead=2)
    assert two is not None and len(two) == 19
    run = planner._Run(scenario, 0.0, Deadline.after(300.0), planner.SolverSettings(), 0)
    problem = prepare(scenario, lattice)
    run.decoupled_plans(problem, lattice, 17, order)
    status, phases = run.best
    assert run.stats["decoupled"] == "schedule, lookahead 3"
    assert len(phases) == 18 and run.warm is not None
    assert validate_plan(scenario, Plan(scenario.name, status, plan_objective(scenario, phases), phases, {})) == []
