"""Small scenarios whose optimum is known by hand, and a self-check of a plan's basic invariants.

One-table cases use a fixed posture (the hand exactly 0.5 m ahead, the paper's fixed
posture) and a robot of radius 0.2 m, so the base poses that pick or place are single
lattice points and the optimum can be worked out on paper (each test says how).
"""

from __future__ import annotations

import math

from expert.plans import Plan, task_cost
from expert.validate import validate_plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import Clutter, DeliveryObject, Obstacle, Posture, Robot, Scenario, Table

ROOM = Rect(0.0, 0.0, 4.0, 3.0)  # metres: the one-table cases' floor
GOAL_TABLE = Rect(3.7, 3.7, 4.3, 4.3)  # metres: the V-C goal table
FIXED = (Posture("fixed", (0.5, 0.5), (0.0, 0.0)),)
RADIUS = 0.2  # metres


def one_table(
    *,
    obstacles: tuple[Rect, ...] = (),
    area: Rect = ROOM,
    start: tuple[float, float] = (1.0, 1.2),
) -> Scenario:
    """A cup from (2.0, 1.2) to (2.0, 1.8) on one table [1.8, 2.2] x [1.0, 2.0]; start west of it."""
    return Scenario(
        name="one-table",
        area=area,
        robot=Robot(start, "+x", RADIUS, FIXED),
        tables=(Table("table", Rect(1.8, 1.0, 2.2, 2.0)),),
        obstacles=tuple(Obstacle(f"obstacle_{k}", r) for k, r in enumerate(obstacles)),
        objects=(DeliveryObject("cup", (2.0, 1.2), (2.0, 1.8)),),
    )


TWO_TABLES = (Table("t1", Rect(1.8, 1.0, 2.2, 2.0)), Table("t2", Rect(4.8, 1.0, 5.2, 2.0)))


def two_tables(objects: tuple[DeliveryObject, ...], name: str) -> Scenario:
    """Two tables 3 m apart, the robot starting west of the first."""
    return Scenario(
        name=name,
        area=Rect(0.0, 0.0, 7.0, 3.0),
        robot=Robot((1.0, 1.5), "+x", RADIUS, FIXED),
        tables=TWO_TABLES,
        objects=objects,
    )


BLOCK = Rect(3.93, 3.93, 4.07, 4.07)  # 0.14 m, centred on the goal (4, 4)


def push_scene(
    name: str,
    clutter: dict[str, Rect],
    *,
    goal_table: Rect = GOAL_TABLE,
    goal: tuple[float, float] = (4.0, 4.0),
    obstacles: tuple[Rect, ...] = (),
) -> Scenario:
    """The paper's V-C layout: a bottle from (2, 2) to ``goal`` on ``goal_table``, with ``clutter`` there."""
    return Scenario(
        name=name,
        area=Rect(-1.0, -1.0, 6.0, 6.0),
        robot=Robot((0.0, 0.0)),
        tables=(Table("src", Rect(1.7, 1.7, 2.3, 2.3)), Table("dst", goal_table)),
        obstacles=tuple(Obstacle(f"obstacle_{k}", r) for k, r in enumerate(obstacles)),
        objects=(DeliveryObject("bottle", (2.0, 2.0), goal),),
        clutter=tuple(Clutter(cid, rect) for cid, rect in clutter.items()),
    )


def bar(side: str) -> Rect:
    """The paper's Obs 1: a 0.36 x 0.05 m bar 5 cm off ``side`` of :data:`BLOCK`."""
    return {
        "+x": Rect(4.12, 3.82, 4.17, 4.18),
        "-x": Rect(3.83, 3.82, 3.88, 4.18),
        "+y": Rect(3.82, 4.12, 4.18, 4.17),
        "-y": Rect(3.82, 3.83, 4.18, 3.88),
    }[side]


def check_plan(scenario: Scenario, plan: Plan, lattice: Lattice | None = None, holding: str | None = None) -> None:
    """Assert what every plan the planner returns must satisfy, beyond the validator's rules."""
    assert plan.status in ("optimal", "feasible"), (plan.status, plan.stats)
    assert plan.found
    lattice = lattice or Lattice.over(scenario.area, 0.05)
    start = plan.phases[0]
    assert start.action == "start" and start.base == scenario.robot.start and start.holding == holding
    for k, phase in enumerate(plan.phases[1:], start=1):
        assert lattice.on_lattice(phase.base), f"phase {k} base {phase.base} is off the lattice"
        if phase.action in ("pick", "place", "push"):
            assert phase.posture in {p.name for p in scenario.robot.postures}
    last = plan.phases[-1]
    assert last.holding is None
    for obj in scenario.objects:
        assert math.dist(last.objects[obj.id], obj.goal) < 1e-9
    assert plan.objective is not None and math.isclose(plan.objective, task_cost(scenario, plan.phases))
    for key in ("solver", "phases_tried", "build_s", "solve_s", "total_s"):
        assert key in plan.stats
    assert validate_plan(scenario, plan, holding=holding) == []


def many_obstacles(count: int, seed: int = 0) -> Scenario:
    """The V-B layout with ``count`` small (0.1 m) obstacles scattered off the tables and the start."""
    import numpy as np

    from fetchcarry_env.families import draw_paper_basic

    rng = np.random.default_rng(seed)
    base = draw_paper_basic(rng, "V")
    obstacles: list[Obstacle] = []
    while len(obstacles) < count:
        x, y = (float(v) for v in rng.uniform(-0.9, 5.9, 2))
        rect = Rect(x - 0.05, y - 0.05, x + 0.05, y + 0.05)
        if rect.distance_to_point((0.0, 0.0)) < 0.5 or any(
            rect.overlaps_rect(t.rect.inflate(0.3)) for t in base.tables
        ):
            continue
        obstacles.append(Obstacle(f"o{len(obstacles)}", rect))
    return Scenario(
        name=f"obstacles-{count}",
        area=base.area,
        robot=base.robot,
        tables=base.tables,
        obstacles=tuple(obstacles),
        objects=base.objects,
    )


def largest_scenario(seed: int = 0) -> Scenario:
    """As large as the scenario format allows: 64 objects, 256 clutter, 64 tables, 1,024 obstacles (48 m room)."""
    import numpy as np

    rng = np.random.default_rng(seed)
    tables = [
        Table(f"t{a}{b}", Rect(3.2 + 6 * a, 3.2 + 6 * b, 4.8 + 6 * a, 4.8 + 6 * b)) for a in range(8) for b in range(8)
    ]
    objects = []
    for k in range(64):
        src, dst = tables[k].rect.center, tables[(k * 7 + 3) % 64].rect.center
        objects.append(DeliveryObject(f"o{k}", (src[0] - 0.6, src[1]), (dst[0] + 0.6, dst[1])))
    clutter = [Clutter("c0_0", Rect.around(objects[0].goal, 0.05, 0.05), 0.1)]
    for k in range(64):
        cx, cy = tables[k].rect.center
        for m, (dx, dy) in enumerate(((0.0, 0.5), (0.0, -0.5), (0.3, 0.2), (-0.3, -0.2))):
            if (k, m) != (0, 0):
                clutter.append(Clutter(f"c{k}_{m}", Rect.around((cx + dx, cy + dy), 0.05, 0.05), 0.1))
    obstacles: list[Obstacle] = []
    while len(obstacles) < 1024:
        x, y = (float(v) for v in rng.uniform(0.5, 47.5, 2))
        rect = Rect.around((x, y), 0.05, 0.05)
        if rect.distance_to_point((1.0, 1.0)) < 1.0 or any(rect.overlaps_rect(t.rect.inflate(0.8)) for t in tables):
            continue
        obstacles.append(Obstacle(f"w{len(obstacles)}", rect))
    return Scenario(
        name="largest",
        area=Rect(0.0, 0.0, 48.0, 48.0),
        robot=Robot((1.0, 1.0)),
        tables=tuple(tables),
        obstacles=tuple(obstacles),
        objects=tuple(objects),
        clutter=tuple(clutter),
    )
