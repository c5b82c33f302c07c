"""The paper's Section V cases as families: fixed tables and start, no jitter but what each case draws.

The planner benchmark's scenarios (:data:`fetchcarry_env.families.PAPER_FAMILIES`). Units are metres.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fetchcarry_env.geometry import Point, Rect, discs_overlap
from fetchcarry_env.scenario import Clutter, DeliveryObject, Obstacle, Robot, Scenario, Table, check_rules
from fetchcarry_env.worlds.base import EXTENT, TABLE_HEIGHT, point_near, square, uniform
from fetchcarry_env.worlds.rooms import PUSH_PATTERNS, neighbour

PAPER_TABLE_SIZE = 0.6  # metres: the V-B and V-C tables, centred at (2, 2) and (4, 4)
PAPER_OBSTACLE_SIZE = 0.4  # metres: the V-B obstacle
PAPER_AREAS: dict[str, tuple[float, float, float, float]] = {
    "I": (0.4, 1.4, 0.4, 1.4),
    "II": (2.4, 3.6, 2.4, 3.6),
    "III": (0.4, 1.6, 2.4, 3.6),
    "IV": (2.4, 3.6, 0.4, 1.6),
    "V": (4.6, 5.6, 4.6, 5.6),
}
"""V-B: where the obstacle's centre is drawn, ``(min x, max x, min y, max y)`` in metres."""
PAPER_CORRIDOR_WIDTH = 1.0  # metres: IV-F's L corridor
PAPER_MULTI_TABLES: tuple[Point, ...] = ((2.0, 2.0), (4.0, 4.0), (4.0, 1.0))  # metres: table centres
PAPER_MULTI_TABLE_SIZE = 0.7  # metres
PAPER_COVER_SIZE = 0.08  # metres: the block standing on each goal of the covered cases


def _paper_tables() -> tuple[Table, Table]:
    return (
        Table("table_src", square((2.0, 2.0), PAPER_TABLE_SIZE), TABLE_HEIGHT),
        Table("table_goal", square((4.0, 4.0), PAPER_TABLE_SIZE), TABLE_HEIGHT),
    )


def draw_paper_basic(rng: np.random.Generator, area: str = "I") -> Scenario:
    """V-B: one object from (2, 2) to (4, 4), start (0, 0), one 0.4 m obstacle drawn in ``area`` (I-V)."""
    x0, x1, y0, y1 = PAPER_AREAS[area]
    tables = _paper_tables()
    while True:
        box = square((uniform(rng, x0, x1), uniform(rng, y0, y1)), PAPER_OBSTACLE_SIZE)
        clear_of_tables = not any(box.overlaps_rect(t.rect.inflate(0.05)) for t in tables)
        if clear_of_tables and box.distance_to_point((0.0, 0.0)) > 0.3 and EXTENT.contains_rect(box):
            break
    return Scenario(
        name=f"vb-{area}",
        area=EXTENT,
        robot=Robot((0.0, 0.0)),
        tables=tables,
        obstacles=(Obstacle("box", box),),
        objects=(DeliveryObject("bottle", (2.0, 2.0), (4.0, 4.0)),),
    )


def draw_paper_push(rng: np.random.Generator, pattern: str = "A") -> Scenario:
    """V-C: as V-B without the obstacle, a 0.12-0.16 m block on the goal and the Table I ``pattern`` (A-E).

    The neighbours are :func:`draw_push`'s (bars 0.10 m high, small blocks 0.08 m, sliding up
    to ``NEIGHBOUR_OFFSET``), except that a bar stands centred on its side of the block.
    Two bars stand on opposite sides (on adjacent sides their ends would overlap).
    """
    bars, blocks = PUSH_PATTERNS[pattern]
    goal = (4.0 + uniform(rng, -0.03, 0.03), 4.0 + uniform(rng, -0.03, 0.03))
    size = uniform(rng, 0.12, 0.16)
    block = square((goal[0] + uniform(rng, -0.02, 0.02), goal[1] + uniform(rng, -0.02, 0.02)), size)
    clutter = [Clutter("block", block)]
    first = int(rng.integers(4))
    sides = [first, (first + 2) % 4, (first + 1) % 4, (first + 3) % 4]
    if rng.integers(2):
        sides[2], sides[3] = sides[3], sides[2]
    if bars < 2:
        sides = [first, *[s for s in (int(v) for v in rng.permutation(4)) if s != first]]
    for k in range(bars + blocks):
        long_bar = k < bars
        item_id = f"obs1_{k + 1}" if long_bar else f"obs2_{k + 1}"
        clutter.append(neighbour(rng, block, sides[k], long_bar, item_id, centred_bar=True))
    return Scenario(
        name=f"vc-{pattern}",
        area=EXTENT,
        robot=Robot((0.0, 0.0)),
        tables=_paper_tables(),
        objects=(DeliveryObject("bottle", (2.0, 2.0), goal),),
        clutter=tuple(clutter),
    )


def draw_paper_corridor(rng: np.random.Generator) -> Scenario:
    """IV-F (Fig. 4): a 6 x 6 m room whose free floor is an L corridor 1 m wide; tables jittered by 5 cm."""
    w = PAPER_CORRIDOR_WIDTH
    jitter = tuple(float(v) for v in rng.uniform(-0.05, 0.05, size=4))
    source = Table("table_src", Rect(2.4 + jitter[0], 0.0, 2.9 + jitter[0], 0.35), TABLE_HEIGHT)
    goal = Table("table_goal", Rect(6.0 - 0.35, 4.6 + jitter[1], 6.0, 5.1 + jitter[1]), TABLE_HEIGHT)
    obj = DeliveryObject(
        "bottle", (source.rect.center[0] + jitter[2] / 2, 0.2), (5.8, goal.rect.center[1] + jitter[3] / 2)
    )
    return Scenario(
        name="corridor-L",
        area=Rect(0.0, 0.0, 6.0, 6.0),
        robot=Robot((0.5, 0.5)),
        tables=(source, goal),
        obstacles=(Obstacle("wall_inner", Rect(0.0, w, 6.0 - w, 6.0)),),  # everything but the L
        objects=(obj,),
    )


def draw_paper_multi(rng: np.random.Generator, count: int = 2) -> Scenario:
    """``count`` objects, each from one of three 0.7 m tables at (2, 2), (4, 4), (4, 1) to another; start (0, 0)."""
    tables = tuple(
        Table(f"table_{k + 1}", square(c, PAPER_MULTI_TABLE_SIZE), TABLE_HEIGHT)
        for k, c in enumerate(PAPER_MULTI_TABLES)
    )
    taken: list[list[Point]] = [[] for _ in tables]
    objects = []
    for k in range(count):
        src = int(rng.integers(len(tables)))
        dst = (src + 1 + int(rng.integers(len(tables) - 1))) % len(tables)
        start = _paper_spot(rng, tables[src].rect, taken[src])
        goal = _paper_spot(rng, tables[dst].rect, taken[dst])
        objects.append(DeliveryObject(f"object_{k + 1}", start, goal))
    return Scenario(name=f"multi-{count}", area=EXTENT, robot=Robot((0.0, 0.0)), tables=tables, objects=tuple(objects))


def _paper_spot(rng: np.random.Generator, table: Rect, taken: list[Point]) -> Point:
    """A point within 0.12 m of an edge of ``table`` (reachable from that side), 8 cm from the others."""
    inner = table.inflate(-0.06)
    while True:
        p = (uniform(rng, inner.min_x, inner.max_x), uniform(rng, inner.min_y, inner.max_y))
        near_edge = min(p[0] - table.min_x, table.max_x - p[0], p[1] - table.min_y, table.max_y - p[1]) <= 0.12
        if near_edge and not any(discs_overlap(p, 0.04, q, 0.04) for q in taken):
            taken.append(p)
            return p


def draw_paper_covered(rng: np.random.Generator, count: int = 2) -> Scenario:
    """``count`` objects as in :func:`draw_paper_multi`, a 0.08 m block on every goal: each is pushed first."""
    while True:
        base = draw_paper_multi(rng, count)
        clutter = tuple(
            Clutter(f"block_{k + 1}", square(point_near(rng, o.goal, 0.01), PAPER_COVER_SIZE))
            for k, o in enumerate(base.objects)
        )
        scenario = replace(base, name=f"covered-{count}", clutter=clutter)
        if not check_rules(scenario):
            return scenario
