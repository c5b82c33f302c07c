"""The first plan in the relaxation's order: the order holds, and the answer is the planner's without it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from expert.milp.bounds import PairCosts
from expert.milp.build import build
from expert.milp.conditional import add_conditional_cuts, conditional_bounds, fix_unreached
from expert.milp.decode import read_steps
from expert.milp.order import add_pick_order
from expert.milp.problem import prepare
from expert.planner import plan
from expert.validate import validate_plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_covered, draw_paper_multi


def _picks(phases) -> list[str]:
    return [p.target for p in phases if p.action == "pick"]


def _assert_same_optimum(scenario, result, plain, holding=None) -> None:
    """``result`` and ``plain`` both proven, with the same phases and task cost; ``result`` valid."""
    assert result.status == plain.status == "optimal"
    assert len(result.phases) == len(plain.phases)
    assert result.objective == pytest.approx(plain.objective, abs=1e-6)
    assert validate_plan(scenario, result, holding=holding) == []


def test_pick_order_is_obeyed():
    """Three objects with their optimal pick order reversed: the restricted model picks them in that order."""
    scenario = draw_paper_multi(np.random.default_rng(3), 3)
    lattice = Lattice.over(scenario.area, 0.05)
    best = plan(scenario, time_limit=60.0, lattice=lattice)
    assert best.status == "optimal"
    reverse = _picks(best.phases)[::-1]
    milp = build(prepare(scenario, lattice), len(best.phases) + 4)  # that order needs 4 phases more
    add_pick_order(milp, reverse)
    milp.model.optimize()
    assert milp.model.getNSols() > 0
    steps = read_steps(milp.problem, milp, milp.model.getBestSol())
    picked = [s.option.target for s in steps if s.option is not None and s.option.kind == "pick"]
    assert picked == reverse


def test_the_options_outside_the_order_fixed_keep_its_best_plan_and_are_freed_after():
    """Three covered goals (seed 7105), 15 phases, picks in the order 2, 1, 3 (not the optimum's): the same
    best plan with the options no plan in that order does fixed to 0; freed again, the model's optimum."""
    scenario = draw_paper_covered(np.random.default_rng(7105), 3)
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05))
    pairs = PairCosts(problem)
    every, order = conditional_bounds(problem, 15, pairs), ["object_2", "object_1", "object_3"]

    def model():  # as the planner builds it: the conditional cuts of every plan
        milp = build(problem, 15, objective_bound=every.least)
        add_conditional_cuts(milp, every)
        return milp

    def best_in_order(milp, fixing: bool) -> tuple[float, list, list]:
        restriction = add_pick_order(milp, order)
        fixed = fix_unreached(milp, conditional_bounds(problem, 15, pairs, order=order)) if fixing else []
        milp.model.optimize()
        return milp.model.getObjVal(), restriction, fixed

    plain_order, _, none = best_in_order(model(), fixing=False)
    milp = model()
    fixed_order, restriction, fixed = best_in_order(milp, fixing=True)
    assert fixed and not none
    assert fixed_order == pytest.approx(plain_order, abs=1e-6)
    milp.model.freeTransform()
    for constraint in restriction:
        milp.model.delCons(constraint)
    for z in fixed:
        milp.model.chgVarUb(z, 1.0)
    milp.model.optimize()
    plain = model()
    plain.model.optimize()
    assert milp.model.getObjVal() == pytest.approx(plain.model.getObjVal(), abs=1e-6)
    assert milp.model.getObjVal() < fixed_order - 1.0  # the restriction and the fixings are gone


def test_the_planner_frees_the_fixings_for_the_whole_model():
    """Three covered goals (seed 7100): the relaxation's order is not the optimum's. The ordered plan (with
    options fixed) is beaten by the unrestricted solve, and the answer is the one without the fixings."""
    scenario = draw_paper_covered(np.random.default_rng(7100), 3)
    result = plan(scenario, time_limit=60.0)
    assert result.status == "optimal" and result.stats["ordered"]["fixed"] > 0
    assert result.stats["decoupled"] == "pick order of the relaxation"
    assert result.objective < result.stats["decoupled_objective"] - 1.0
    unfixed = plan(scenario, time_limit=60.0, order_fixings=False)
    assert unfixed.status == "optimal" and unfixed.stats["ordered"]["fixed"] == 0
    assert len(result.phases) == len(unfixed.phases)
    assert result.objective == pytest.approx(unfixed.objective, abs=1e-6)


def test_an_order_no_plan_follows_has_every_option_fixed():
    """Three objects (multi-3, seed 3), 9 phases: only the optimum's pick order has a plan; any other, no option
    is left, so the ordered model is infeasible before SCIP searches."""
    scenario = draw_paper_multi(np.random.default_rng(3), 3)
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05))
    pairs = PairCosts(problem)
    assert conditional_bounds(problem, 9, pairs, order=["object_2", "object_1", "object_3"]).least < math.inf
    blocked = conditional_bounds(problem, 9, pairs, order=["object_1", "object_2", "object_3"])
    assert blocked.least == math.inf
    milp = build(problem, 9)
    assert len(fix_unreached(milp, blocked)) == sum(len(chosen) for chosen in milp.z)


@pytest.mark.parametrize(("draw", "count", "seed"), [(draw_paper_multi, 5, 2024), (draw_paper_covered, 3, 7000)])
def test_the_answer_is_the_one_without_it(draw, count, seed):
    """Same phases and task cost as the planner with the decoupled first plan instead (the optimum is unchanged)."""
    scenario = draw(np.random.default_rng(seed), count)
    ordered = plan(scenario, time_limit=60.0)
    decoupled = plan(scenario, time_limit=60.0, ordered_first_plan=False)
    assert ordered.stats["decoupled"] == "pick order of the relaxation"
    assert ordered.stats["ordered"]["status"] == "optimal"
    assert decoupled.stats["decoupled"].startswith("schedule") and "ordered" not in decoupled.stats
    _assert_same_optimum(scenario, ordered, decoupled)


def test_without_nodes_for_it_the_decoupled_plan_comes_instead():
    """One node for the ordered model, which finds no plan in it: the decoupled passes run; the answer is optimal."""
    scenario = draw_paper_multi(np.random.default_rng(2024), 4)
    result = plan(scenario, time_limit=60.0, ordered_nodes=1)
    assert result.stats["ordered"]["status"] == "nodelimit"
    assert result.stats["decoupled"].startswith("schedule")
    assert result.status == "optimal"
    assert validate_plan(scenario, result) == []


def test_a_model_infeasible_at_its_root_is_solved_no_further():
    """Three covered goals (seed 7007): the first model (14 phases) and its relaxation's order admit no plan.

    The root proof settles the model (no second solve of it), the decoupled plans aim at
    15 phases, and the answer is the optimum the planner finds without the ordered plan.
    """
    scenario = draw_paper_covered(np.random.default_rng(7007), 3)
    result = plan(scenario, time_limit=120.0)
    first, last = result.stats["solves"][0], result.stats["solves"][-1]
    assert result.stats["ordered"]["status"] == "infeasible" and result.stats["ordered"]["root"] == "infeasible"
    assert first["status"] == "infeasible" and first["root_proof"] is True
    assert last["phases"] == first["phases"] + 1 and last["warm_start"] is True
    plain = plan(scenario, time_limit=120.0, ordered_first_plan=False)
    _assert_same_optimum(scenario, result, plain)


def test_a_longer_phase_count_starts_from_its_own_ordered_plan():
    """Three covered goals (seed 7000): the optimum has one phase more than the fewest. The longer count's
    model restricted to the relaxation's order at that count finds it first; the answer is the planner's
    without ordered plans."""
    scenario = draw_paper_covered(np.random.default_rng(7000), 3)
    result = plan(scenario, time_limit=60.0)
    longer = result.stats["longer_ordered"]
    assert [entry["phases"] for entry in longer] == [len(result.phases)]
    assert longer[0]["cost"] == pytest.approx(result.objective, abs=1e-9)
    plain = plan(scenario, time_limit=60.0, ordered_first_plan=False)
    _assert_same_optimum(scenario, result, plain)


def test_a_count_holding_nothing_cheaper_than_the_first_plan_ends_the_search():
    """Three covered goals (seed 7023): the decoupled plan (13 phases) costs less than any plan of the
    model. Each model admits only plans costing no more than the best so far, so the 13-phase model
    is proven to hold none, no longer count can, and the decoupled plan is the answer, proven."""
    scenario = draw_paper_covered(np.random.default_rng(7023), 3)
    result = plan(scenario, time_limit=60.0)
    last = result.stats["solves"][-1]
    assert last["status"] == "infeasible" and last["cap"] == pytest.approx(result.objective, abs=1e-9)
    assert result.status == "optimal" and result.stats["decoupled"].startswith("schedule")
    assert result.objective == pytest.approx(result.stats["decoupled_objective"], abs=1e-9)
    model_only = plan(scenario, time_limit=60.0, ordered_first_plan=False, decoupled_from=10**6)
    assert result.objective <= model_only.objective + 1e-9
    assert validate_plan(scenario, result) == []


def test_an_object_in_the_hand_is_placed_first_in_the_ordered_plan():
    """Four objects, one in the hand (a mid-episode state, as DAgger asks): the ordered plan places it
    before any pick, and the answer is the planner's without first plans."""
    scenario = draw_paper_multi(np.random.default_rng(2), 4)
    held = scenario.objects[0].id
    result = plan(scenario, time_limit=60.0, holding=held)
    assert result.stats["ordered"]["order"][0] == held
    assert result.stats["decoupled"] == "pick order of the relaxation"
    plain = plan(scenario, time_limit=60.0, holding=held, ordered_first_plan=False, decoupled_from=10**6)
    _assert_same_optimum(scenario, result, plain, holding=held)
