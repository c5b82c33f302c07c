"""The skeleton graph's layered minima (``expert.milp.skeleton_graph``) equal a priority-queue search.

The reference here is Dijkstra's search (``expert.milp.bounds.settle``) over the same
steps, the way the bounds were computed before they shared one graph: per skeleton state
the least phases and travel from the start, and per state without poses the least phases
from the start and to the end.
"""

from __future__ import annotations

import math
from itertools import pairwise

import numpy as np
import pytest

from expert.milp import skeleton_graph
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

    ``order``: a pick of one of its objects only once the one before it is delivered (``add_pick_order``'s rule).
    """
    problem = pairs.problem
    before = dict(zip(order[1:], order[:-1], strict=True)) if order else {}

    def expand(state):
        delivered, held, pushed, where = state
        for key, (d, h, p) in skeleton_moves(problem, delivered, held, pushed):
            if key[0] == "pick" and key[1] in before and before[key[1]] not in delivered:
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
    assert graph.q.max() >= 3 and graph.by_destination.size  # known before: the shorter graph filters it
    short = graph.within(3)
    assert short.q.max() <= 2 and len(short.states) == len(graph.states)
    assert len(short.src) == int((graph.q <= 2).sum())
    assert short.edge_starts[-1] == len(short.src) and short.edge_starts == sorted(short.edge_starts)
    anew = [e0 + np.argsort(short.dst[e0:e1], kind="stable") for e0, e1 in pairwise(short.edge_starts)]
    assert np.array_equal(short.by_destination, np.concatenate(anew))  # the full graph's order, filtered
    assert graph.within(int(graph.q.max()) + 1) is graph


ORDERS = {  # name: (whether the first object is held at the start, the order of the object ids)
    "reversed": (False, lambda ids: ids[::-1]),
    "held one first": (True, lambda ids: ids),
    "first left out, an unknown id skipped": (False, lambda ids: ["not_an_object", *ids[:0:-1]]),
}
IN_ORDER = [(CASES[2], name) for name in ORDERS] + [(CASES[3], "reversed")]  # two objects, one held: no order to keep


@pytest.mark.parametrize(("scenario", "orders"), IN_ORDER, ids=[f"{s.name}-{name}" for s, name in IN_ORDER])
def test_a_graph_in_order_has_the_paths_that_pick_in_that_order(scenario, orders):
    """The least phases to each state over the graph without the picks out of order, as a search in that order."""
    holding, order_of = ORDERS[orders]
    ids = [o.id for o in scenario.objects]
    pairs = _pairs(scenario, ids[0] if holding else None)
    graph, order = pairs.graph(), order_of(ids)
    in_order = graph.in_order(order, pairs.problem.deliver)
    searched = _least_by_search(pairs, 0, [o for o in order if o in pairs.problem.deliver])
    layered = in_order.least_from_start(in_order.q.astype(float))
    for sid, (delivered, held, pushed, _, box) in enumerate(graph.states):
        assert layered[sid] == searched.get((delivered, held, pushed, box), math.inf)
    assert len(in_order.states) == len(graph.states) and len(in_order.src) < len(graph.src)
    assert np.isinf(layered).any() and not np.isinf(graph.least_from_start(graph.q.astype(float))).any()


def _same_graph(a, b) -> None:
    assert a.level_starts == b.level_starts and a.edge_starts == b.edge_starts
    for name in ("src", "dst", "q", "t", "finished", "delivered", "placed", "slot", "group"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.states == b.states and a.slots == b.slots and a.actions.nodes == b.actions.nodes


@pytest.mark.parametrize("scenario", CASES, ids=[s.name for s in CASES])
def test_a_level_listed_in_chunks_is_the_same_graph(monkeypatch, scenario):
    """A level's edges are listed a chunk of sources at a time (memory, the deadline): the chunks change nothing."""
    whole = _pairs(scenario).graph()
    monkeypatch.setattr(skeleton_graph, "CHUNK_EDGES", 7)
    _same_graph(_pairs(scenario).graph(), whole)


def test_sets_wider_than_62_bits_are_python_integers(monkeypatch):
    """More than 62 objects or pieces (the format allows 64 and 256): the same graph in Python integers."""
    scenario = CASES[3]  # two objects covered: pushes too
    whole = _pairs(scenario).graph()
    monkeypatch.setattr(skeleton_graph.Alphabet, "dtype", property(lambda self: object))
    wide = _pairs(scenario).graph()
    assert wide.delivered_set.dtype == object
    _same_graph(wide, whole)
    codes = skeleton_graph._codes([(np.array([1, 1, 2]), 1 << 70), (np.array([3, 4, 3]), 1 << 70)])
    assert len(set(codes.tolist())) == 3


def test_a_graph_past_its_budget_of_edges_is_refused_before_it_is_listed():
    pairs = _pairs(CASES[2])  # three objects
    edges = len(pairs.graph().src)
    small = PairCosts(pairs.problem, max_edges=edges - 1)
    with pytest.raises(skeleton_graph.GraphTooLarge, match=f"{edges - 1:,} edges"):
        small.graph()
    assert len(PairCosts(pairs.problem, max_edges=edges).graph().src) == edges
