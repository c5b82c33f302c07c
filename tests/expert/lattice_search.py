"""An exhaustive search for single-object plans on the lattice, written apart from the MILP.

It knows only the scenario's rules as the validator states them: the base disc inside
the area, every move's swept disc at least the radius from every table and obstacle
(the exact rule), a pick or place from a lattice point whose posture reaches the object
with an arm line that crosses no obstacle. Phases are layers of a dynamic programme
over (lattice point, stage), stage 0: not picked, 1: held, 2: placed; each phase is a
straight move (possibly of length zero) followed by at most one arm action, as in a
plan. It returns the fewest phases that deliver the object and, for that number, the
least task cost (travel plus W1 for each phase the object waits: all but the start and the last).

Units are metres. Only for small rooms and coarse lattices: it looks at every pair of
lattice points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import HEADINGS
from fetchcarry_env.kinematics import DIAGONAL_WEIGHT, WAIT_COST, arm_line_clear, reaches
from fetchcarry_env.scenario import Scenario

SLACK = 1e-6  # metres: a move this much closer than the radius still counts as clear
TERNARY_STEPS = 60  # iterations of the ternary search for the segment-rectangle distance


@dataclass(frozen=True)
class SearchResult:
    phases: int | None  # the fewest phases (the start included), None: no plan within max_phases
    objective: float | None  # the least task cost with that many phases
    path: tuple[tuple[tuple[float, float], str | None], ...] = ()  # one optimal plan: (base, action) per phase


def _rect_distance(x: np.ndarray, y: np.ndarray, rect) -> np.ndarray:
    dx = np.maximum(np.maximum(rect.min_x - x, 0.0), x - rect.max_x)
    dy = np.maximum(np.maximum(rect.min_y - y, 0.0), y - rect.max_y)
    return np.hypot(dx, dy)


def _segment_clear(p: np.ndarray, q: np.ndarray, rects, radius: float) -> np.ndarray:
    """For each pair of rows of ``p`` and ``q`` (shape (n, 2)): the segment stays ``radius`` from every rect."""
    clear = np.ones(len(p), dtype=bool)
    for rect in rects:
        lo, hi = np.zeros(len(p)), np.ones(len(p))
        for _ in range(TERNARY_STEPS):  # the distance to a convex set is convex along the segment
            a, b = lo + (hi - lo) / 3, hi - (hi - lo) / 3
            da = _rect_distance(p[:, 0] + a * (q[:, 0] - p[:, 0]), p[:, 1] + a * (q[:, 1] - p[:, 1]), rect)
            db = _rect_distance(p[:, 0] + b * (q[:, 0] - p[:, 0]), p[:, 1] + b * (q[:, 1] - p[:, 1]), rect)
            smaller = da < db
            hi = np.where(smaller, b, hi)
            lo = np.where(smaller, lo, a)
        t = (lo + hi) / 2
        best = np.minimum.reduce(
            [
                _rect_distance(p[:, 0] + t * (q[:, 0] - p[:, 0]), p[:, 1] + t * (q[:, 1] - p[:, 1]), rect),
                _rect_distance(p[:, 0], p[:, 1], rect),
                _rect_distance(q[:, 0], q[:, 1], rect),
            ]
        )
        clear &= best >= radius - SLACK
    return clear


def _travel(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    dx, dy = np.abs(q[..., 0] - p[..., 0]), np.abs(q[..., 1] - p[..., 1])
    return dx + dy + DIAGONAL_WEIGHT * np.abs(dx - dy)


def search(scenario: Scenario, lattice: Lattice, max_phases: int = 8) -> SearchResult:
    """The fewest phases and least Eq. 1 of any plan delivering the scenario's one object (see the module)."""
    (obj,) = scenario.objects
    robot = scenario.robot
    rects = [t.rect for t in scenario.tables] + [o.rect for o in scenario.obstacles]
    points = np.array(
        [lattice.point(i, j) for i in range(lattice.shape[0]) for j in range(lattice.shape[1])], dtype=float
    )
    inside = np.array([scenario.area.contains_disc(tuple(p), robot.radius, tol=1e-9) for p in points])
    far = np.ones(len(points), dtype=bool)
    for rect in rects:
        far &= _rect_distance(points[:, 0], points[:, 1], rect) >= robot.radius - SLACK
    points = points[inside & far]
    n = len(points)
    obstacles = [o.rect for o in scenario.obstacles]

    def poses(where) -> np.ndarray:
        return np.array(
            [
                any(
                    reaches(posture, tuple(p), h, where) and arm_line_clear(tuple(p), where, obstacles)
                    for h in HEADINGS
                    for posture in robot.postures
                )
                for p in points
            ]
        )

    pick, place = poses(obj.start), poses(obj.goal)
    ii, jj = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    pairs = ii < jj
    ok = np.zeros((n, n), dtype=bool)
    ok[ii[pairs], jj[pairs]] = _segment_clear(points[ii[pairs]], points[jj[pairs]], rects, robot.radius)
    ok |= ok.T
    np.fill_diagonal(ok, True)
    cost = np.where(ok, _travel(points[:, None, :], points[None, :, :]), math.inf)
    start = np.array([robot.start], dtype=float)
    from_start = np.where(
        _segment_clear(np.repeat(start, n, axis=0), points, rects, robot.radius), _travel(start, points), math.inf
    )
    # best[stage][point]: least travel to stand at the point after the phase, in that stage.
    best = [from_start, np.where(pick, from_start, math.inf), np.full(n, math.inf)]
    parents: list = [None]  # parents[phase][stage]: (previous point, previous stage) per point
    for steps in range(2, max_phases):
        arrived = [np.min(b[:, None] + cost, axis=0) for b in best]
        came = [np.argmin(b[:, None] + cost, axis=0) for b in best]
        picked = pick & (arrived[0] < arrived[1])
        best = [
            arrived[0],
            np.minimum(arrived[1], np.where(pick, arrived[0], math.inf)),
            np.where(place, arrived[1], math.inf),
        ]
        parents.append([(came[0], 0), (np.where(picked, came[0], came[1]), np.where(picked, 0, 1)), (came[1], 1)])
        if np.isfinite(best[2]).any():
            path = _path(points, parents, int(np.argmin(best[2])))
            return SearchResult(steps + 1, float(best[2].min()) + WAIT_COST * (steps - 1), path)
    return SearchResult(None, None)


def _path(points: np.ndarray, parents: list, last: int) -> tuple:
    """Walk the parents back from ``last`` (stage 2 at the last phase): ``(base, action)`` per phase after the start."""
    out = []
    point, stage = last, 2
    for phase in range(len(parents) - 1, 0, -1):
        previous, stages = parents[phase][stage]
        before = int(stages if np.ndim(stages) == 0 else stages[point])
        action = None if stage == before else ("pick", "place")[before]
        out.append(((float(points[point, 0]), float(points[point, 1])), action))
        point, stage = int(previous[point]), before
    out.append(((float(points[point, 0]), float(points[point, 1])), "pick" if stage == 1 else None))
    return tuple(reversed(out))
