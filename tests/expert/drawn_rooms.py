"""Small single-object rooms drawn on purpose: random walls, L-shaped corridors, diagonal gaps between corners.

Each draw is a 3 x 3 m room with one table and one object, retried until the scenario
obeys every rule; the exhaustive search of the env's rules (``test_exact_rule.py``) and the
collision model's tests plan them. Units are metres.
"""

from __future__ import annotations

import math

import numpy as np

from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import DeliveryObject, Obstacle, Robot, Scenario, Table, check_rules

ROOM = Rect(0.0, 0.0, 3.0, 3.0)


def random_room(rng: np.random.Generator, name: str) -> Scenario:
    """A 0.5 m table with the object moved across it, one to three walls, a random start."""
    while True:
        tx, ty = (float(v) for v in rng.uniform(0.9, 2.1, 2))
        obj = DeliveryObject(
            "bottle",
            (tx - 0.15, ty + float(rng.uniform(-0.15, 0.15))),
            (tx + 0.15, ty + float(rng.uniform(-0.15, 0.15))),
        )
        walls = []
        for m in range(int(rng.integers(1, 4))):
            x, y = (float(v) for v in rng.uniform(0.2, 2.8, 2))
            w, h = (float(v) for v in rng.uniform(0.1, 0.9, 2))
            walls.append(Obstacle(f"wall_{m}", Rect(x - w / 2, y - h / 2, x + w / 2, y + h / 2)))
        sx, sy = (float(v) for v in rng.uniform(0.3, 2.7, 2))
        scenario = Scenario(
            name=name,
            area=ROOM,
            robot=Robot((sx, sy)),
            tables=(Table("table", Rect(tx - 0.25, ty - 0.25, tx + 0.25, ty + 0.25)),),
            obstacles=tuple(walls),
            objects=(obj,),
        )
        if not check_rules(scenario):
            return scenario


def corridor_room(rng: np.random.Generator, name: str) -> Scenario:
    """An L-shaped corridor (bottom, then right) 0.46-0.8 m wide round a block, to a table in the top strip."""
    while True:
        wb, wr = (float(v) for v in rng.uniform(0.46, 0.8, 2))
        top = float(rng.uniform(2.0, 2.2))
        tx = float(rng.uniform(0.7, 1.6))
        scenario = Scenario(
            name=name,
            area=ROOM,
            robot=Robot((float(rng.uniform(0.3, 1.0)), wb / 2)),
            tables=(Table("table", Rect(tx - 0.25, 2.45, tx + 0.25, 2.95)),),
            obstacles=(Obstacle("block", Rect(0.0, wb, 3.0 - wr, top)),),
            objects=(DeliveryObject("bottle", (tx - 0.15, 2.55), (tx + 0.15, 2.55)),),
        )
        if not check_rules(scenario):
            return scenario


def diagonal_room(rng: np.random.Generator, name: str) -> Scenario:
    """Walls top-left and bottom-right whose corners leave a diagonal gap of 0.45-0.65 m at 30-60 degrees."""
    while True:
        gap, angle = float(rng.uniform(0.45, 0.65)), math.radians(float(rng.uniform(30.0, 60.0)))
        xa, yb = (float(v) for v in rng.uniform(1.0, 1.4, 2))
        xb, ya = xa + gap * math.cos(angle), yb + gap * math.sin(angle)
        scenario = Scenario(
            name=name,
            area=ROOM,
            robot=Robot((float(rng.uniform(0.3, 0.8)), float(rng.uniform(0.3, 0.8)))),
            tables=(Table("table", Rect(2.2, 2.2, 2.7, 2.7)),),
            obstacles=(Obstacle("wall_a", Rect(0.0, ya, xa, 3.0)), Obstacle("wall_b", Rect(xb, 0.0, 3.0, yb))),
            objects=(DeliveryObject("bottle", (2.3, 2.45), (2.6, 2.45)),),
        )
        if not check_rules(scenario):
            return scenario
