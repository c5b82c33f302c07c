"""``perturbed``: the training families' scenarios with what a real home changes.

From a scenario of the ``iid`` kind (one of basic, push, corridor, multi-2, as the
``training`` family draws it), :func:`perturb` moves every table by up to
:data:`TABLE_SHIFT` along each axis (with whatever stands on it: object starts, goals,
clutter), moves the start by up to :data:`START_SHIFT`, and adds one to three
distractors: small blocks standing on tables on no goal and no object. The family also
names a physics variation (:mod:`fetchcarry_env.worlds.physics`, ``home``): each
piece of clutter's mass and friction are drawn per episode, so a push lands elsewhere
than the planner's model says, and the expert replans in closed loop. Units are metres.

One factor at a time: ``perturb(..., factors=...)`` applies only some of the geometric
factors (:data:`LAYOUT`, the tables and start moved; :data:`DISTRACTORS_FACTOR`, the
blocks added), and the families ``perturbed-layout``, ``perturbed-distractors`` and
``perturbed-physics`` (no geometric factor, the physics variation alone) each vary one.
Every factor is drawn whether it is applied or not, so a seed of a one-factor family is
the same scenario as that seed of ``perturbed`` without the other factors (as long as
both draws pass the family's checks at the first attempt), and ``perturbed``'s own draws
are unchanged.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fetchcarry_env.geometry import Point, Rect
from fetchcarry_env.scenario import Clutter, Scenario
from fetchcarry_env.worlds.base import name, point_near, square, uniform

TABLE_SHIFT = 0.05  # metres, per axis
START_SHIFT = 0.10  # metres, per axis
DISTRACTORS = (1, 3)  # how many, inclusive
DISTRACTOR_SIZE = (0.05, 0.08)  # metres: side of a distractor block
DISTRACTOR_HEIGHT = 0.08  # metres
DISTRACTOR_CLEARANCE = 0.05  # metres kept from every goal, object and other piece of clutter


LAYOUT = "layout"  # the tables (with what stands on them) and the start moved
DISTRACTORS_FACTOR = "distractors"  # one to three small blocks added on tables
GEOMETRIC_FACTORS = frozenset({LAYOUT, DISTRACTORS_FACTOR})


def perturb(
    rng: np.random.Generator,
    scenario: Scenario,
    factors: frozenset[str] = GEOMETRIC_FACTORS,
    family: str = "perturbed",
) -> Scenario:
    """``scenario`` with its tables and start moved a little and one to three distractors added.

    Only the ``factors`` given are applied, though every one is drawn (see the module
    docstring); ``family`` names the scenario (``family-NNNNNN``).
    """
    unknown = set(factors) - GEOMETRIC_FACTORS
    if unknown:
        raise ValueError(f"unknown perturbation factor(s) {sorted(unknown)}; known: {sorted(GEOMETRIC_FACTORS)}")
    shifts = [
        (uniform(rng, -TABLE_SHIFT, TABLE_SHIFT), uniform(rng, -TABLE_SHIFT, TABLE_SHIFT)) for _ in scenario.tables
    ]

    def moved(p: Point) -> Point:
        for table, (dx, dy) in zip(scenario.tables, shifts, strict=True):
            if table.rect.contains_point(p):
                return (p[0] + dx, p[1] + dy)
        return p

    tables = tuple(replace(t, rect=t.rect.translate(*d)) for t, d in zip(scenario.tables, shifts, strict=True))
    objects = tuple(replace(o, start=moved(o.start), goal=moved(o.goal)) for o in scenario.objects)
    clutter = [replace(c, rect=_moved_rect(c.rect, moved)) for c in scenario.clutter]
    start = point_near(rng, scenario.robot.start, START_SHIFT)
    shifted = replace(scenario, tables=tables, objects=objects, clutter=tuple(clutter))
    added: list[tuple[Clutter, tuple[float, float]]] = []  # each distractor and its table's shift
    for k in range(int(rng.integers(DISTRACTORS[0], DISTRACTORS[1] + 1))):
        spot = _distractor(rng, shifted, f"distractor_{k + 1}")
        if spot is not None:
            block, table = spot
            added.append((block, shifts[table]))
            clutter.append(block)
            shifted = replace(shifted, clutter=tuple(clutter))
    named = name(family, rng)
    base = replace(scenario, tables=tables, objects=objects, clutter=tuple(clutter[: len(scenario.clutter)]))
    blocks = [block for block, _ in added]
    if LAYOUT not in factors:  # the blocks keep their places on their tables, which stay where they were
        base, start = scenario, scenario.robot.start
        blocks = [replace(block, rect=block.rect.translate(-dx, -dy)) for block, (dx, dy) in added]
    distractors = tuple(blocks) if DISTRACTORS_FACTOR in factors else ()
    return replace(base, name=named, robot=replace(scenario.robot, start=start), clutter=base.clutter + distractors)


def _moved_rect(rect: Rect, moved) -> Rect:
    cx, cy = rect.center
    nx, ny = moved((cx, cy))
    return rect.translate(nx - cx, ny - cy)


def _distractor(rng: np.random.Generator, scenario: Scenario, item_id: str) -> tuple[Clutter, int] | None:
    """A small block on a random table, clear of every goal, object and piece of clutter, and the table's index
    (None if none fits)."""
    index = int(rng.integers(len(scenario.tables)))
    table = scenario.tables[index].rect
    size = uniform(rng, *DISTRACTOR_SIZE)
    inner = table.inflate(-size / 2 - 0.01)
    for _ in range(30):
        block = square((uniform(rng, inner.min_x, inner.max_x), uniform(rng, inner.min_y, inner.max_y)), size)
        near = block.inflate(DISTRACTOR_CLEARANCE)
        discs = [(o.start, o.radius) for o in scenario.objects] + [(o.goal, o.radius) for o in scenario.objects]
        if any(near.overlaps_disc(c, r) for c, r in discs) or any(near.overlaps_rect(c.rect) for c in scenario.clutter):
            continue
        return Clutter(item_id, block, DISTRACTOR_HEIGHT), index
    return None
