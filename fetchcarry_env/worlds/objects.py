"""``objects-k``: k objects over several tables in one room sized to fit them (k = 1 .. 12).

The room is a square of side ``4 + 0.375 k`` metres (4.4 m for one object, 7 m, the
whole extent, from eight) in the corner of the shared extent; its floor is cut into 3 x 3 cells, the robot
starts in the corner cell and ``min(6, 2 + k // 2)`` tables (0.6-0.8 m squares,
jittered within their cells) stand in as many of the other eight cells, drawn at random.
Each object goes from one table to another. Half of the scenarios have clutter on the
goals: each goal is then covered by a small block with probability 0.4 (at least one
is). Units are metres.
"""

from __future__ import annotations

import numpy as np

from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import Clutter, Scenario, Table
from fetchcarry_env.worlds.base import (
    COVER_HEIGHT,
    COVER_SIZE,
    EXTENT,
    TABLE_HEIGHT,
    covers,
    deliveries,
    name,
    point_near,
    robot,
    square,
    uniform,
)

MAX_OBJECTS = 12  # the largest k
COVERED_SHARE = 0.5  # of the scenarios, those with clutter on goals
COVER_CHANCE = 0.4  # each goal's, in those
ROOM_SIDE = (4.0, 0.375)  # metres: the room's side is ROOM_SIDE[0] + ROOM_SIDE[1] * k
CELLS = 3  # per side of the room
TABLE_SIZE = (0.6, 0.8)  # metres
AISLE = 0.3  # metres kept between a table's jitter and its cell's edge


def room_side(count: int) -> float:
    """The side of the square room that holds ``count`` objects (metres, at most the extent's)."""
    return min(EXTENT.max_x - EXTENT.min_x, ROOM_SIDE[0] + ROOM_SIDE[1] * count)


def table_count(count: int) -> int:
    """How many tables hold ``count`` objects: two, and one more per two objects, at most six."""
    return min(6, 2 + count // 2)


def draw_objects(rng: np.random.Generator, count: int) -> Scenario:
    """``count`` objects over :func:`table_count` tables in a room of side :func:`room_side`."""
    if not 1 <= count <= MAX_OBJECTS:
        raise ValueError(f"objects-k draws 1 to {MAX_OBJECTS} objects, got {count}")
    side = room_side(count)
    area = Rect(EXTENT.min_x, EXTENT.min_y, EXTENT.min_x + side, EXTENT.min_y + side)
    cell = side / CELLS
    free_cells = [(i, j) for i in range(CELLS) for j in range(CELLS) if (i, j) != (0, 0)]
    chosen = rng.choice(len(free_cells), size=table_count(count), replace=False)
    tables = []
    for k, index in enumerate(sorted(int(c) for c in chosen)):
        i, j = free_cells[index]
        size = uniform(rng, *TABLE_SIZE)
        jitter = min(0.3, max(0.0, (cell - size) / 2 - AISLE))
        centre = (area.min_x + (i + 0.5) * cell, area.min_y + (j + 0.5) * cell)
        tables.append(Table(f"table_{k + 1}", square(point_near(rng, centre, jitter), size), TABLE_HEIGHT))
    objects = deliveries(rng, tables, count)
    clutter: list[Clutter] = []
    if rng.random() < COVERED_SHARE:
        clutter = covers(rng, objects, COVER_CHANCE)
        if not clutter:
            goal = objects[int(rng.integers(len(objects)))]
            block = square(point_near(rng, goal.goal, 0.01), uniform(rng, *COVER_SIZE))
            clutter = [Clutter(f"block_{goal.id}", block, COVER_HEIGHT)]
    start = point_near(rng, (area.min_x + cell / 2, area.min_y + cell / 2), 0.2)
    return Scenario(
        name=name(f"objects{count}", rng),
        area=area,
        robot=robot(rng, start),
        tables=tuple(tables),
        objects=tuple(objects),
        clutter=tuple(clutter),
    )
