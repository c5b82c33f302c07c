"""Seeded scenario families: the paper's layouts and variations of them.

Every family draws from the ``numpy.random.Generator`` it is given (the env passes its
``np_random``, seeded by ``reset(seed=...)``), so a seed gives the same scenario bit for
bit. A family only returns scenarios that pass every rule of ``docs/scenario-format.md`` and
whose every object and goal the robot can reach from at least one side
(:mod:`fetchcarry_env.reachability`); a layout that fails is drawn again.

=========  ==============================================================================
family     what it draws
=========  ==============================================================================
basic      the paper's V-B: a source and a goal table, one 0.4 m obstacle at random,
           with the tables, the object and the start jittered
push       V-C: clutter standing on the goal, plus long bars and small blocks around it
           that limit the push directions (the paper's Table I patterns A-E, Fig. 3)
corridor   IV-F: two rooms joined by an L-shaped or straight corridor; the rest of the
           room is obstacles
multi      2 to 4 objects between two or three tables (``multi-2`` ... ``multi-4``: fixed)
mixed      one of basic, push, corridor and multi, uniformly
training   one of basic, push, corridor and multi-2, uniformly: the families learners are
           trained on (one and two objects; the benchmark's ``iid`` split cycles through
           the same four)
=========  ==============================================================================

Held-out layouts (for evaluation, never drawn by the families above): ``turned-room``
and ``turned-corridor`` draw a basic or push room, or a corridor, and turn the whole
scenario a quarter turn counter-clockwise about the centre of the extent
(:func:`turn_quarter`). The robot then starts in the bottom-right corner, the rooms and
corridors run the other way, and no training family ever draws such a layout; the
lattice maps onto itself, so every action stays on it. The training families' draws do
not change (the same seed gives the same scenario as before these families existed).

The paper's Section V cases (the planner benchmark's scenarios, :data:`PAPER_FAMILIES`;
not in :data:`FAMILY_NAMES`, which ``mixed``, ``training`` and the command line list):
fixed tables and start, no jitter but what each case draws.

==================  ====================================================================
family              what it draws
==================  ====================================================================
paper-basic-I..V    V-B: start (0, 0), 0.6 m tables at (2, 2) and (4, 4), one 0.4 m
                    obstacle whose centre is drawn in one of five areas (the paper's Fig. 5
                    is not in our copy; these are ours): I between the start and the source
                    table, II between the tables, III beside the source table on the far
                    side from (4, 0), IV its mirror image, V behind the goal table
paper-push-A..E     V-C: V-B without the obstacle, a 0.12-0.16 m block on the goal and the
                    Table I neighbours of :func:`draw_push` (bars centred on their side)
paper-corridor      IV-F (Fig. 4): a 6 x 6 m room whose free floor is an L corridor 1 m wide
paper-multi-2..6    2-6 objects, each from one of three 0.7 m tables to another
paper-covered-2, 3  as paper-multi, with a 0.08 m block on every goal (each pushed first)
==================  ====================================================================

All families share one extent, so that ``mixed`` and a fixed action lattice work.
Units are metres.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from typing import TypeVar

import numpy as np

from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect, discs_overlap, heading_vector, to_world_frame
from fetchcarry_env.kinematics import (
    hand_blocker,
    push_contact,
    push_headings,
    push_stroke,
    reaches,
    swept_rect,
)
from fetchcarry_env.observation import Capacity
from fetchcarry_env.reachability import FreeSpace, unreachable_targets
from fetchcarry_env.scenario import Clutter, DeliveryObject, Obstacle, Posture, Robot, Scenario, Table, check_rules
from fetchcarry_env.worlds.apartment import draw_apartment
from fetchcarry_env.worlds.base import EXTENT, TABLE_HEIGHT, free_spot, name, point_near, robot, square, uniform
from fetchcarry_env.worlds.ladder import draw_ladder
from fetchcarry_env.worlds.objects import MAX_OBJECTS, draw_objects
from fetchcarry_env.worlds.perturbed import perturb
from fetchcarry_env.worlds.physics import HOME, PhysicsVariation
from fetchcarry_env.worlds.unseen import draw_unseen

PUSH_RESOLUTION = 0.05  # metres: the default lattice; strokes are checked on it
MAX_ATTEMPTS = 200  # layouts drawn before a family gives up (never reached in tests)

Sampler = Callable[[np.random.Generator], Scenario]
T = TypeVar("T")


@dataclass(frozen=True)
class Family:
    """A named scenario generator, the floor extent its scenarios lie in, and what the env needs for them.

    ``capacity`` is the observation's room that holds every scenario the family draws
    (the env's default for the family; a draw that would not fit is drawn again), and
    ``physics`` the physics variation the env applies to its episodes, if any
    (:mod:`fetchcarry_env.worlds.physics`).
    """

    name: str
    description: str
    extent: Rect
    draw: Sampler
    capacity: Capacity = field(default_factory=Capacity)
    physics: PhysicsVariation | None = None

    def sample(self, rng: np.random.Generator) -> Scenario:
        """A valid, workable scenario drawn from ``rng`` that fits :attr:`capacity`."""
        for _ in range(MAX_ATTEMPTS):
            scenario = self.draw(rng)
            if (
                self.capacity.fits(scenario)
                and not check_rules(scenario)
                and not unreachable_targets(scenario)
                and _pushes_possible(scenario)
            ):
                return scenario
        raise RuntimeError(f"family {self.name!r} drew no workable scenario in {MAX_ATTEMPTS} attempts")


# ---------------------------------------------------------------------- helpers
_square, _uniform, _point_near, _robot, _name = square, uniform, point_near, robot, name


def _pushes_possible(scenario: Scenario) -> bool:
    """Every piece of clutter on a goal can be pushed off it in at least one direction."""
    space: FreeSpace | None = None
    for item in scenario.clutter:
        covered = [(o.goal, o.radius) for o in scenario.objects if item.rect.overlaps_disc(o.goal, o.radius)]
        if not covered:
            continue
        space = space or FreeSpace(scenario)
        if not any(_push_works(scenario, space, item, direction, covered) for direction in HEADINGS):
            return False
    return True


def _push_works(
    scenario: Scenario, space: FreeSpace, item: Clutter, direction: Heading, covered: list[tuple[Point, float]]
) -> bool:
    """The paper's s/o/q preprocessing as one test.

    The push stays on the table, sweeps over nothing else, and some base pose reaches its contact.
    """
    stroke = push_stroke(item.rect, direction, covered, PUSH_RESOLUTION)
    swept = swept_rect(item.rect, direction, stroke)
    table = scenario.table_under_rect(item.rect)
    if table is None or not table.rect.contains_rect(swept):
        return False
    others = [c.rect for c in scenario.clutter if c.id != item.id]
    discs = [(o.start, o.radius) for o in scenario.objects] + [(o.goal, o.radius) for o in scenario.objects]
    if any(swept.overlaps_rect(r) for r in others):
        return False
    if any(swept.overlaps_disc(c, r) and not item.rect.overlaps_disc(c, r) for c, r in discs):
        return False
    contact = push_contact(item.rect, direction)
    if not _hand_fits(scenario, item, contact):
        return False
    ux, uy = heading_vector(direction)
    for heading in push_headings(direction):
        for posture in scenario.robot.postures:
            for base in _bases_reaching(contact, heading, posture):
                end = (base[0] + ux * stroke, base[1] + uy * stroke)
                hand_end = (contact[0] + ux * stroke, contact[1] + uy * stroke)
                if (
                    space.reachable(base)
                    and space.reachable(end)
                    and reaches(posture, base, heading, contact)
                    and _arm_clear_through_stroke(scenario, item, (base, end, contact, hand_end))
                ):
                    return True
    return False


def _hand_fits(scenario: Scenario, item: Clutter, contact: Point) -> bool:
    """The hand (a cube of ``2 * HAND_HALF_SIZE`` at the push contact) overlaps no other clutter and no object.

    The environment refuses a push without room for the hand behind the piece.
    """
    others = ((c.id, c.rect) for c in scenario.clutter if c.id != item.id)
    return hand_blocker(contact, others, ((o.id, o.start, o.radius) for o in scenario.objects), tol=0.0) is None


def _arm_clear_through_stroke(scenario: Scenario, item: Clutter, points: tuple[Point, ...]) -> bool:
    """Eq. 19 through a push (the paper's q), as the planner models it.

    The bases and hands at both ends of the stroke lie on one side of every obstacle and
    every other piece of clutter, so the arm sweeps across none of them.
    """
    blockers = [o.rect for o in scenario.obstacles] + [c.rect for c in scenario.clutter if c.id != item.id]
    return all(_one_side(rect, points) for rect in blockers)


def _one_side(rect: Rect, points: tuple[Point, ...]) -> bool:
    return (
        all(x >= rect.max_x for x, _ in points)
        or all(x <= rect.min_x for x, _ in points)
        or all(y >= rect.max_y for _, y in points)
        or all(y <= rect.min_y for _, y in points)
    )


def _bases_reaching(point: Point, heading: Heading, posture: Posture) -> list[Point]:
    """Base positions from which ``posture`` at ``heading`` puts the hand on ``point`` (narrowed ranges)."""
    lateral = (posture.lateral[0] + posture.lateral[1]) / 2
    out = []
    for forward in np.linspace(posture.forward[0] + 0.03, posture.forward[1] - 0.03, 4):
        dx, dy = to_world_frame(heading, float(forward), lateral)
        out.append((point[0] - dx, point[1] - dy))
    return out


def _free_spot(
    rng: np.random.Generator, table: Rect, radius: float, margin: float, taken: list[tuple[Point, float]]
) -> Point:
    """A point on ``table`` clear of ``taken`` discs (:func:`fetchcarry_env.worlds.base.free_spot`)."""
    return free_spot(rng, table, radius, margin, taken)


# ---------------------------------------------------------------------- basic (V-B)
def draw_basic(rng: np.random.Generator, obstacle: bool = True) -> Scenario:
    """The paper's V-B layout, jittered: tables at about (2, 2) and (4, 4), start about (0, 0)."""
    source_center = _point_near(rng, (2.0, 2.0), 0.4)
    goal_center = _point_near(rng, (4.0, 4.0), 0.4)
    source = Table("table_src", _square(source_center, 0.6), TABLE_HEIGHT)
    goal = Table("table_goal", _square(goal_center, 0.6), TABLE_HEIGHT)
    start = _point_near(rng, (0.0, 0.0), 0.3)
    obj = DeliveryObject("bottle", _point_near(rng, source_center, 0.15), _point_near(rng, goal_center, 0.15))
    obstacles = ()
    if obstacle:
        for _ in range(50):
            box = _square((_uniform(rng, 0.2, 5.0), _uniform(rng, 0.2, 5.0)), 0.4)
            clear = all(not box.overlaps_rect(t.rect.inflate(0.3)) for t in (source, goal))
            if clear and box.distance_to_point(start) > 0.5:
                obstacles = (Obstacle("box_1", box),)
                break
    return Scenario(
        name=_name("basic", rng),
        area=EXTENT,
        robot=_robot(rng, start),
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
    goal_table = Table("table_goal", _square(base.tables[1].rect.center, 0.8), TABLE_HEIGHT)
    cx, cy = goal_table.rect.center
    goal = _point_near(rng, (cx, cy), 0.08)
    obj = DeliveryObject("bottle", base.objects[0].start, goal)
    size = _uniform(rng, 0.10, 0.16)
    clutter = [Clutter("block", _square(_point_near(rng, goal, 0.02), size), 0.10)]
    sides = [int(s) for s in rng.permutation(4)]  # which side of the block each neighbour stands on
    for k in range(bars + blocks):
        side = sides[k % 4]
        long_bar = k < bars
        clutter.append(
            _neighbour(rng, clutter[0].rect, side, long_bar, f"bar_{k + 1}" if long_bar else f"small_{k + 1}")
        )
    return Scenario(
        name=_name(f"push{pattern}", rng),
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


def _neighbour(
    rng: np.random.Generator, block: Rect, side: int, long_bar: bool, item_id: str, centred_bar: bool = False
) -> Clutter:
    """A bar (0.36 x 0.05 m) or a small block (0.06 m) standing 3-8 cm off one side of ``block``.

    Its centre slides up to ``NEIGHBOUR_OFFSET`` along that side; with ``centred_bar`` a bar
    does not slide (it is centred on the side and draws no offset).
    """
    gap = _uniform(rng, 0.03, 0.08)
    length, width = (0.36, 0.05) if long_bar else (0.06, 0.06)
    cx, cy = block.center
    offset = 0.0 if long_bar and centred_bar else _uniform(rng, -NEIGHBOUR_OFFSET, NEIGHBOUR_OFFSET)
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
    width = _uniform(rng, 0.75, 1.0)
    low = _uniform(rng, -0.5, 1.9 - width)  # bottom edge of the horizontal leg
    start = _point_near(rng, (-0.2, -0.2), 0.2)
    source = Table("table_src", _square(_point_near(rng, (0.9, 1.0), 0.15), 0.6), TABLE_HEIGHT)
    if shape == "L":
        leg = _uniform(rng, 3.3, 5.2 - width)  # left edge of the vertical leg
        obstacles = [
            Rect(-1.0, 2.0, 3.0, 6.0),  # above room A
            Rect(2.0, low + width, leg, 2.0),  # inner corner, below the top block
            Rect(3.0, 2.0, leg, 3.0),  # between the top block and room B
            Rect(leg + width, low, 6.0, 3.0),  # right of the vertical leg
        ]
        if low > -1.0:
            obstacles.append(Rect(2.0, -1.0, 6.0, low))  # below the horizontal leg
        goal_center = _point_near(rng, (4.6, 5.0), 0.2)
    else:
        obstacles = [Rect(2.0, low + width, 4.0, 6.0)]
        if low > -1.0:
            obstacles.append(Rect(2.0, -1.0, 4.0, low))
        goal_center = _point_near(rng, (5.0, 1.0), 0.2)
    goal = Table("table_goal", _square(goal_center, 0.6), TABLE_HEIGHT)
    obj = DeliveryObject("bottle", _point_near(rng, source.rect.center, 0.15), _point_near(rng, goal_center, 0.15))
    return Scenario(
        name=_name(f"corridor{shape}", rng),
        area=EXTENT,
        robot=_robot(rng, start),
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
        Table(f"table_{k + 1}", _square(_point_near(rng, c, 0.3), 0.7), TABLE_HEIGHT) for k, c in enumerate(centers)
    ]
    taken: dict[int, list[tuple[Point, float]]] = {k: [] for k in range(len(tables))}
    objects = []
    for k in range(count):
        src = int(rng.integers(len(tables)))
        dst = (src + 1 + int(rng.integers(len(tables) - 1))) % len(tables)
        start = _free_spot(rng, tables[src].rect, 0.035, 0.02, taken[src])
        taken[src].append((start, 0.035))
        goal = _free_spot(rng, tables[dst].rect, 0.035, 0.02, taken[dst])
        taken[dst].append((goal, 0.035))
        objects.append(DeliveryObject(f"object_{k + 1}", start, goal))
    return Scenario(
        name=_name(f"multi{count}", rng),
        area=EXTENT,
        robot=_robot(rng, _point_near(rng, (0.0, 0.0), 0.3)),
        tables=tuple(tables),
        objects=tuple(objects),
    )


# ---------------------------------------------------------------------- the paper's Section V cases
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
        Table("table_src", _square((2.0, 2.0), PAPER_TABLE_SIZE), TABLE_HEIGHT),
        Table("table_goal", _square((4.0, 4.0), PAPER_TABLE_SIZE), TABLE_HEIGHT),
    )


def draw_paper_basic(rng: np.random.Generator, area: str = "I") -> Scenario:
    """V-B: one object from (2, 2) to (4, 4), start (0, 0), one 0.4 m obstacle drawn in ``area`` (I-V)."""
    x0, x1, y0, y1 = PAPER_AREAS[area]
    tables = _paper_tables()
    while True:
        box = _square((_uniform(rng, x0, x1), _uniform(rng, y0, y1)), PAPER_OBSTACLE_SIZE)
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
    goal = (4.0 + _uniform(rng, -0.03, 0.03), 4.0 + _uniform(rng, -0.03, 0.03))
    size = _uniform(rng, 0.12, 0.16)
    block = _square((goal[0] + _uniform(rng, -0.02, 0.02), goal[1] + _uniform(rng, -0.02, 0.02)), size)
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
        clutter.append(_neighbour(rng, block, sides[k], long_bar, item_id, centred_bar=True))
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
        Table(f"table_{k + 1}", _square(c, PAPER_MULTI_TABLE_SIZE), TABLE_HEIGHT)
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
        p = (_uniform(rng, inner.min_x, inner.max_x), _uniform(rng, inner.min_y, inner.max_y))
        near_edge = min(p[0] - table.min_x, table.max_x - p[0], p[1] - table.min_y, table.max_y - p[1]) <= 0.12
        if near_edge and not any(discs_overlap(p, 0.04, q, 0.04) for q in taken):
            taken.append(p)
            return p


def draw_paper_covered(rng: np.random.Generator, count: int = 2) -> Scenario:
    """``count`` objects as in :func:`draw_paper_multi`, a 0.08 m block on every goal: each is pushed first."""
    while True:
        base = draw_paper_multi(rng, count)
        clutter = tuple(
            Clutter(f"block_{k + 1}", _square(_point_near(rng, o.goal, 0.01), PAPER_COVER_SIZE))
            for k, o in enumerate(base.objects)
        )
        scenario = replace(base, name=f"covered-{count}", clutter=clutter)
        if not check_rules(scenario):
            return scenario


# ---------------------------------------------------------------------- held-out layouts
TURNED_HEADING: dict[Heading, Heading] = {"+x": "+y", "+y": "-x", "-x": "-y", "-y": "+x"}
"""Where each heading points after a quarter turn counter-clockwise."""


def turn_quarter(scenario: Scenario, extent: Rect = EXTENT) -> Scenario:
    """``scenario`` turned a quarter turn counter-clockwise about the centre of the square ``extent``.

    A point ``(x, y)`` goes to ``(cx + cy - y, cy - cx + x)``; rectangles, headings and the
    area turn with it; sizes, heights and the robot's postures (relative to its heading) are unchanged.
    """
    cx, cy = extent.center

    def point(p: Point) -> Point:
        return (cx + cy - p[1], cy - cx + p[0])

    def rect(r: Rect) -> Rect:
        (x0, y0), (x1, y1) = point((r.min_x, r.max_y)), point((r.max_x, r.min_y))
        return Rect(x0, y0, x1, y1)

    return replace(
        scenario,
        name=f"turned-{scenario.name}",
        area=rect(scenario.area),
        robot=replace(
            scenario.robot, start=point(scenario.robot.start), heading=TURNED_HEADING[scenario.robot.heading]
        ),
        tables=tuple(replace(t, rect=rect(t.rect)) for t in scenario.tables),
        obstacles=tuple(replace(o, rect=rect(o.rect)) for o in scenario.obstacles),
        objects=tuple(replace(o, start=point(o.start), goal=point(o.goal)) for o in scenario.objects),
        clutter=tuple(replace(c, rect=rect(c.rect)) for c in scenario.clutter),
    )


def draw_turned_room(rng: np.random.Generator) -> Scenario:
    """A basic or push room (even odds), turned a quarter turn: a held-out layout."""
    return turn_quarter((draw_basic, draw_push)[int(rng.integers(2))](rng))


def draw_turned_corridor(rng: np.random.Generator) -> Scenario:
    """An L-shaped or straight corridor, turned a quarter turn: a held-out layout."""
    return turn_quarter(draw_corridor(rng))


# ---------------------------------------------------------------------- registry
def _family_per_value(
    name: str,
    description: str,
    draw: Callable[[np.random.Generator, T], Scenario],
    values: Iterable[T],
    capacity: Callable[[T], Capacity] = lambda _: Capacity(),
) -> list[Family]:
    """One family per value: ``{}`` in ``name`` and ``description`` stands for it; it is ``draw``'s second argument.

    ``capacity`` gives each family's observation capacity from its value.
    """
    return [
        Family(name.format(v), description.format(v), EXTENT, lambda rng, v=v: draw(rng, v), capacity(v))
        for v in values
    ]


def _objects_capacity(count: int) -> Capacity:
    """Room for ``count`` objects and as many pieces of clutter (at least the default's four and eight)."""
    default = Capacity()
    return Capacity(objects=max(default.objects, count), clutter=max(default.clutter, count))


def draw_mixed(rng: np.random.Generator) -> Scenario:
    """One of basic, push, corridor and multi, uniformly."""
    return (draw_basic, draw_push, draw_corridor, draw_multi)[int(rng.integers(4))](rng)


def draw_training(rng: np.random.Generator) -> Scenario:
    """One of basic, push, corridor and multi-2 (two objects), uniformly: what learners are trained on."""
    choice = int(rng.integers(4))
    if choice == 3:
        return draw_multi(rng, 2)
    return (draw_basic, draw_push, draw_corridor)[choice](rng)


def draw_perturbed(rng: np.random.Generator) -> Scenario:
    """A ``training`` scenario (the ``iid`` kind) with its tables and start moved and distractors added."""
    return perturb(rng, draw_training(rng))


OBJECT_COUNTS: tuple[int, ...] = tuple(range(1, MAX_OBJECTS + 1))  # the k of the objects-k families
GRADED: tuple[Family, ...] = (
    *(
        Family(
            f"objects-{k}",
            f"{k} object(s) over several tables in a room sized to fit, clutter on goals in half",
            EXTENT,
            lambda rng, k=k: draw_objects(rng, k),
            capacity=_objects_capacity(k),
        )
        for k in OBJECT_COUNTS
    ),
    Family(
        "apartment",
        "2-4 rooms joined by doors and corridors, 3-6 tables, 2-5 objects, clutter on some goals",
        EXTENT,
        draw_apartment,
        capacity=Capacity(objects=5),
    ),
    Family(
        "unseen-layouts", "held out: T-junction, U corridor, rooms in a row, table in a dead end", EXTENT, draw_unseen
    ),
    Family(
        "perturbed",
        "iid scenarios with tables and start moved, distractors, clutter mass and friction varied",
        EXTENT,
        draw_perturbed,
        physics=HOME,
    ),
)
"""The graded worlds (:mod:`fetchcarry_env.worlds`): registered after the families above, drawn by none of them."""

FAMILIES: dict[str, Family] = {
    family.name: family
    for family in (
        Family("basic", "V-B: one object, two tables, one random obstacle", EXTENT, draw_basic),
        Family("push", "V-C: clutter on the goal to push aside, Table I neighbours", EXTENT, draw_push),
        Family("corridor", "IV-F: rooms joined by an L-shaped or straight corridor", EXTENT, draw_corridor),
        Family("multi", "2 to 4 objects over two or three tables", EXTENT, draw_multi),
        *_family_per_value("multi-{}", "{} objects over two or three tables", draw_multi, (2, 3, 4)),
        Family("mixed", "basic, push, corridor or multi, uniformly", EXTENT, draw_mixed),
        Family("training", "basic, push, corridor or multi-2, uniformly (one and two objects)", EXTENT, draw_training),
        Family("turned-room", "held out: a basic or push room turned a quarter turn", EXTENT, draw_turned_room),
        Family("turned-corridor", "held out: a corridor turned a quarter turn", EXTENT, draw_turned_corridor),
        *GRADED,
        Family("objects-1-4", "objects-k with k uniform in 1..4 (the ladder's training family)", EXTENT, draw_ladder),
    )
}
HELD_OUT_FAMILIES: tuple[str, ...] = ("turned-room", "turned-corridor")
"""Families whose layouts no training family draws (for the benchmark's ``layouts-v0`` split)."""
UNSEEN_LAYOUT_FAMILIES: tuple[str, ...] = ("unseen-layouts",)
TRAINING_PREFIXES: tuple[str, ...] = ("basic", "push", "corridor", "multi", "turned-")
"""How the names of the training families' scenarios (and the turned ones) begin."""
TRAINING_FAMILIES: tuple[str, ...] = ("basic", "push", "corridor", "multi-2")
"""The families a learner trains on (the ``iid`` split's, the expert's and the mask's checks' default)."""
"""Topologies no training family draws, not even turned (for a new version of the ``layouts`` split)."""
FAMILY_NAMES: tuple[str, ...] = tuple(FAMILIES)
DEFAULT_FAMILY = "push"

PAPER_MULTI_COUNTS: tuple[int, ...] = (2, 3, 4, 5, 6)  # objects of the paper-multi-N families
PAPER_COVERED_COUNTS: tuple[int, ...] = (2, 3)  # objects of the paper-covered-N families
PAPER_FAMILIES: dict[str, Family] = {
    family.name: family
    for family in (
        *_family_per_value("paper-basic-{}", "V-B: one object, the obstacle in area {}", draw_paper_basic, PAPER_AREAS),
        *_family_per_value(
            "paper-push-{}", "V-C: a block on the goal, Table I pattern {}", draw_paper_push, PUSH_PATTERNS
        ),
        Family("paper-corridor", "IV-F: the L corridor of Fig. 4", EXTENT, draw_paper_corridor),
        *_family_per_value(
            "paper-multi-{}",
            "{} objects over three fixed tables",
            draw_paper_multi,
            PAPER_MULTI_COUNTS,
            _objects_capacity,
        ),
        *_family_per_value(
            "paper-covered-{}",
            "{} objects, a block on every goal",
            draw_paper_covered,
            PAPER_COVERED_COUNTS,
            _objects_capacity,
        ),
    )
}
"""The planner benchmark's cases (the paper's Section V); not drawn by ``mixed`` or ``training``."""
PAPER_FAMILY_NAMES: tuple[str, ...] = tuple(PAPER_FAMILIES)


def get_family(name: str) -> Family:
    """The family called ``name``, in :data:`FAMILIES` or :data:`PAPER_FAMILIES`.

    ``ValueError`` lists the known names otherwise.
    """
    family = FAMILIES.get(name) or PAPER_FAMILIES.get(name)
    if family is None:
        known = ", ".join((*FAMILY_NAMES, *PAPER_FAMILY_NAMES))
        raise ValueError(f"unknown scenario family {name!r}; known: {known}")
    return family
