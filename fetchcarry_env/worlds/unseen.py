"""``unseen-layouts``: topologies no training family draws, for the benchmark's held-out layouts.

One of four, uniformly (one or two objects, as the training families have, but one
in rooms-in-row, where the expert plans two in more than 10 s a third of the time;
each goal covered by a block with probability 0.5):

=============  =====================================================================
layout         what it draws
=============  =====================================================================
t-junction     a corridor across the whole floor, 1.2-1.6 m wide, with a table at each
               end, and a stem 0.75-1.1 m wide from the start up to its middle
u-corridor     a U: up the left leg from the start, along the top past a table against
               the top wall, down the right leg to a table at its end (1.3-1.6 m wide)
rooms-in-row   three rooms in a row joined by doors 0.85-1.0 m wide, lined up; a table in each
dead-end       a room with the source table and a corridor 1.1-1.4 m wide leaving it
               that ends at the goal table
=============  =====================================================================

The training families draw one room (basic, push, multi) or two rooms joined by a
straight or L-shaped corridor (corridor); none of these has a junction, a U, three
rooms in a chain or a table at the end of a corridor. Units are metres.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np

from fetchcarry_env.geometry import Point, Rect
from fetchcarry_env.scenario import Scenario, Table
from fetchcarry_env.worlds.base import (
    EXTENT,
    TABLE_HEIGHT,
    covers,
    deliveries,
    name,
    point_near,
    robot,
    uniform,
    walls_around,
)

END_TABLE_DEPTH = 0.5  # metres: a table standing across the end of a corridor
SIDE_GAP = 0.03  # metres between such a table and the corridor's side walls
COVER_CHANCE = 0.5

Floor = tuple[list[Rect], list[Rect], Point]  # free rectangles, table rectangles, start


def _end_table(corridor: Rect, end: str, depth: float = END_TABLE_DEPTH) -> Rect:
    """A table across ``corridor``'s ``end`` (``"-x"``, ``"+x"``, ``"-y"``, ``"+y"``), touching no wall."""
    g = SIDE_GAP
    if end == "-x":
        return Rect(corridor.min_x + g, corridor.min_y + g, corridor.min_x + depth, corridor.max_y - g)
    if end == "+x":
        return Rect(corridor.max_x - depth, corridor.min_y + g, corridor.max_x - g, corridor.max_y - g)
    if end == "-y":
        return Rect(corridor.min_x + g, corridor.min_y + g, corridor.max_x - g, corridor.min_y + depth)
    return Rect(corridor.min_x + g, corridor.max_y - depth, corridor.max_x - g, corridor.max_y - g)


def t_junction(rng: np.random.Generator) -> Floor:
    width, stem = uniform(rng, 1.2, 1.6), uniform(rng, 0.75, 1.1)
    y = uniform(rng, 2.0, EXTENT.max_y - width - 0.3)
    x = uniform(rng, 1.5, 3.5 - stem)
    bar = Rect(EXTENT.min_x, y, EXTENT.max_x, y + width)
    trunk = Rect(x, EXTENT.min_y, x + stem, y)
    start = (x + stem / 2, EXTENT.min_y + 0.5)
    return [bar, trunk], [_end_table(bar, "-x"), _end_table(bar, "+x")], start


def u_corridor(rng: np.random.Generator) -> Floor:
    width = uniform(rng, 1.3, 1.6)
    right = EXTENT.max_x - uniform(rng, 0.0, 1.5)
    top = EXTENT.max_y - uniform(rng, 0.0, 1.0)
    left_leg = Rect(EXTENT.min_x, EXTENT.min_y, EXTENT.min_x + width, top)
    bar = Rect(EXTENT.min_x, top - width, right, top)
    right_leg = Rect(right - width, EXTENT.min_y, right, top)
    middle = uniform(rng, EXTENT.min_x + width + 0.5, right - width - 1.1)
    shelf = Rect(middle, top - END_TABLE_DEPTH, middle + 0.6, top - SIDE_GAP)
    start = (EXTENT.min_x + width / 2, EXTENT.min_y + 0.5)
    return [left_leg, bar, right_leg], [shelf, _end_table(right_leg, "-y")], start


def rooms_in_row(rng: np.random.Generator) -> Floor:
    height = uniform(rng, 4.0, EXTENT.max_y - EXTENT.min_y)
    span = (EXTENT.max_x - EXTENT.min_x - 0.4) / 3
    rooms = [
        Rect(
            EXTENT.min_x + k * (span + 0.2), EXTENT.min_y, EXTENT.min_x + k * (span + 0.2) + span, EXTENT.min_y + height
        )
        for k in range(3)
    ]
    doors = []
    line = uniform(rng, EXTENT.min_y + 0.3, EXTENT.min_y + height - 1.3)  # the doors line up (within 0.1 m)
    for a, b in itertools.pairwise(rooms):
        y = line + uniform(rng, -0.1, 0.1)
        doors.append(Rect(a.max_x, y, b.min_x, y + uniform(rng, 0.85, 1.0)))
    tables = []
    for k, room in enumerate(rooms):
        size = uniform(rng, 0.6, 0.7)
        low = room.min_y + (1.6 if k == 0 else 0.6)
        cy = uniform(rng, low + size / 2, room.max_y - 0.6 - size / 2)
        cx = room.center[0] + uniform(rng, -0.1, 0.1)
        tables.append(Rect.around((cx, cy), size / 2, size / 2))
    start = (rooms[0].center[0], EXTENT.min_y + 0.5)
    return [*rooms, *doors], tables, start


def dead_end(rng: np.random.Generator) -> Floor:
    side = uniform(rng, 3.5, 4.2)
    room = Rect(EXTENT.min_x, EXTENT.min_y, EXTENT.min_x + side, EXTENT.min_y + side)
    width, length = uniform(rng, 1.1, 1.4), uniform(rng, 1.5, EXTENT.max_x - room.max_x)
    if rng.random() < 0.5:
        y = uniform(rng, room.min_y + 1.2, room.max_y - width)
        corridor = Rect(room.max_x, y, room.max_x + length, y + width)
        end = _end_table(corridor, "+x")
    else:
        x = uniform(rng, room.min_x + 1.2, room.max_x - width)
        corridor = Rect(x, room.max_y, x + width, room.max_y + length)
        end = _end_table(corridor, "+y")
    source = Rect.around(point_near(rng, room.center, 0.3), 0.3, 0.3)
    start = (EXTENT.min_x + 0.5, EXTENT.min_y + 0.5)
    return [room, corridor], [source, end], start


LAYOUTS: dict[str, Callable[[np.random.Generator], Floor]] = {
    "t-junction": t_junction,
    "u-corridor": u_corridor,
    "rooms-in-row": rooms_in_row,
    "dead-end": dead_end,
}


def draw_unseen(rng: np.random.Generator, layout: str | None = None) -> Scenario:
    """One of :data:`LAYOUTS` (uniformly, or ``layout``), one or two objects, the goal covered half the time."""
    layout = layout or tuple(LAYOUTS)[int(rng.integers(len(LAYOUTS)))]
    free, rects, start = LAYOUTS[layout](rng)
    tables = [Table(f"table_{k + 1}", r, TABLE_HEIGHT) for k, r in enumerate(rects)]
    objects = deliveries(rng, tables, 1 if layout == "rooms-in-row" else 1 + int(rng.integers(2)))
    return Scenario(
        name=name(layout, rng),
        area=EXTENT,
        robot=robot(rng, point_near(rng, start, 0.1)),
        tables=tuple(tables),
        obstacles=tuple(walls_around(EXTENT, free)),
        objects=tuple(objects),
        clutter=tuple(covers(rng, objects, COVER_CHANCE)),
    )
