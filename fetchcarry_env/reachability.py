"""Cheap geometric checks that a scenario can be worked: every object and goal reachable from a side.

Used by the scenario families to reject layouts that no planner could solve (an object
whose every side is blocked, a goal behind a wall, a room the base cannot get into).
They are conservative in the same way as the planner (:mod:`expert`): the base keeps
half a lattice cell more than its radius from tables and obstacles, reach ranges are
narrowed by half a cell.
"""

from __future__ import annotations

import numpy as np

from fetchcarry_env.geometry import HEADINGS, Point, Rect, to_world_frame
from fetchcarry_env.kinematics import arm_line_clear
from fetchcarry_env.scenario import Scenario

GRID = 0.05  # metres between the cells of the free-space grid
MARGIN = 0.03  # metres kept beyond the base radius (the planner keeps half a 5 cm cell)


class FreeSpace:
    """The base-centre positions that are free of tables and obstacles, and which of them the start reaches."""

    def __init__(self, scenario: Scenario, margin: float = MARGIN, grid: float = GRID) -> None:
        self.scenario = scenario
        self.clearance = scenario.robot.radius + margin
        area = scenario.area.inflate(-self.clearance)
        self.origin = (area.min_x, area.min_y)
        self.grid = grid
        xs = area.min_x + grid * np.arange(max(int((area.max_x - area.min_x) / grid) + 1, 1))
        ys = area.min_y + grid * np.arange(max(int((area.max_y - area.min_y) / grid) + 1, 1))
        gx, gy = np.meshgrid(xs, ys, indexing="ij")
        free = np.ones(gx.shape, dtype=bool)
        for rect in (*(t.rect for t in scenario.tables), *(o.rect for o in scenario.obstacles)):
            dx = np.maximum(np.maximum(rect.min_x - gx, 0.0), gx - rect.max_x)
            dy = np.maximum(np.maximum(rect.min_y - gy, 0.0), gy - rect.max_y)
            free &= np.hypot(dx, dy) > self.clearance
        self.free = free
        self.reached = self._flood(self._cell(scenario.robot.start, nearest_free=True))

    def _cell(self, p: Point, nearest_free: bool = False) -> tuple[int, int] | None:
        i = round((p[0] - self.origin[0]) / self.grid)
        j = round((p[1] - self.origin[1]) / self.grid)
        candidates = [(i, j)]
        if nearest_free:
            candidates += [(i + di, j + dj) for di in (-1, 0, 1) for dj in (-1, 0, 1)]
        for ci, cj in candidates:
            if 0 <= ci < self.free.shape[0] and 0 <= cj < self.free.shape[1] and self.free[ci, cj]:
                return (ci, cj)
        return None

    def _flood(self, seed: tuple[int, int] | None) -> np.ndarray:
        """The free cells 4-connected to ``seed``: its component of the free grid (``scipy.ndimage.label``).

        The components of the 4-neighbourhood, as a flood fill by repeated dilation finds
        them (cell for cell the same: ``tests/env/test_speed_reachability.py``), in about
        0.1 ms instead of 7-13 ms per scenario.
        """
        if seed is None:
            return np.zeros_like(self.free)
        from scipy import ndimage  # here: the env's import does not need it

        labels, _count = ndimage.label(self.free)  # the default structure of 2-D arrays: the 4-neighbourhood
        return labels == labels[seed]

    def reachable(self, base: Point) -> bool:
        """True when the base can stand at ``base`` and get there from the start."""
        cell = self._cell(base)
        if cell is None or not self.reached[cell]:
            return False
        blockers = (*(t.rect for t in self.scenario.tables), *(o.rect for o in self.scenario.obstacles))
        return all(r.distance_to_point(base) > self.clearance for r in blockers)


def approach_poses(scenario: Scenario, target: Point, margin: float = MARGIN) -> list[Point]:
    """Candidate base positions from which some posture and heading put the hand over ``target``."""
    poses = []
    for heading in HEADINGS:
        for posture in scenario.robot.postures:
            f_lo, f_hi = posture.forward[0] + margin, posture.forward[1] - margin
            lateral = (posture.lateral[0] + posture.lateral[1]) / 2
            if f_hi < f_lo:
                f_lo = f_hi = (posture.forward[0] + posture.forward[1]) / 2
            for forward in np.linspace(f_lo, f_hi, 4):
                dx, dy = to_world_frame(heading, float(forward), lateral)
                poses.append((target[0] - dx, target[1] - dy))
    return poses


def reachable_from_a_side(scenario: Scenario, target: Point, space: FreeSpace, ignore: tuple[Rect, ...] = ()) -> bool:
    """True when the base can get to a pose that reaches ``target`` with a clear arm line (Eq. 19)."""
    blockers = [o.rect for o in scenario.obstacles] + [c.rect for c in scenario.clutter if c.rect not in ignore]
    return any(
        space.reachable(base) and arm_line_clear(base, target, blockers) for base in approach_poses(scenario, target)
    )


def unreachable_targets(scenario: Scenario) -> list[str]:
    """Descriptions of every object start or goal no side of which the robot can work from (empty: all fine)."""
    space = FreeSpace(scenario)
    problems = []
    for obj in scenario.objects:
        covering = tuple(c.rect for c in scenario.clutter if c.rect.overlaps_disc(obj.goal, obj.radius))
        if not reachable_from_a_side(scenario, obj.start, space):
            problems.append(f"object {obj.id!r} start")
        if not reachable_from_a_side(scenario, obj.goal, space, ignore=covering):
            problems.append(f"object {obj.id!r} goal")
    return problems
