"""The least number of straight moves (:mod:`expert.milp.moves`) is the exact breadth-first count over lattice points.

The reference search walks lattice point by lattice point with the env's move rule
(:class:`tests.expert.exhaustive.Exhaustive`), apart from the signature graph it checks.
The fallback's routes (:mod:`expert.approach`) take that many moves, each one the env allows.
"""

from __future__ import annotations

import itertools

import gymnasium as gym
import numpy as np
import pytest
from drawn_rooms import corridor_room, diagonal_room
from exhaustive import Exhaustive

import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
from expert.approach import Routes, fewest_moves_order
from expert.milp.moves import UNREACHABLE, problem_moves
from expert.milp.problem import prepare
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_corridor
from fetchcarry_env.regions import IndexBox
from fetchcarry_env.rules import move_refusal
from fetchcarry_env.scenario import Scenario


def point_moves(search: Exhaustive, source: np.ndarray) -> np.ndarray:
    """``(N,)``: least moves from any base of the mask ``source`` (or the start, when it is None) to every base."""
    least = np.full(len(search.cells), UNREACHABLE, dtype=np.int64)
    least[source] = 0
    frontier, moves = np.flatnonzero(source), 0
    while frontier.size:
        moves += 1
        reached = np.zeros(len(search.cells), dtype=bool)
        for n in frontier:
            reached |= search.reachable(int(n))
        reached &= least == UNREACHABLE
        least[reached] = moves
        frontier = np.flatnonzero(reached)
    return least


def scenarios() -> list[Scenario]:
    rng = np.random.default_rng(11)
    return [draw_paper_corridor(rng), corridor_room(rng, "corridor"), diagonal_room(rng, "diagonal")]


@pytest.mark.parametrize("scenario", scenarios(), ids=lambda s: s.name)
def test_least_moves_from_the_start_and_between_boxes_are_the_point_by_point_count(scenario: Scenario):
    lattice = Lattice.over(scenario.area, 0.25)
    problem = prepare(scenario, lattice)
    moves, search = problem_moves(problem), Exhaustive(scenario, lattice)
    cells = [IndexBox(int(i), int(i), int(j), int(j)) for i, j in search.cells]

    start = len(search.cells)
    from_start = 1 + point_moves(search, search.reachable(start)) if search.reachable(start).any() else None
    assert from_start is not None
    from_start[(search.cells == problem.start_index).all(axis=1)] = 0  # the start's own lattice point: no move
    assert [moves.steps(problem, None, cell) for cell in cells] == from_start.tolist()
    assert from_start.max() >= 3  # the rooms need detours: not the one-or-two-move case

    rng = np.random.default_rng(0)
    for _ in range(40):
        lo = rng.integers(0, np.array(lattice.shape) - 1, size=(2, 2))
        size = rng.integers(0, 4, size=(2, 2))
        a, b = (IndexBox(int(i), int(i + di), int(j), int(j + dj)) for (i, j), (di, dj) in zip(lo, size, strict=True))
        inside_a = np.array([a.contains(int(i), int(j)) for i, j in search.cells], dtype=bool)
        inside_b = np.array([b.contains(int(i), int(j)) for i, j in search.cells], dtype=bool)
        if not inside_a.any():
            continue
        expected = int(point_moves(search, inside_a)[inside_b].min()) if inside_b.any() else UNREACHABLE
        assert moves.steps(problem, a, b) == expected, (a, b)


@pytest.mark.parametrize("seed", [1, 8])
def test_a_route_takes_the_least_moves_and_the_env_accepts_each(seed: int):
    """The fallback's legs (:class:`expert.approach.Routes`) in an apartment: the least moves, each allowed."""
    env = gym.make("FetchCarryPush-v0", family="apartment")
    env.reset(seed=seed)
    scenario, lattice = env.unwrapped.scenario, env.unwrapped.lattice
    routes = Routes(scenario, lattice)
    start = scenario.robot.start
    least = routes.least(start)
    rng = np.random.default_rng(seed)
    ends = rng.choice(np.flatnonzero(least < UNREACHABLE), size=25, replace=False)
    assert least[ends].max() >= 4  # across the rooms
    for end in ends:
        route = routes.route(start, int(end))
        assert route is not None and len(route) == least[end] and route[-1] == routes.point(int(end))
        for a, b in itertools.pairwise([start, *route]):
            assert move_refusal(scenario, lattice, a, b) is None, (a, b)


def test_the_fewest_moves_order_is_the_best_of_every_order():
    env = gym.make("FetchCarryPush-v0", family="apartment")
    env.reset(seed=8)
    scenario, lattice = env.unwrapped.scenario, env.unwrapped.lattice
    routes = Routes(scenario, lattice)
    start = scenario.robot.start
    jobs = {o.id: (o.start, o.goal) for o in scenario.objects}

    def moves(order) -> int:
        total = int(routes.moves.from_point(start)[routes.region(jobs[order[0]][0])].min())
        for i, j in itertools.pairwise(order):
            total += routes.moves.between(routes.region(jobs[i][1]), routes.region(jobs[j][0]))
        return total

    every = {order: moves(order) for order in itertools.permutations(jobs)}
    chosen = tuple(fewest_moves_order(routes, start, jobs))
    assert sorted(chosen) == sorted(jobs) and every[chosen] == min(every.values())
    assert max(every.values()) > min(every.values())  # the order matters here
