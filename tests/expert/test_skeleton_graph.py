"""The skeleton graph's layered minima (``expert.milp.skeleton_graph``) equal a priority-queue search.

The reference here is Dijkstra's search (``expert.milp.bounds.settle``) over the same
steps, the way the bounds were computed before they shared one graph: per skeleton state
the least phases and travel from the start, and per state without poses the least phases
from the start and to the end.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from expert.milp.bounds import PairCosts, min_travel, settle, skeleton
from expert.milp.problem import prepare
from expert.milp.skeleton_graph import all_done, skeleton_moves
from fetchcarry_env import families
from fetchcarry_env.actions import Lattice


def _cases():
    rng = np.random.default_rng(5)
    return [
        families.draw_paper_push(rng, "E"),
        families.draw_paper_corridor(rng),
        families.draw_paper_multi(rng, 3),
        families.draw_paper_covered(rng, 2),
    ]


CASES = _cases()


def _pairs(scenario, holding=None) -> PairCosts:
    return PairCosts(prepare(scenario, Lattice.over(scenario.area, 0.05), holding=holding))


def _least_by_search(pairs: PairCosts, which: int, order: list[str] | None = None) -> dict:
    """Per state ``(delivered, held, pushed, exit box)``: the least phases (``which`` 0) or travel (1) to it.

    ``order``: only the picks of the object next in it.
    """
    problem = pairs.problem

    def expand(state):
        delivered, held, pushed, where = state
        for key, (d, h, p) in skeleton_moves(problem, delivered, held, pushed):
            if order is not None and key[0] == "pick" and order.index(key[1]) != len(delivered):
                continue
            for entry, exit_box in pairs.actions[key].poses:
                yield pairs.step(where, key[0], entry, exit_box)[which], (d, h, p, exit_box)

    start = (frozenset(), problem.holding, frozenset(), None)
    return {state: cost for cost, state in settle(start, expand)}


@pytest.mark.parametrize("holding", [False, True])
@pytest.mark.parametrize("scenario", CASES, ids=[s.name for s in CASES])
def test_the_least_phases_and_travel_are_the_searchs(scenario, holding):
    pairs = _pairs(scenario, scenario.objects[0].id if holding else None)
    problem, graph = pairs.problem, pairs.graph()
    for which, cost in ((0, graph.q.astype(float)), (1, graph.t)):
        searched = _least_by_search(pairs, which)
        layered = graph.least_from_start(cost)
        for sid, (delivered, held, pushed, _, box) in enumerate(graph.states):
            assert layered[sid] == pytest.approx(searched[delivered, held, pushed, box], abs=1e-9)
        done = [c for (d, _, p, _), c in searched.items() if all_done(problem, d, p)]
        if which == 0:
            bound = skeleton(problem, pairs)
            assert bound.phases == 1 + min(done)
            for count, phase in enumerate(bound.earliest):
                assert phase == min(c for (d, *_), c in searched.items() if len(d) == count)
        else:
            assert min_travel(problem, pairs) == pytest.approx(min(done), abs=1e-9)


@pytest.mark.parametrize("scenario", CASES, ids=[s.name for s in CASES])
def test_the_graph_without_poses_has_the_least_phases_between_actions(scenario):
    """Per (delivered, held, pushed, last action): arrival and the phases still needed, as a search finds them."""
    pairs = _pairs(scenario)
    problem, actions = pairs.problem, pairs.graph().actions

    def least_between(last, key) -> int:  # over the exit boxes of ``last`` and the poses of ``key``
        exits = [None] if last is None else {e for _, e in pairs.actions[last].poses}
        return min(pairs.step(w, key[0], en, ex)[0] for w in exits for en, ex in pairs.actions[key].poses)

    def expand(node):
        delivered, held, pushed, last = node
        for key, (d, h, p) in skeleton_moves(problem, delivered, held, pushed):
            yield least_between(last, key), (d, h, p, key)

    searched = {node: cost for cost, node in settle((frozenset(), problem.holding, frozenset(), None), expand)}
    q = actions.q.astype(float)
    arrival = actions.least_from_start(q)
    remaining = actions.least_to_end(q, actions.finished, dead_end=math.inf)
    assert len(actions.nodes) == len(searched)
    for gid, node in enumerate(actions.nodes):
        assert arrival[gid] == searched[node]
        nexts = list(expand(node))
        if all_done(problem, node[0], node[2]):
            assert remaining[gid] == 0 and not nexts
        else:
            assert remaining[gid] == min(c + remaining[actions.nodes.index(nxt)] for c, nxt in nexts)


def test_a_graph_within_n_phases_has_no_longer_step():
    pairs = _pairs(CASES[1])  # the corridor: steps of two and three phases
    graph = pairs.graph()
    assert graph.q.max() >= 3
    short = graph.within(3)
    assert short.q.max() <= 2 and len(short.states) == len(graph.states)
    assert len(short.src) == int((graph.q <= 2).sum())
    assert short.edge_starts[-1] == len(short.src) and short.edge_starts == sorted(short.edge_starts)
    assert graph.within(int(graph.q.max()) + 1) is graph


@pytest.mark.parametrize("scenario", CASES[2:], ids=[s.name for s in CASES[2:]])
def test_a_graph_in_order_has_the_paths_that_pick_in_that_order(scenario):
    """The least phases to each state over the graph without the picks out of order, as a search in that order."""
    pairs = _pairs(scenario)
    graph = pairs.graph()
    order = [o.id for o in scenario.objects][::-1]
    in_order = graph.in_order(order)
    assert len(in_order.states) == len(graph.states) and len(in_order.src) < len(graph.src)
    searched = _least_by_search(pairs, 0, order)
    layered = in_order.least_from_start(in_order.q.astype(float))
    for sid, (delivered, held, pushed, _, box) in enumerate(graph.states):
        assert layered[sid] == searched.get((delivered, held, pushed, box), math.inf)
    picked = [graph.states[d][3][1] for d in in_order.dst if graph.states[d][3][0] == "pick"]
    assert picked and set(picked) <= set(order)
