"""``apartment``: two to four rooms joined by doors and corridors of varied width, procedural from a seed.

The shared extent (7 x 7 m) is split into a 2 x 2 grid of rooms (two rooms: side by
side) separated by a wall (0.2 m) or a corridor (0.8-1.4 m long), one choice per split
line. With three rooms one of the three the robot does not start in is walled up. Rooms
next to each other are joined through a door or a corridor 0.7-1.1 m wide: a spanning
tree of the rooms, plus (four rooms) the fourth link with probability 0.3, which makes a
loop. Three to six tables (0.6-0.75 m squares) stand in the rooms, clear of the doors
and of each other by a passage; two to five objects each go from one table to another,
and each goal is covered by a small block with probability 0.35. The robot starts in
the bottom-left room. Units are metres.
"""

from __future__ import annotations

import numpy as np

from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import Scenario, Table
from fetchcarry_env.worlds.base import (
    EXTENT,
    TABLE_HEIGHT,
    covers,
    deliveries,
    name,
    point_near,
    robot,
    square,
    uniform,
    walls_around,
)

WALL = 0.2  # metres: a wall between two rooms
CORRIDOR_LENGTH = (0.8, 1.4)  # metres
DOOR_WIDTH = (0.7, 1.1)  # metres: doors and corridors
MIN_ROOM = 2.6  # metres: a room's smallest side
TABLES = (3, 6)  # inclusive
OBJECTS = (2, 5)  # inclusive
TABLE_SIZE = (0.6, 0.75)  # metres
PASSAGE = 0.6  # metres kept between two tables, and between a table and a door's mouth
COVER_CHANCE = 0.35
LOOP_CHANCE = 0.3

# Rooms of the 2 x 2 grid: 0 bottom-left (the start), 1 bottom-right, 2 top-left, 3 top-right.
LINKS = ((0, 1), (2, 3), (0, 2), (1, 3))  # pairs of rooms next to each other (x gap, x gap, y gap, y gap)


def draw_apartment(rng: np.random.Generator) -> Scenario:
    """Two to four rooms, three to six tables, two to five objects, clutter on some goals."""
    count = int(rng.integers(2, 5))
    gaps = [WALL if rng.random() < 0.5 else uniform(rng, *CORRIDOR_LENGTH) for _ in range(2)]
    split_x = uniform(rng, EXTENT.min_x + MIN_ROOM, EXTENT.max_x - MIN_ROOM - gaps[0])
    split_y = uniform(rng, EXTENT.min_y + MIN_ROOM, EXTENT.max_y - MIN_ROOM - gaps[1])
    columns = [(EXTENT.min_x, split_x), (split_x + gaps[0], EXTENT.max_x)]
    rows = [(EXTENT.min_y, split_y), (split_y + gaps[1], EXTENT.max_y)] if count > 2 else [(EXTENT.min_y, EXTENT.max_y)]
    grid = {
        k: Rect(
            columns[k % 2][0],
            rows[min(k // 2, len(rows) - 1)][0],
            columns[k % 2][1],
            rows[min(k // 2, len(rows) - 1)][1],
        )
        for k in range(2 * len(rows))
    }
    if count == 3:
        del grid[1 + int(rng.integers(3))]
    rooms = dict(grid)
    links = [pair for pair in LINKS if pair[0] in rooms and pair[1] in rooms]
    if count == 4:
        dropped = int(rng.integers(4))
        links = [pair for k, pair in enumerate(links) if k != dropped or rng.random() < LOOP_CHANCE]
    doors = [_door(rng, rooms[a], rooms[b]) for a, b in links]
    tables = _tables(rng, list(rooms.values()), doors)
    objects = deliveries(rng, tables, int(rng.integers(OBJECTS[0], OBJECTS[1] + 1)))
    start_room = rooms[0]
    start = point_near(rng, (start_room.min_x + 0.6, start_room.min_y + 0.6), 0.2)
    return Scenario(
        name=name(f"apartment{count}", rng),
        area=EXTENT,
        robot=robot(rng, start),
        tables=tuple(tables),
        obstacles=tuple(walls_around(EXTENT, [*rooms.values(), *doors])),
        objects=tuple(objects),
        clutter=tuple(covers(rng, objects, COVER_CHANCE)),
    )


def _door(rng: np.random.Generator, a: Rect, b: Rect) -> Rect:
    """The free rectangle joining rooms ``a`` and ``b`` across the gap between them (a door or a corridor)."""
    width = uniform(rng, *DOOR_WIDTH)
    if a.max_x <= b.min_x:  # side by side: the opening runs along x
        low, high = max(a.min_y, b.min_y) + 0.1, min(a.max_y, b.max_y) - 0.1 - width
        y = uniform(rng, low, high)
        return Rect(a.max_x, y, b.min_x, y + width)
    low, high = max(a.min_x, b.min_x) + 0.1, min(a.max_x, b.max_x) - 0.1 - width
    x = uniform(rng, low, high)
    return Rect(x, a.max_y, x + width, b.min_y)


def _tables(rng: np.random.Generator, rooms: list[Rect], doors: list[Rect]) -> list[Table]:
    """Three to six tables in the rooms, clear of each other and of the doors by :data:`PASSAGE`."""
    wanted = int(rng.integers(TABLES[0], TABLES[1] + 1))
    rects: list[Rect] = []
    for _ in range(40 * wanted):
        if len(rects) == wanted:
            break
        room = rooms[int(rng.integers(len(rooms)))]
        size = uniform(rng, *TABLE_SIZE)
        inner = room.inflate(-(size / 2 + uniform(rng, 0.05, 0.6)))
        if not inner.is_proper:
            continue
        rect = square((uniform(rng, inner.min_x, inner.max_x), uniform(rng, inner.min_y, inner.max_y)), size)
        start_corner = square((rooms[0].min_x + 0.6, rooms[0].min_y + 0.6), 1.2)
        blocked = [r.inflate(PASSAGE) for r in (*rects, *doors)] + [start_corner]
        if not any(rect.overlaps_rect(b) for b in blocked):
            rects.append(rect)
    return [Table(f"table_{k + 1}", r, TABLE_HEIGHT) for k, r in enumerate(rects)]
