"""The training families' rooms: the paper's V-B (``basic``), V-C (``push``), IV-F (``corridor``), ``multi``.

Each draws from the generator it is given, so a seed gives the same scenario bit for bit;
``mixed``, ``training`` and ``perturbed`` combine them. Units are metres.
"""

from __future__ import annotations

import numpy as np

from fetchcarry_env.geometry import Point, Rect
from fetchcarry_env.scenario import Clutter, DeliveryObject, Obstacle, Scenario, Table
from fetchcarry_env.worlds.base import EXTENT, TABLE_HEIGHT, free_spot, name, point_near, robot, square, uniform
from fetchcarry_env.worlds.perturbed import DISTRACTORS_FACTOR, GEOMETRIC_FACTORS, LAYOUT, perturb


def draw_basic(rng: np.random.Generator, obstacle: bool = True) -> Scenario:
    """The paper's V-B layout, jittered: tables at about (2, 2) and (4, 4), start about (0, 0)."""
    source_center = point_near(rng, (2.0, 2.0), 0.4)
    goal_center = point_near(rng, (4.0, 4.0), 0.4)
    source = Table("table_src", square(source_center, 0.6), TABLE_HEIGHT)
    goal = Table("table_goal", square(goal_center, 0.6), TABLE_HEIGHT)
    start = point_near(rng, (0.0, 0.0), 0.3)
    obj = DeliveryObject("bottle", point_near(rng, source_center, 0.15), point_near(rng, goal_center, 0.15))
    obstacles = ()
    if obstacle:
        for _ in range(50):
            box = square((uniform(rng, 0.2, 5.0), uniform(rng, 0.2, 5.0)), 0.4)
            clear = all(not box.overlaps_rect(t.rect.inflate(0.3)) for t in (source, goal))
            if clear and box.distance_to_point(start) > 0.5:
                obstacles = (Obstacle("box_1", box),)
                break
    return Scenario(
        name=name("basic", rng),
        area=EXTENT,
        robot=robot(rng, start),
        tables=(source, goal),
        obstacles=obstacles,
        objects=(obj,),
    )


# ---------------------------------------------------------------------- push (V-C)
PUSH_PATTERNS: dict[str, tuple[int, int]] = {"A": (1, 0), "B": (0, 1), "C": (2, 0), "D": (0, 2), "E": (1, 1)}
"""The paper's Table I: how many long bars (Obs 1) and small blocks (Obs 2) stand by the pushed piece."""


def draw_push(rng: np.random.Generator, pattern: str | None = None) -> Scenario:
    """V-C: a block on the goal, with the neighbours of a Table I pattern around it on the goal table."""
    pattern = pattern or "ABCDE"[int(rng.integers(5))]
    bars, blocks = PUSH_PATTERNS[pattern]
    base = draw_basic(rng, obstacle=bool(rng.integers(2)))
    goal_table = Table("table_goal", square(base.tables[1].rect.center, 0.8), TABLE_HEIGHT)
    cx, cy = goal_table.rect.center
    goal = point_near(rng, (cx, cy), 0.08)
    obj = DeliveryObject("bottle", base.objects[0].start, goal)
    size = uniform(rng, 0.10, 0.16)
    clutter = [Clutter("block", square(point_near(rng, goal, 0.02), size), 0.10)]
    sides = [int(s) for s in rng.permutation(4)]  # which side of the block each neighbour stands on
    for k in range(bars + blocks):
        side = sides[k % 4]
        long_bar = k < bars
        clutter.append(
            neighbour(rng, clutter[0].rect, side, long_bar, f"bar_{k + 1}" if long_bar else f"small_{k + 1}")
        )
    return Scenario(
        name=name(f"push{pattern}", rng),
        area=base.area,
        robot=base.robot,
        tables=(base.tables[0], goal_table),
        obstacles=base.obstacles,
        objects=(obj,),
        clutter=tuple(clutter),
    )


NEIGHBOUR_OFFSET = 0.05  # metres: how far a neighbour's centre may slide along the side it stands by
BAR_HEIGHT = 0.10  # metres: Obs 1, the long bar
SMALL_BLOCK_HEIGHT = 0.08  # metres: Obs 2, the small block


def neighbour(
    rng: np.random.Generator, block: Rect, side: int, long_bar: bool, item_id: str, centred_bar: bool = False
) -> Clutter:
    """A bar (0.36 x 0.05 m) or a small block (0.06 m) standing 3-8 cm off one side of ``block``.

    Its centre slides up to ``NEIGHBOUR_OFFSET`` along that side; with ``centred_bar`` a bar
    does not slide (it is centred on the side and draws no offset).
    """
    gap = uniform(rng, 0.03, 0.08)
    length, width = (0.36, 0.05) if long_bar else (0.06, 0.06)
    cx, cy = block.center
    offset = 0.0 if long_bar and centred_bar else uniform(rng, -NEIGHBOUR_OFFSET, NEIGHBOUR_OFFSET)
    if side in (0, 2):  # +x / -x side: a bar standing along y
        x = block.max_x + gap + width / 2 if side == 0 else block.min_x - gap - width / 2
        rect = Rect.around((x, cy + offset), width / 2, length / 2)
    else:
        y = block.max_y + gap + width / 2 if side == 1 else block.min_y - gap - width / 2
        rect = Rect.around((cx + offset, y), length / 2, width / 2)
    return Clutter(item_id, rect, BAR_HEIGHT if long_bar else SMALL_BLOCK_HEIGHT)


# ---------------------------------------------------------------------- corridor (IV-F)
def draw_corridor(rng: np.random.Generator, shape: str | None = None) -> Scenario:
    """Two rooms joined by an L-shaped or a straight corridor; everything else is obstacles."""
    shape = shape or ("L", "straight")[int(rng.integers(2))]
    width = uniform(rng, 0.75, 1.0)
    low = uniform(rng, -0.5, 1.9 - width)  # bottom edge of the horizontal leg
    start = point_near(rng, (-0.2, -0.2), 0.2)
    source = Table("table_src", square(point_near(rng, (0.9, 1.0), 0.15), 0.6), TABLE_HEIGHT)
    if shape == "L":
        leg = uniform(rng, 3.3, 5.2 - width)  # left edge of the vertical leg
        obstacles = [
            Rect(-1.0, 2.0, 3.0, 6.0),  # above room A
            Rect(2.0, low + width, leg, 2.0),  # inner corner, below the top block
            Rect(3.0, 2.0, leg, 3.0),  # between the top block and room B
            Rect(leg + width, low, 6.0, 3.0),  # right of the vertical leg
        ]
        if low > -1.0:
            obstacles.append(Rect(2.0, -1.0, 6.0, low))  # below the horizontal leg
        goal_center = point_near(rng, (4.6, 5.0), 0.2)
    else:
        obstacles = [Rect(2.0, low + width, 4.0, 6.0)]
        if low > -1.0:
            obstacles.append(Rect(2.0, -1.0, 4.0, low))
        goal_center = point_near(rng, (5.0, 1.0), 0.2)
    goal = Table("table_goal", square(goal_center, 0.6), TABLE_HEIGHT)
    obj = DeliveryObject("bottle", point_near(rng, source.rect.center, 0.15), point_near(rng, goal_center, 0.15))
    return Scenario(
        name=name(f"corridor{shape}", rng),
        area=EXTENT,
        robot=robot(rng, start),
        tables=(source, goal),
        obstacles=tuple(Obstacle(f"wall_{k + 1}", r) for k, r in enumerate(obstacles) if r.is_proper),
        objects=(obj,),
    )


# ---------------------------------------------------------------------- multi
def draw_multi(rng: np.random.Generator, count: int | None = None) -> Scenario:
    """2 to 4 objects spread over two or three tables, each to be carried to another table."""
    count = count or int(rng.integers(2, 5))
    centers = [(2.0, 2.0), (4.0, 4.0), (4.0, 1.0)][: 2 + int(rng.integers(2))]
    tables = [
        Table(f"table_{k + 1}", square(point_near(rng, c, 0.3), 0.7), TABLE_HEIGHT) for k, c in enumerate(centers)
    ]
    taken: dict[int, list[tuple[Point, float]]] = {k: [] for k in range(len(tables))}
    objects = []
    for k in range(count):
        src = int(rng.integers(len(tables)))
        dst = (src + 1 + int(rng.integers(len(tables) - 1))) % len(tables)
        start = free_spot(rng, tables[src].rect, 0.035, 0.02, taken[src])
        taken[src].append((start, 0.035))
        goal = free_spot(rng, tables[dst].rect, 0.035, 0.02, taken[dst])
        taken[dst].append((goal, 0.035))
        objects.append(DeliveryObject(f"object_{k + 1}", start, goal))
    return Scenario(
        name=name(f"multi{count}", rng),
        area=EXTENT,
        robot=robot(rng, point_near(rng, (0.0, 0.0), 0.3)),
        tables=tuple(tables),
        objects=tuple(objects),
    )


# ---------------------------------------------------------------------- mixtures
def draw_mixed(rng: np.random.Generator) -> Scenario:
    """One of basic, push, corridor and multi, uniformly."""
    return (draw_basic, draw_push, draw_corridor, draw_multi)[int(rng.integers(4))](rng)


def draw_training(rng: np.random.Generator) -> Scenario:
    """One of basic, push, corridor and multi-2 (two objects), uniformly: what learners are trained on."""
    choice = int(rng.integers(4))
    if choice == 3:
        return draw_multi(rng, 2)
    return (draw_basic, draw_push, draw_corridor)[choice](rng)


def draw_perturbed(rng: np.random.Generator, factors: frozenset[str] = GEOMETRIC_FACTORS) -> Scenario:
    """A ``training`` scenario (the ``iid`` kind) with its tables and start moved and distractors added.

    ``factors``: only these of the two (:mod:`fetchcarry_env.worlds.perturbed`); the scenario is named after
    the family of the factors (``perturbed``, ``perturbed-layout``, ``perturbed-distractors``, ``perturbed-physics``).
    """
    return perturb(rng, draw_training(rng), factors, PERTURBED_FAMILIES[frozenset(factors)])


PERTURBED_FAMILIES = {  # the geometric factors of each perturbed family
    GEOMETRIC_FACTORS: "perturbed",
    frozenset({LAYOUT}): "perturbed-layout",
    frozenset({DISTRACTORS_FACTOR}): "perturbed-distractors",
    frozenset(): "perturbed-physics",
}
