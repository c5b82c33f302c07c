"""Leaving a corner gap: a base the MILP cannot plan from, and the straight move out of it.

The MILP keeps the base out of every table and obstacle grown by the radius into a
square (the paper's Eq. 18), which is stricter than the disc the env tests: a base that
a move stopped at a contact near a corner can stand where the planner has no plan from.
:func:`escape_move` finds the nearest lattice point outside every grown square that one
straight move reaches without a contact. Units are metres.
"""

from __future__ import annotations

from dataclasses import replace

from expert.milp.grid import point_in_region
from expert.plans import Phase
from expert.tracking import PlannedAction
from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.observation import WorldState
from fetchcarry_env.rules import move_refusal
from fetchcarry_env.scenario import Scenario

ESCAPE_RADIUS_CELLS = 4  # lattice cells: how far an escape from a corner gap may go


def corner_gap(scenario: Scenario, world: WorldState) -> str | None:
    """The id of a table or obstacle whose square grown by the radius holds the base (the MILP's Eq. 18), or None."""
    radius = scenario.robot.radius
    for item in (*scenario.tables, *scenario.obstacles):
        if not any(point_in_region(world.base, item.rect, radius, region) for region in range(4)):
            return item.id
    return None


def escape_move(scenario: Scenario, world: WorldState, lattice: Lattice) -> PlannedAction | None:
    """A move to the nearest lattice point outside every grown square that the env's move rule allows, or None."""
    for cell in cells_around(lattice, lattice.index(world.base), ESCAPE_RADIUS_CELLS):
        base = lattice.point(*cell)
        if (
            scenario.area.contains_disc(base, scenario.robot.radius)
            and corner_gap(scenario, replace(world, base=base)) is None
            and move_refusal(scenario, lattice, world.base, base) is None
        ):
            objects = {k: v[:2] for k, v in world.objects.items()}
            expected = Phase(base, world.heading, "move", holding=world.holding, objects=objects)
            return PlannedAction(Action(cell, world.heading, 0, Mode.MOVE), expected)
    return None


def cells_around(lattice: Lattice, cell: tuple[int, int], r: int) -> list[tuple[int, int]]:
    """Lattice points within ``r`` cells of ``cell``, nearest first (``cell`` itself first)."""
    nx, ny = lattice.shape
    around = [
        (cell[0] + i, cell[1] + j)
        for i in range(-r, r + 1)
        for j in range(-r, r + 1)
        if i * i + j * j <= r * r and 0 <= cell[0] + i < nx and 0 <= cell[1] + j < ny
    ]
    return sorted(around, key=lambda c: ((c[0] - cell[0]) ** 2 + (c[1] - cell[1]) ** 2, c))
