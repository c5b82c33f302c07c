"""Drawing helpers shared by every scenario family: squares, jitter, free spots, floors made of rooms.

A floor is a union of free rectangles (rooms, doors, corridors); :func:`walls_around`
turns the rest of the area into a few wall rectangles. Units are metres.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fetchcarry_env.geometry import HEADINGS, Point, Rect, discs_overlap
from fetchcarry_env.scenario import Clutter, DeliveryObject, Obstacle, Robot, Table

EXTENT = Rect(-1.0, -1.0, 6.0, 6.0)  # metres: the floor every family's room lies in
TABLE_HEIGHT = 0.70  # metres
COVER_SIZE = (0.08, 0.11)  # metres: side of a block standing on a goal (low, high)
COVER_HEIGHT = 0.08  # metres
OBJECT_RADIUS = 0.035  # metres: the scenario format's default object
OBJECT_GAP = 0.08  # metres kept between the discs of two objects' starts or goals on one table


def square(center: Point, size: float) -> Rect:
    """The axis-aligned square of side ``size`` centred at ``center``."""
    return Rect.around(center, size / 2, size / 2)


def uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(rng.uniform(low, high))


def point_near(rng: np.random.Generator, center: Point, spread: float) -> Point:
    """A point within ``spread`` of ``center`` along each axis, uniformly."""
    return (center[0] + uniform(rng, -spread, spread), center[1] + uniform(rng, -spread, spread))


def robot(rng: np.random.Generator, start: Point) -> Robot:
    """The default robot at ``start`` facing one of the four headings, uniformly."""
    return Robot(start=start, heading=HEADINGS[int(rng.integers(4))])


def name(family: str, rng: np.random.Generator) -> str:
    """``family-NNNNNN``: a scenario name with six digits drawn from ``rng``."""
    return f"{family}-{int(rng.integers(1_000_000)):06d}"


def free_spot(
    rng: np.random.Generator,
    table: Rect,
    radius: float,
    margin: float,
    taken: list[tuple[Point, float]],
    gap: float = 0.02,
) -> Point:
    """A point on ``table`` (``margin`` inside its edge), ``gap`` clear of the ``taken`` discs; the centre if none."""
    inner = table.inflate(-(radius + margin))
    for _ in range(50):
        p = (uniform(rng, inner.min_x, inner.max_x), uniform(rng, inner.min_y, inner.max_y))
        if not any(discs_overlap(p, radius + gap, c, r) for c, r in taken):
            return p
    return inner.center


def deliveries(rng: np.random.Generator, tables: Sequence[Table], count: int) -> list[DeliveryObject]:
    """``count`` objects, each from one table to another (both drawn uniformly), :data:`OBJECT_GAP` apart."""
    taken: dict[int, list[tuple[Point, float]]] = {k: [] for k in range(len(tables))}
    objects = []
    for k in range(count):
        src = int(rng.integers(len(tables)))
        dst = (src + 1 + int(rng.integers(len(tables) - 1))) % len(tables)
        spots = []
        for table in (src, dst):
            spot = free_spot(rng, tables[table].rect, OBJECT_RADIUS, 0.03, taken[table], gap=OBJECT_GAP)
            taken[table].append((spot, OBJECT_RADIUS))
            spots.append(spot)
        objects.append(DeliveryObject(f"object_{k + 1}", spots[0], spots[1]))
    return objects


def covers(rng: np.random.Generator, objects: Sequence[DeliveryObject], chance: float) -> list[Clutter]:
    """A block on each goal with probability ``chance`` (side :data:`COVER_SIZE`, up to 1 cm off the goal)."""
    blocks = []
    for obj in objects:
        if rng.random() < chance:
            size = uniform(rng, *COVER_SIZE)
            blocks.append(Clutter(f"block_{obj.id}", square(point_near(rng, obj.goal, 0.01), size), COVER_HEIGHT))
    return blocks


def walls_around(area: Rect, free: Sequence[Rect]) -> list[Obstacle]:
    """The part of ``area`` outside every ``free`` rectangle, as few wall rectangles as a sweep finds.

    The area is cut along every edge of the free rectangles into cells; each row's runs
    of walled cells are merged, then runs with the same ends in consecutive rows.
    """
    xs = sorted(
        {area.min_x, area.max_x, *(min(max(v, area.min_x), area.max_x) for r in free for v in (r.min_x, r.max_x))}
    )
    ys = sorted(
        {area.min_y, area.max_y, *(min(max(v, area.min_y), area.max_y) for r in free for v in (r.min_y, r.max_y))}
    )
    runs: list[tuple[int, int, int, int]] = []  # (x start, x end, y start, y end) cell indices, end exclusive
    open_runs: dict[tuple[int, int], int] = {}  # x run -> the row it started in
    for j in range(len(ys) - 1):
        cy = (ys[j] + ys[j + 1]) / 2
        walled = [
            not any(r.contains_point(((xs[i] + xs[i + 1]) / 2, cy), tol=0.0) for r in free) for i in range(len(xs) - 1)
        ]
        row: list[tuple[int, int]] = []
        i = 0
        while i < len(walled):
            if walled[i]:
                start = i
                while i < len(walled) and walled[i]:
                    i += 1
                row.append((start, i))
            i += 1
        for run in list(open_runs):
            if run not in row:
                runs.append((*run, open_runs.pop(run), j))
        for run in row:
            open_runs.setdefault(run, j)
    runs += [(*run, start, len(ys) - 1) for run, start in open_runs.items()]
    rects = [Rect(xs[a], ys[c], xs[b], ys[d]) for a, b, c, d in sorted(runs, key=lambda r: (r[2], r[0]))]
    return [Obstacle(f"wall_{k + 1}", r) for k, r in enumerate(rects) if r.is_proper]
