"""The expert's optimum is the env's: an exhaustive search over the env's own rules never beats the MILP.

The env's motion and arm rules are the planner's model stated exactly
(``docs/design.md``, "The env's rules are the planner's model"), so SCIP's proof of
optimality is a proof for the env. Checked here against an independent brute-force
planner (:mod:`exhaustive`: the paper's action model, the env's rule functions for
everything geometric, uniform-cost search of the task cost) on single-object
scenarios of every family that has them, corridors and diagonal gaps drawn on
purpose, and two and three objects, on a 0.1 m lattice: the planner's plan with
``extra_phases=6`` (the least task cost over every plan with up to six phases more
than the fewest) costs no more than the search's optimum, and every one of its
actions is accepted by the env.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from drawn_rooms import corridor_room, diagonal_room, random_room
from exhaustive import W1, Exhaustive, plan_eq1, plan_task_cost

import expert
from expert.milp.grid import DiagonalPlane, Grid, move_regions
from fetchcarry_env.actions import Lattice
from fetchcarry_env.env import FetchCarryPushEnv
from fetchcarry_env.families import get_family
from fetchcarry_env.rules import move_blockers, move_refusal
from fetchcarry_env.scenario import Scenario

RESOLUTION = 0.1  # metres: the default postures' ranges (15 cm forward, 10 cm lateral) still hold lattice points


def _family(name: str, seed: int) -> Callable[[], Scenario]:
    return lambda: get_family(name).sample(np.random.default_rng(seed))


def _drawn(maker: Callable, seed: int, name: str) -> Callable[[], Scenario]:
    return lambda: maker(np.random.default_rng(seed), f"{name}-{seed}")


CASES = {  # name: the scenario (single objects of every family with them, layouts drawn on purpose, 2-3 objects)
    "basic-0": _family("basic", 0),
    "push-0": _family("push", 0),
    "corridor-0": _family("corridor", 0),
    "turned-room-1": _family("turned-room", 1),
    "turned-corridor-1": _family("turned-corridor", 1),
    "objects-1-0": _family("objects-1", 0),
    "objects-1-1": _family("objects-1", 1),  # the env's 1 mm reach tolerance beat the planner here
    "unseen-layouts-2": _family("unseen-layouts", 2),
    "corridor-room-0": _drawn(corridor_room, 0, "corridor"),
    "corridor-room-2": _drawn(corridor_room, 2, "corridor"),
    "corridor-room-5": _drawn(corridor_room, 5, "corridor"),
    "diagonal-gap-0": _drawn(diagonal_room, 0, "diagonal"),
    "diagonal-gap-1": _drawn(diagonal_room, 1, "diagonal"),
    "diagonal-gap-4": _drawn(diagonal_room, 4, "diagonal"),
    "diagonal-gap-5": _drawn(diagonal_room, 5, "diagonal"),
    "room-2": _drawn(random_room, 2, "room"),
    "objects-2-0": _family("objects-2", 0),
    "multi-2-0": _family("multi-2", 0),
}
SLOW = {  # the slowest: 2 to 6 s of search each
    "push-1": _family("push", 1),
    "perturbed-0": _family("perturbed", 0),
    "unseen-layouts-0": _family("unseen-layouts", 0),  # two objects, a piece of clutter, walls
    "training-0": _family("training", 0),
    "objects-3-0": _family("objects-3", 0),
}


def _cases() -> list:
    return [pytest.param(name, make, id=name) for name, make in CASES.items()] + [
        pytest.param(name, make, id=name, marks=pytest.mark.slow) for name, make in SLOW.items()
    ]


@pytest.mark.parametrize(("name", "make"), _cases())
def test_no_plan_the_env_allows_beats_the_planner_s_optimum(name: str, make: Callable[[], Scenario]) -> None:
    scenario = make()
    env = FetchCarryPushEnv(scenario=scenario, resolution=RESOLUTION)
    lattice = env.lattice
    assert lattice == Lattice.over(scenario.area, RESOLUTION)
    result = expert.plan(scenario, lattice=lattice, extra_phases=6, time_limit=120)
    optimum = Exhaustive(scenario, lattice).solve()
    assert result.status == "optimal" and optimum is not None, (result.status, optimum)
    cost = _task_cost_of(scenario, result)
    assert optimum.cost >= cost - 1e-6, (name, optimum, cost)
    assert not (optimum.phases < len(result.phases) and optimum.cost < cost), (optimum.phases, len(result.phases))
    Exhaustive(scenario, lattice).replay(optimum)  # the search's plan is the env's, step by step
    _executes(env, scenario, result)


def _task_cost_of(scenario: Scenario, result) -> float:
    """The plan's task cost, checked against its objective: Eq. 1 plus W1 for each object and step is the task cost.

    (A plan's ``objective`` is Eq. 1 of its phases, or, once the planner reports the
    task's cost itself, that cost: either must agree with the phases.)
    """
    phases = result.phases
    task, eq1 = plan_task_cost(scenario, phases), plan_eq1(scenario, phases)
    assert all(math.dist(o.start, o.goal) > 1e-3 for o in scenario.objects)  # nothing delivered at the start
    assert eq1 + W1 * len(scenario.objects) * (len(phases) - 1) == pytest.approx(task, abs=1e-9)
    assert math.isclose(result.objective, eq1, abs_tol=1e-6) or math.isclose(result.objective, task, abs_tol=1e-6)
    return task


def _executes(env: FetchCarryPushEnv, scenario: Scenario, result) -> None:
    """The planner's plan, action by action through ``step``: every action accepted, every object delivered."""
    env.reset(seed=0)
    info = {}
    for action in expert.plan_to_actions(result, scenario, env.lattice):
        _obs, _reward, _terminated, _truncated, info = env.step(action.to_array())
        assert info["invalid_action"] is None, (action, info["invalid_action"])
    assert info["is_success"]
    env.close()


@pytest.mark.parametrize("name", ["push-0", "corridor-room-0", "diagonal-gap-4", "multi-2-0"])
def test_the_env_s_move_rule_is_the_model_s_eq_18(name: str) -> None:
    """move_refusal against the planner's regions (the default grid: octagons, the area's domain), pair by pair."""
    scenario = {**CASES, **SLOW}[name]()
    lattice = Lattice.over(scenario.area, RESOLUTION)
    radius = scenario.robot.radius
    grid = Grid.for_area(lattice, scenario.area, radius)
    walls = [rect for _, rect in move_blockers(scenario)]
    regions = [move_regions(grid, rect, radius) for rect in walls]
    rng = np.random.default_rng(5)
    cells = [tuple(c) for c in rng.integers(0, lattice.shape, size=(6000, 2)).tolist()]
    allowed = refused = 0
    for a, b in zip(cells[::2], cells[1::2], strict=True):
        model = all(grid.domain.contains(*c) for c in (a, b)) and all(
            any(_holds(p, a) and _holds(p, b) for p in planes) for planes in regions
        )
        env = move_refusal(scenario, lattice, lattice.point(*a), lattice.point(*b)) is None
        assert env == model, (a, b)
        allowed, refused = allowed + env, refused + (not env)
    assert allowed > 20 and refused > 20


def _holds(plane, cell: tuple[int, int]) -> bool:
    """Whether a region of ``move_regions`` holds the lattice point (the planner's integer test)."""
    if isinstance(plane, DiagonalPlane):
        return plane.holds_at(*cell)
    return plane.holds(cell[plane.axis])
