"""The planner benchmark's scenarios: the paper's Section V, rebuilt as seeded scenario generators.

Each generator draws from the ``numpy.random.Generator`` it is given, so a seed gives
the same scenario bit for bit. They build :class:`~fetchcarry_env.scenario.Scenario`
records directly (independent of the env's families) and return only scenarios that
pass every rule of ``docs/scenario-format.md``.

V-B (basic performance): start (0, 0), 0.6 m tables centred at (2, 2) (the object) and
(4, 4) (its goal), one 0.4 m square obstacle whose centre is drawn uniformly in one of
five areas (the paper's Fig. 5 is not in our copy of the paper; these are ours):

====  ==========================  ====================================================
area  centre drawn in             where that is
====  ==========================  ====================================================
I     [0.4, 1.4] x [0.4, 1.4]     between the start and the source table
II    [2.4, 3.6] x [2.4, 3.6]     between the two tables, on the straight line
III   [0.4, 1.6] x [2.4, 3.6]     beside the source table, on the far side from (4, 0)
IV    [2.4, 3.6] x [0.4, 1.6]     the mirror image of III across the diagonal
V     [4.6, 5.6] x [4.6, 5.6]     behind the goal table, off every short path
====  ==========================  ====================================================

V-C (push-aside): as V-B without the obstacle, plus a block (0.12-0.16 m) standing on
the goal and the neighbours of the paper's Table I pattern: Obs 1 is a long bar
(0.36 x 0.05 m) that blocks the side it stands on, Obs 2 a small block (0.06 m); each
stands 3-8 cm off a different side of the block. Pattern A: one bar; B: one small
block; C: two bars; D: two small blocks; E: one of each.

IV-F (L corridor, the paper's Fig. 4): a 6 x 6 m room whose free floor is an L-shaped
corridor 1 m wide from the start at the bottom-left, along the bottom and up the
right; the rest is obstacles. The source table stands in the corridor's lower leg, the
goal table at the top of the upper leg.

Multi (2-6 objects): tables at (2, 2), (4, 4) and (4, 1), each object on one
table and its goal on another. Covered (2, 3 objects): the same with a 0.08 m block
standing on every goal, so every delivery needs a push first.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from fetchcarry_env.geometry import Point, Rect, discs_overlap
from fetchcarry_env.scenario import Clutter, DeliveryObject, Obstacle, Robot, Scenario, Table, check_rules

ROOM = Rect(-1.0, -1.0, 6.0, 6.0)  # metres: the floor of V-B, V-C and the multi-object cases
TABLE_SIZE = 0.6  # metres, the paper's V-B tables
OBSTACLE_SIZE = 0.4  # metres, the paper's V-B obstacle
AREAS: dict[str, tuple[float, float, float, float]] = {
    "I": (0.4, 1.4, 0.4, 1.4),
    "II": (2.4, 3.6, 2.4, 3.6),
    "III": (0.4, 1.6, 2.4, 3.6),
    "IV": (2.4, 3.6, 0.4, 1.6),
    "V": (4.6, 5.6, 4.6, 5.6),
}
PATTERNS: dict[str, tuple[int, int]] = {"A": (1, 0), "B": (0, 1), "C": (2, 0), "D": (0, 2), "E": (1, 1)}
"""The paper's Table I: (long bars, small blocks) beside the block on the goal."""

Generator = Callable[[np.random.Generator], Scenario]


def _square(center: Point, size: float) -> Rect:
    return Rect.around(center, size / 2, size / 2)


def _tables() -> tuple[Table, Table]:
    return Table("table_src", _square((2.0, 2.0), TABLE_SIZE)), Table("table_goal", _square((4.0, 4.0), TABLE_SIZE))


def _checked(scenario: Scenario) -> Scenario:
    problems = check_rules(scenario)
    if problems:
        raise AssertionError(f"benchmark scenario {scenario.name!r} breaks the rules: {problems}")
    return scenario


def basic(area: str, rng: np.random.Generator) -> Scenario:
    """V-B: one object from (2, 2) to (4, 4), one obstacle drawn in ``area`` (I-V)."""
    x0, x1, y0, y1 = AREAS[area]
    tables = _tables()
    while True:
        box = _square((float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1))), OBSTACLE_SIZE)
        clear_of_tables = not any(box.overlaps_rect(t.rect.inflate(0.05)) for t in tables)
        if clear_of_tables and box.distance_to_point((0.0, 0.0)) > 0.3 and ROOM.contains_rect(box):
            break
    return _checked(
        Scenario(
            name=f"vb-{area}",
            area=ROOM,
            robot=Robot((0.0, 0.0)),
            tables=tables,
            obstacles=(Obstacle("box", box),),
            objects=(DeliveryObject("bottle", (2.0, 2.0), (4.0, 4.0)),),
        )
    )


def push(pattern: str, rng: np.random.Generator) -> Scenario:
    """V-C: a block on the goal and the Table I ``pattern`` (A-E) of neighbours around it."""
    bars, blocks = PATTERNS[pattern]
    goal = (4.0 + float(rng.uniform(-0.03, 0.03)), 4.0 + float(rng.uniform(-0.03, 0.03)))
    size = float(rng.uniform(0.12, 0.16))
    block = _square((goal[0] + float(rng.uniform(-0.02, 0.02)), goal[1] + float(rng.uniform(-0.02, 0.02))), size)
    clutter = [Clutter("block", block)]
    first = int(rng.integers(4))
    # Two bars stand on opposite sides (on adjacent sides their ends would overlap); blocks take the rest.
    sides = [first, (first + 2) % 4, (first + 1) % 4, (first + 3) % 4]
    if rng.integers(2):
        sides[2], sides[3] = sides[3], sides[2]
    if bars < 2:
        sides = [first, *[s for s in (int(v) for v in rng.permutation(4)) if s != first]]
    for k in range(bars + blocks):
        long_bar = k < bars
        clutter.append(_neighbour(rng, block, sides[k], long_bar, f"obs1_{k + 1}" if long_bar else f"obs2_{k + 1}"))
    return _checked(
        Scenario(
            name=f"vc-{pattern}",
            area=ROOM,
            robot=Robot((0.0, 0.0)),
            tables=_tables(),
            objects=(DeliveryObject("bottle", (2.0, 2.0), goal),),
            clutter=tuple(clutter),
        )
    )


def _neighbour(rng: np.random.Generator, block: Rect, side: int, long_bar: bool, item_id: str) -> Clutter:
    """Obs 1 (a 0.36 x 0.05 m bar across ``side``) or Obs 2 (a 0.06 m block), 3-8 cm off that side."""
    gap = float(rng.uniform(0.03, 0.08))
    length, width = (0.36, 0.05) if long_bar else (0.06, 0.06)
    cx, cy = block.center
    offset = 0.0 if long_bar else float(rng.uniform(-0.04, 0.04))
    if side in (0, 2):  # +x / -x side: stands along y
        x = block.max_x + gap + width / 2 if side == 0 else block.min_x - gap - width / 2
        rect = Rect.around((x, cy + offset), width / 2, length / 2)
    else:
        y = block.max_y + gap + width / 2 if side == 1 else block.min_y - gap - width / 2
        rect = Rect.around((cx + offset, y), length / 2, width / 2)
    table = _square((4.0, 4.0), TABLE_SIZE)
    rect = Rect(
        max(rect.min_x, table.min_x),
        max(rect.min_y, table.min_y),
        min(rect.max_x, table.max_x),
        min(rect.max_y, table.max_y),
    )
    return Clutter(item_id, rect, 0.10)


CORRIDOR_WIDTH = 1.0  # metres


def corridor(rng: np.random.Generator) -> Scenario:
    """IV-F: an L-shaped corridor (Fig. 4), the rest of the room obstacles; tables jittered by 5 cm."""
    room = Rect(0.0, 0.0, 6.0, 6.0)
    w = CORRIDOR_WIDTH
    obstacles = (Obstacle("wall_inner", Rect(0.0, w, 6.0 - w, 6.0)),)  # everything but the L
    jitter = tuple(float(v) for v in rng.uniform(-0.05, 0.05, size=4))
    source = Table("table_src", Rect(2.4 + jitter[0], 0.0, 2.9 + jitter[0], 0.35))
    goal = Table("table_goal", Rect(6.0 - 0.35, 4.6 + jitter[1], 6.0, 5.1 + jitter[1]))
    obj = DeliveryObject(
        "bottle", (source.rect.center[0] + jitter[2] / 2, 0.2), (5.8, goal.rect.center[1] + jitter[3] / 2)
    )
    return _checked(
        Scenario(
            name="corridor-L",
            area=room,
            robot=Robot((0.5, 0.5)),
            tables=(source, goal),
            obstacles=obstacles,
            objects=(obj,),
        )
    )


MULTI_TABLES = ((2.0, 2.0), (4.0, 4.0), (4.0, 1.0))  # metres: table centres of the multi-object cases
MULTI_TABLE_SIZE = 0.7  # metres


def multi(count: int, rng: np.random.Generator) -> Scenario:
    """``count`` objects, each from one of three tables to another."""
    tables = tuple(Table(f"table_{k + 1}", _square(c, MULTI_TABLE_SIZE)) for k, c in enumerate(MULTI_TABLES))
    taken: list[list[Point]] = [[] for _ in tables]
    objects = []
    for k in range(count):
        src = int(rng.integers(len(tables)))
        dst = (src + 1 + int(rng.integers(len(tables) - 1))) % len(tables)
        start = _spot(rng, tables[src].rect, taken[src])
        goal = _spot(rng, tables[dst].rect, taken[dst])
        objects.append(DeliveryObject(f"object_{k + 1}", start, goal))
    return _checked(
        Scenario(name=f"multi-{count}", area=ROOM, robot=Robot((0.0, 0.0)), tables=tables, objects=tuple(objects))
    )


def _spot(rng: np.random.Generator, table: Rect, taken: list[Point]) -> Point:
    """A point within 0.12 m of an edge of ``table`` (reachable from that side), 8 cm from the others."""
    inner = table.inflate(-0.06)
    while True:
        p = (float(rng.uniform(inner.min_x, inner.max_x)), float(rng.uniform(inner.min_y, inner.max_y)))
        near_edge = min(p[0] - table.min_x, table.max_x - p[0], p[1] - table.min_y, table.max_y - p[1]) <= 0.12
        if near_edge and not any(discs_overlap(p, 0.04, q, 0.04) for q in taken):
            taken.append(p)
            return p


COVER_SIZE = 0.08  # metres: the block standing on each goal in the covered cases


def covered(count: int, rng: np.random.Generator) -> Scenario:
    """``count`` objects as in :func:`multi`, and a block (0.08 m) standing on every goal: each is pushed first."""
    while True:
        base = multi(count, rng)
        clutter = tuple(
            Clutter(
                f"block_{k + 1}",
                _square(
                    (o.goal[0] + float(rng.uniform(-0.01, 0.01)), o.goal[1] + float(rng.uniform(-0.01, 0.01))),
                    COVER_SIZE,
                ),
                0.10,
            )
            for k, o in enumerate(base.objects)
        )
        scenario = Scenario(
            name=f"covered-{count}",
            area=base.area,
            robot=base.robot,
            tables=base.tables,
            objects=base.objects,
            clutter=clutter,
        )
        if not check_rules(scenario):
            return scenario
