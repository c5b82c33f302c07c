"""Held-out layouts: a training room or corridor turned a quarter turn about the centre of the extent.

The robot then starts in the bottom-right corner and the rooms and corridors run the other
way, which no training family draws; the lattice maps onto itself, so every action stays on it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fetchcarry_env.geometry import Heading, Point, Rect
from fetchcarry_env.scenario import Scenario
from fetchcarry_env.worlds.base import EXTENT
from fetchcarry_env.worlds.rooms import draw_basic, draw_corridor, draw_push

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
