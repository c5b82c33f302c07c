"""The first plan in the relaxation's order: the order holds, and the answer is the planner's without it."""

from __future__ import annotations

import numpy as np
import pytest

import expert.planner as planner
from expert.milp.build import build
from expert.milp.decode import read_steps
from expert.milp.order import add_pick_order
from expert.milp.problem import prepare
from expert.planner import plan
from expert.validate import validate_plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_covered, draw_paper_multi


def _picks(phases) -> list[str]:
    return [p.target for p in phases if p.action == "pick"]


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


@pytest.mark.parametrize(("draw", "count", "seed"), [(draw_paper_multi, 5, 2024), (draw_paper_covered, 3, 7000)])
def test_the_answer_is_the_one_without_it(monkeypatch, draw, count, seed):
    """Same phases and Eq. 1 as the planner with the decoupled first plan instead (the optimum is unchanged)."""
    scenario = draw(np.random.default_rng(seed), count)
    ordered = plan(scenario, time_limit=60.0)
    monkeypatch.setattr(planner, "ORDERED_FIRST_PLAN", False)
    decoupled = plan(scenario, time_limit=60.0)
    assert ordered.status == decoupled.status == "optimal"
    assert ordered.stats["decoupled"] == "pick order of the relaxation"
    assert ordered.stats["ordered"]["status"] == "optimal"
    assert decoupled.stats["decoupled"].startswith("schedule") and "ordered" not in decoupled.stats
    assert len(ordered.phases) == len(decoupled.phases)
    assert ordered.objective == pytest.approx(decoupled.objective, abs=1e-6)
    assert validate_plan(scenario, ordered) == []


def test_without_time_for_it_the_decoupled_plan_comes_instead(monkeypatch):
    """No time for the ordered model (its share 0): the decoupled passes run, and the answer is still optimal."""
    scenario = draw_paper_multi(np.random.default_rng(2024), 4)
    monkeypatch.setattr(planner, "ORDERED_SHARE", 0.0)
    result = plan(scenario, time_limit=60.0)
    assert result.stats["ordered"]["status"] == "timelimit"
    assert result.stats["decoupled"].startswith("schedule")
    assert result.status == "optimal"
    assert validate_plan(scenario, result) == []


def test_a_model_infeasible_at_its_root_is_solved_no_further(monkeypatch):
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
    monkeypatch.setattr(planner, "ORDERED_FIRST_PLAN", False)
    plain = plan(scenario, time_limit=120.0)
    assert result.status == plain.status == "optimal"
    assert len(result.phases) == len(plain.phases)
    assert result.objective == pytest.approx(plain.objective, abs=1e-6)
    assert validate_plan(scenario, result) == []
