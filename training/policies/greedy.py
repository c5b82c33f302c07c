"""``GreedyPolicy``: decoupled task-then-motion planning, the approach the paper argues against.

It fixes the task first, greedily, and only then the motion, one phase at a time:

1. **Task**: place the held object; else take the nearest object not delivered (by
   the paper's travel cost from the base) and, if a piece of clutter stands on its
   goal, push that piece off first; else pick the object.
2. **Pose**: of the lattice poses from which the env would accept that single phase
   (:func:`fetchcarry_env.rules.check_action`; for a push, the stroke that just clears
   the goal, :func:`fetchcarry_env.kinematics.push_stroke`), the one cheapest to reach
   by a search on the free lattice (Dijkstra over the 8-connected lattice points where
   the base clears every table, obstacle and the area's edge; steps cost the paper's
   travel cost).
3. **Motion**: the phase itself when the straight move to its pose is free; otherwise a
   move to the farthest point of the searched path that the env's move rule lets a
   straight move reach (:func:`fetchcarry_env.rules.move_refusal`).

It never looks ahead: the pose chosen for a pick ignores where the place will be, which
is what the MILP's joint task-and-motion optimisation buys. Like the expert it plans from
the observation alone (:func:`fetchcarry_env.observation.decode`), speaks
stable-baselines3's ``predict`` protocol, returns the env's ``MultiDiscrete`` actions,
and returns the idle action (a move to where the base stands) when it finds no pose.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import replace
from typing import Any

import numpy as np

from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.geometry import HEADINGS, Heading, Point, heading_vector, to_world_frame
from fetchcarry_env.kinematics import (
    DIAGONAL_WEIGHT,
    hand_offset,
    push_contact,
    push_headings,
    push_stroke,
    travel_cost,
)
from fetchcarry_env.observation import Capacity, WorldState, decode
from fetchcarry_env.phases import PhaseLayout
from fetchcarry_env.rules import check_action, clutter_rect, move_refusal
from fetchcarry_env.scenario import Scenario

CLEARANCE_MARGIN = 0.01  # metres kept beyond the base radius by the lattice search
AT_POSE = 1e-5  # metres: the base stands at a pose (observations are float32: about 0.2 µm of rounding at 4 m)
_STEPS = [(di, dj) for di in (-1, 0, 1) for dj in (-1, 0, 1) if (di, dj) != (0, 0)]


class GreedyPolicy:
    """Greedy task order, then the cheapest pose for each phase alone (see the module docstring)."""

    def __init__(self, env: Any = None, *, lattice: Lattice | None = None, capacity: Capacity | None = None) -> None:
        self.lattice: Lattice = lattice if lattice is not None else env.get_wrapper_attr("lattice")
        self.capacity: Capacity = capacity if capacity is not None else env.get_wrapper_attr("capacity")
        self.layout = PhaseLayout.for_postures(resolution=self.lattice.resolution, capacity=self.capacity)
        self._free_for: tuple | None = None
        self._free: np.ndarray | None = None

    def reset(self) -> None:
        """Nothing to forget between episodes (the policy keeps no plan)."""

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True, **_: Any
    ) -> tuple[np.ndarray, Any]:
        """The greedy action for each observation (a batch gives a batch); ``state`` is returned unchanged."""
        flat = np.asarray(observation["observation"] if isinstance(observation, dict) else observation)
        rows = flat if flat.ndim == 2 else flat[None, :]
        actions = np.stack([self._act(*decode(row, self.capacity)).to_array() for row in rows])
        return (actions if flat.ndim == 2 else actions[0]), state

    # ------------------------------------------------------------------ one decision
    def _act(self, scenario: Scenario, world: WorldState) -> Action:
        poses = self._task_poses(scenario, world)
        if not poses:
            return self._idle(world)
        extra: dict[tuple[int, int], float] = {}
        for pose, added, _push in poses:
            extra[pose.cell] = min(extra.get(pose.cell, math.inf), added)
        cost, previous = self._search(scenario, world, extra)
        best = min(poses, key=lambda p: (cost.get(p[0].cell, math.inf) + p[1], p[0].cell, p[0].heading))
        action = best[0]
        if cost.get(action.cell, math.inf) == math.inf:
            return self._idle(world)
        target = self.lattice.point(*action.cell)
        if action.mode == Mode.PUSH:  # the pose is where the stroke starts
            if math.dist(target, world.base) <= AT_POSE:
                return best[2]
            if move_refusal(scenario, self.lattice, world.base, target) is None:
                return Action(action.cell, world.heading, 0, Mode.MOVE)
        elif move_refusal(scenario, self.lattice, world.base, target) is None:
            return action
        return self._step_along(scenario, world, action.cell, previous)

    def _task_poses(self, scenario: Scenario, world: WorldState) -> list[tuple[Action, float, Action | None]]:
        """``(pose action, extra cost, push action)`` of every pose from which the env accepts the next phase."""
        if world.holding is not None:
            obj = scenario.object(world.holding)
            return [(a, 0.0, None) for a in self._acting_poses(scenario, world, obj.goal, obj.id, Mode.PLACE)]
        delivered = set(world.delivered(scenario))
        left = [o for o in scenario.objects if o.id not in delivered]
        if not left:
            return []
        obj = min(left, key=lambda o: (travel_cost(world.base, world.objects[o.id][:2]), o.id))
        for item in scenario.clutter:
            rect = clutter_rect(scenario, world, item.id)
            if rect.overlaps_disc(obj.goal, obj.radius):
                return self._push_poses(scenario, world, item.id, [(obj.goal, obj.radius)])
        return [
            (a, 0.0, None) for a in self._acting_poses(scenario, world, world.objects[obj.id][:2], obj.id, Mode.PICK)
        ]

    def _acting_poses(self, scenario: Scenario, world: WorldState, point: Point, item: str, mode: Mode) -> list[Action]:
        """Pick or place actions, from poses around ``point``, that the env accepts on ``item``."""
        out = []
        for heading, cell, posture in self._window(scenario, point):
            action = Action(cell, heading, posture, mode)
            there = replace(world, base=self.lattice.point(*cell))  # the phase alone: the motion is searched
            phase = check_action(scenario, there, self.lattice, action)
            if not isinstance(phase, str) and phase.target == item:
                out.append(action)
        return out

    def _push_poses(
        self, scenario: Scenario, world: WorldState, item: str, covered: list[tuple[Point, float]]
    ) -> list[tuple[Action, float, Action | None]]:
        """Stroke-start poses (as moves) with the stroke's cost and the push action, for each direction."""
        rect = clutter_rect(scenario, world, item)
        out = []
        for direction in HEADINGS:
            stroke = push_stroke(rect, direction, covered, self.lattice.resolution)
            cells = round(stroke / self.lattice.resolution)
            ux, uy = heading_vector(direction)
            contact = push_contact(rect, direction)
            for heading, cell, posture in self._window(scenario, contact, push_headings(direction)):
                end = (cell[0] + ux * cells, cell[1] + uy * cells)
                if not (0 <= end[0] < self.lattice.shape[0] and 0 <= end[1] < self.lattice.shape[1]):
                    continue
                start = self.lattice.point(*cell)
                push = Action(end, heading, posture, Mode.PUSH)
                phase = check_action(scenario, replace(world, base=start, heading=heading), self.lattice, push)
                if isinstance(phase, str) or phase.target != item:
                    continue
                if move_refusal(scenario, self.lattice, start, phase.base) is not None:
                    continue
                out.append((Action(cell, heading, posture, Mode.PUSH), travel_cost(start, phase.base), push))
        return out

    def _window(
        self, scenario: Scenario, point: Point, headings: tuple[Heading, ...] = HEADINGS
    ) -> list[tuple[Heading, tuple[int, int], int]]:
        """``(heading, cell, posture)`` of the lattice poses from which a posture reaches ``point``."""
        center = self.lattice.index(point)
        nf, nl = self.layout.window
        out = []
        for heading in headings:
            for f in range(nf):
                for lat in range(nl):
                    dx, dy = to_world_frame(heading, self.layout.forward[0] + f, lat - self.layout.lateral)
                    cell = (center[0] - int(dx), center[1] - int(dy))
                    if not (0 <= cell[0] < self.lattice.shape[0] and 0 <= cell[1] < self.lattice.shape[1]):
                        continue
                    offset = hand_offset(self.lattice.point(*cell), heading, point)
                    posture = next((k for k, p in enumerate(scenario.robot.postures) if p.reaches(*offset)), None)
                    if posture is not None:
                        out.append((heading, cell, posture))
        return out

    # ------------------------------------------------------------------ motion
    def _free_cells(self, scenario: Scenario) -> np.ndarray:
        """Lattice points where the base clears every table and obstacle and stays in the area (cached per layout)."""
        key = scenario.layout_key
        if self._free_for != key:
            xs, ys = self.lattice.axis_points(0), self.lattice.axis_points(1)
            gx, gy = np.meshgrid(xs, ys, indexing="ij")
            clearance = scenario.robot.radius + CLEARANCE_MARGIN
            area = scenario.area.inflate(-clearance)
            free = (gx >= area.min_x) & (gx <= area.max_x) & (gy >= area.min_y) & (gy <= area.max_y)
            for rect in (*(t.rect for t in scenario.tables), *(o.rect for o in scenario.obstacles)):
                dx = np.maximum(np.maximum(rect.min_x - gx, 0.0), gx - rect.max_x)
                dy = np.maximum(np.maximum(rect.min_y - gy, 0.0), gy - rect.max_y)
                free &= np.hypot(dx, dy) > clearance
            self._free_for, self._free = key, free
        return self._free

    def _search(self, scenario: Scenario, world: WorldState, goals: dict[tuple[int, int], float]) -> tuple[dict, dict]:
        """Dijkstra on the free lattice from the base's cell: cost (paper's travel cost) and predecessor per cell.

        It stops once no cell left can beat the best goal cell found, counting each goal's
        ``goals[cell]`` extra cost: the costs of the goal cells it settled are then final.
        """
        free = self._free_cells(scenario).tolist()  # plain lists: element access is much cheaper than numpy's
        nx, ny = len(free), len(free[0])
        res = self.lattice.resolution
        start = self.lattice.index(world.base)
        cost = {start: travel_cost(world.base, self.lattice.point(*start))}
        previous: dict = {start: None}
        queue = [(cost[start], start)]
        axis, diagonal = res * (1 + DIAGONAL_WEIGHT), 2 * res
        best = math.inf
        while queue:
            c, cell = heapq.heappop(queue)
            if c > cost[cell] or c > best:
                if c > best:
                    break
                continue
            if cell in goals:
                best = min(best, c + goals[cell])
            i, j = cell
            for di, dj in _STEPS:
                ni, nj = i + di, j + dj
                if not (0 <= ni < nx and 0 <= nj < ny) or not free[ni][nj]:
                    continue
                if di and dj and not (free[ni][j] and free[i][nj]):
                    continue  # no cutting corners
                total = c + (diagonal if di and dj else axis)
                if total < cost.get((ni, nj), math.inf):
                    cost[(ni, nj)] = total
                    previous[(ni, nj)] = cell
                    heapq.heappush(queue, (total, (ni, nj)))
        return cost, previous

    def _step_along(self, scenario: Scenario, world: WorldState, goal: tuple[int, int], previous: dict) -> Action:
        """A move to the farthest point of the searched path to ``goal`` that a straight move reaches freely."""
        path = [goal]
        while previous[path[-1]] is not None:
            path.append(previous[path[-1]])
        path.reverse()
        for cell in reversed(path[1:]):
            if move_refusal(scenario, self.lattice, world.base, self.lattice.point(*cell)) is None:
                return Action(cell, world.heading, 0, Mode.MOVE)
        return Action(path[1] if len(path) > 1 else goal, world.heading, 0, Mode.MOVE)

    def _idle(self, world: WorldState) -> Action:
        return Action(self.lattice.index(world.base), world.heading, 0, Mode.MOVE)
