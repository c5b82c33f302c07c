"""Eq. 1's bounds given an action's pose box and phase (``expert.milp.conditional``) are lower bounds.

Checked against optimal plans found without them: every action of the optimum is done at
a pose box and phase whose bound is at most the optimum's Eq. 1, the least bound is
``min_objective``, and the planner with the cuts and fixings finds the same optimum.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from expert.decoupled import steps_of
from expert.milp.bounds import PairCosts, cheapest_schedule, min_objective, skeleton
from expert.milp.conditional import _forward, _leave, conditional_bounds, exit_box_of, least_by_last_phase
from expert.milp.deadline import NEVER
from expert.milp.problem import prepare
from expert.planner import plan
from expert.validate import validate_plan
from fetchcarry_env import families
from fetchcarry_env.actions import Lattice
from fetchcarry_env.kinematics import WAIT_COST


def _cases():
    rng = np.random.default_rng(11)
    cases = [
        families.draw_paper_basic(rng, "II"),
        families.draw_paper_push(rng, "E"),
        families.draw_paper_corridor(rng),
    ]
    cases += [families.draw_paper_multi(rng, 2), families.draw_paper_multi(rng, 3), families.draw_paper_multi(rng, 3)]
    cases += [families.draw_paper_covered(rng, 2), families.draw_paper_covered(rng, 2)]
    return cases


CASES = _cases()


@pytest.mark.parametrize("scenario", CASES, ids=[f"{k}-{s.name}" for k, s in enumerate(CASES)])
def test_the_optimum_respects_every_conditional_bound(scenario):
    without = plan(scenario, time_limit=60, conditional=False)
    assert without.status == "optimal"
    lattice = Lattice.over(scenario.area, 0.05)
    problem = prepare(scenario, lattice)
    pairs = PairCosts(problem)
    n_phases = len(without.phases)
    last_at_end = without.stats["solves"][-1]["fewest_cuts"]
    conditional = conditional_bounds(problem, n_phases, pairs, last_at_end=last_at_end)
    least = min(float(np.min(row)) for row in conditional.bound.values())
    assert least == pytest.approx(min_objective(problem, n_phases, pairs, last_at_end=last_at_end))
    steps = steps_of(problem, without.phases)
    assert steps is not None
    actions = 0
    for k, step in enumerate(steps, start=1):
        if step.option is None:
            continue
        actions += 1
        value = conditional.at((step.option.kind, step.option.target), exit_box_of(step.option), k)
        assert math.isfinite(value)
        assert value <= without.objective + 1e-6, (k, step.option.kind, step.option.target)
    assert actions == 2 * len(scenario.objects) + len(problem.pushes.pushable)
    with_cuts = plan(scenario, time_limit=60)
    assert with_cuts.status == "optimal"
    assert len(with_cuts.phases) == n_phases
    assert with_cuts.objective == pytest.approx(without.objective, abs=1e-6)
    assert validate_plan(scenario, with_cuts) == []


def test_an_action_at_a_phase_too_early_for_it_has_no_bound():
    scenario = families.draw_paper_multi(np.random.default_rng(11), 3)
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05))
    pairs = PairCosts(problem)
    conditional = conditional_bounds(problem, 12, pairs)
    places = {(key, box): row for (key, box), row in conditional.bound.items() if key[0] == "place"}
    assert places and all(math.isinf(row[1]) for row in places.values())  # a place needs a pick before it
    for object_id in problem.deliver:  # but every object can be placed at some later phase
        assert any(math.isfinite(float(np.min(row))) for (key, _), row in places.items() if key[1] == object_id)


@pytest.mark.parametrize("extra", [1, 2])
def test_extra_phases_keep_their_optimum(extra):
    """The ``N + k`` model (idle phases allowed, no fewest-phases cuts) gets the cuts too: same answer as without."""
    scenario = families.draw_paper_multi(np.random.default_rng(3), 2)
    with_cuts = plan(scenario, time_limit=60, extra_phases=extra)
    without = plan(scenario, time_limit=60, extra_phases=extra, conditional=False)
    assert with_cuts.status == without.status == "optimal"
    assert len(with_cuts.phases) == len(without.phases)
    assert with_cuts.objective == pytest.approx(without.objective, abs=1e-6)
    assert validate_plan(scenario, with_cuts) == []


def test_an_object_in_the_hand_keeps_its_optimum():
    scenario = families.draw_paper_multi(np.random.default_rng(4), 3)
    held = scenario.objects[0].id
    with_cuts = plan(scenario, time_limit=60, holding=held)
    without = plan(scenario, time_limit=60, holding=held, conditional=False)
    assert with_cuts.status == without.status == "optimal"
    assert len(with_cuts.phases) == len(without.phases)
    assert with_cuts.objective == pytest.approx(without.objective, abs=1e-6)
    assert validate_plan(scenario, with_cuts, holding=held) == []


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_order_of_picks_is_the_cheapest_schedules(seed):
    """The decoupled plan's order, read off the bounds, is the one ``cheapest_schedule`` finds."""
    scenario = families.draw_paper_multi(np.random.default_rng(seed), 4)
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05))
    pairs = PairCosts(problem)
    n_phases = skeleton(problem, pairs).phases + 1
    _, schedule = cheapest_schedule(problem, n_phases, pairs)
    picks = [key[1] for key, _ in schedule if key[0] == "pick"]
    assert conditional_bounds(problem, n_phases, pairs).order("pick") == picks


def _dense_bounds(problem, n: int, pairs: PairCosts, last_at_end: bool, order=None) -> dict:
    """The conditional bounds as the searches compute them over every phase ``0 .. N - 1`` of every state."""
    graph = pairs.graph().within(n)
    if order is not None:
        graph = graph.in_order(order, problem.deliver)
    bonus = np.zeros((n, graph.state_count))
    bonus[:, graph.placed] = WAIT_COST * np.arange(n)[:, None]
    if last_at_end:
        last = graph.placed & graph.finished
        bonus[: n - 1, last] = math.inf
        bonus[n - 1, last] = WAIT_COST * (n - 1)
    total = _forward(graph, n, bonus, NEVER) + _leave(graph, n, bonus, NEVER) - WAIT_COST * len(problem.deliver)
    bounds: dict = {}
    for state in range(1, graph.state_count):
        slot = graph.slots[graph.slot[state]]
        bounds[slot] = np.minimum(bounds.get(slot, np.full(n, math.inf)), total[:, state])
    return bounds


BANDS = [(scenario, extra) for scenario in CASES[3:] for extra in (0, 2)]


@pytest.mark.parametrize(("scenario", "extra"), BANDS, ids=[f"{s.name}+{extra}" for s, extra in BANDS])
def test_the_band_has_the_dense_tables_values_bit_for_bit(scenario, extra):
    """The searches keep only the phases where a state can lie on a plan (``Band``): nothing else changes."""
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05))
    pairs = PairCosts(problem)
    n = skeleton(problem, pairs).phases + extra
    for last_at_end, order in ((False, None), (True, None), (False, list(problem.deliver)[::-1])):
        banded = conditional_bounds(problem, n, pairs, last_at_end=last_at_end, order=order).bound
        dense = _dense_bounds(problem, n, pairs, last_at_end, order)
        assert banded.keys() == dense.keys()
        for slot, row in dense.items():
            assert np.array_equal(banded[slot], row), slot
    graph = pairs.graph().within(n + 4)
    bonus = np.zeros((n + 4, graph.state_count))
    bonus[:, graph.placed] = WAIT_COST * np.arange(n + 4)[:, None]
    forward = _forward(graph, n + 4, bonus, NEVER)[:, graph.finished & graph.placed]
    dense_by_last = forward.min(axis=1) - WAIT_COST * len(problem.deliver)
    assert np.array_equal(least_by_last_phase(problem, n + 4, pairs), dense_by_last)
