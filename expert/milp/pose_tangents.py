"""The corner tangents seen from the poses (``plan(..., pose_tangents=True)``), kept only where they add a move.

A move from a pose (a lattice point of a pick, place or push option) past a rounded
corner along a tangent the model lacks needs one more phase. Every line through a pose
point that touches a rectangle grown by the radius gives a direction
(:func:`expert.milp.grid.pose_normals`); the region beyond the rectangle's tangent with
that normal holds the point, so a move from it to any lattice point in that region
clears the rectangle exactly. Such directions are many (a hundred and more per rectangle
on the 0.05 m lattice), and each costs a binary per move; most add nothing. One is kept
when some pose point ``w`` in its region and some free lattice point ``q`` in it are not
already in one common region of that rectangle (the sides and ``corner_detail``'s
tangents), and ``q`` is allowed from ``w`` by every other rectangle with all its
candidate directions: a move the model did not have, and one the others let pass. Of
those, every one is kept at a tight corner (closer than ``2 r + TIGHT_MARGIN`` to another
rectangle or the area's edge: a gap or a corridor, where the exact direction decides
whether the base passes), and one per :data:`BIN` of angle elsewhere. Dropping a
direction only removes moves, so the model stays safe either way.

Units: lattice indices.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import DiagonalPlane, Grid, Plane, corner_normals, move_regions, pose_normals
from expert.milp.options import PoseOption
from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import Scenario


def _members(planes: list[Plane], ii: np.ndarray, jj: np.ndarray) -> np.ndarray:
    """Shape (planes, points): whether each lattice point ``(ii[k], jj[k])`` lies in each plane."""
    out = np.zeros((len(planes), ii.shape[0]), dtype=bool)
    for n, plane in enumerate(planes):
        if isinstance(plane, DiagonalPlane):
            out[n] = plane.su * ii + plane.sv * jj >= plane.bound
        else:
            index = ii if plane.axis == 0 else jj
            out[n] = index <= plane.bound if plane.upper else index >= plane.bound
    return out


def _shared(at_pose: np.ndarray, at_point: np.ndarray) -> np.ndarray:
    """Shape (poses, points): whether some plane holds both (from the two membership tables of the same planes)."""
    return (at_pose.T.astype(np.float32) @ at_point.astype(np.float32)) > 0


BIN = 0.1  # radians: at an open corner, of the useful directions in one bin this wide only the one holding most poses
TIGHT_MARGIN = 0.3  # metres: a corner closer than 2 radius + this to another rect or the edge is tight: all kept


def _tight(scenario: Scenario, rect: Rect, normal: tuple[int, int]) -> bool:
    """Whether the corner of ``rect`` that ``normal`` touches is tight (:data:`TIGHT_MARGIN`): a gap or a corridor."""
    corner = (rect.max_x if normal[0] > 0 else rect.min_x, rect.max_y if normal[1] > 0 else rect.min_y)
    area = scenario.area
    edge = min(corner[0] - area.min_x, area.max_x - corner[0], corner[1] - area.min_y, area.max_y - corner[1])
    others = [r for r in (*(t.rect for t in scenario.tables), *(o.rect for o in scenario.obstacles)) if r != rect]
    return min([edge, *(r.distance_to_point(corner) for r in others)]) < 2 * scenario.robot.radius + TIGHT_MARGIN


def _binned(normals: list[tuple[tuple[int, int], int]]) -> tuple[tuple[int, int], ...]:
    """From ``(normal, poses held)`` pairs: per run of :data:`BIN` radians (by angle), the normal holding most poses."""
    ordered = sorted(normals, key=lambda item: math.atan2(item[0][1], item[0][0]))
    out: list[tuple[int, int]] = []
    start, best = None, None
    for normal, held in ordered:
        angle = math.atan2(normal[1], normal[0])
        if start is None or angle - start > BIN:
            if best is not None:
                out.append(best[0])
            start, best = angle, (normal, held)
        elif held > best[1]:
            best = (normal, held)
    if best is not None:
        out.append(best[0])
    return tuple(out)


def pose_grid(scenario: Scenario, grid: Grid, options: list[PoseOption], deadline: Deadline = NEVER) -> Grid:
    """``grid`` with, per table and obstacle, the pose directions that add a move (see the module)."""
    radius = scenario.robot.radius
    poses = sorted(
        {
            (i, j)
            for o in options
            for box in {o.box, o.end_box}
            for i in range(box.i_lo, box.i_hi + 1)
            for j in range(box.j_lo, box.j_hi + 1)
        }
    )
    if not poses:
        return grid
    rects = [*(t.rect for t in scenario.tables), *(o.rect for o in scenario.obstacles)]
    points = [grid.point(i, j) for i, j in poses]
    candidates = []
    for rect in rects:
        deadline.check()
        regular = corner_normals(grid.corner_detail)
        candidates.append((rect, tuple(n for n in pose_normals(grid, points, rect, radius) if n not in regular)))
    full = dataclasses.replace(grid, extra_normals=tuple(candidates))
    d = grid.domain
    ii, jj = (a.ravel() for a in np.meshgrid(np.arange(d.i_lo, d.i_hi + 1), np.arange(d.j_lo, d.j_hi + 1)))
    pi, pj = np.array([p[0] for p in poses]), np.array([p[1] for p in poses])
    tables = []  # per rect: (base count, memberships at the domain points, at the poses) over all planes
    for rect in rects:
        planes = list(move_regions(full, rect, radius))
        base = len(move_regions(grid, rect, radius))
        tables.append((base, _members(planes, ii, jj), _members(planes, pi, pj)))
    free = np.logical_and.reduce([at_point.any(axis=0) for _, at_point, _ in tables])
    allowed = [_shared(at_pose, at_point) for _, at_point, at_pose in tables]  # with every candidate
    kept = []
    for r, (rect, normals) in enumerate(candidates):
        deadline.check()
        base, at_point, at_pose = tables[r]
        others = np.logical_and.reduce([a for s, a in enumerate(allowed) if s != r] or [np.ones_like(allowed[r])])
        new = others & ~_shared(at_pose[:base], at_point[:base]) & free[None, :]  # (poses, points)
        counts = at_pose[base:].astype(np.float32) @ new.astype(np.float32)  # (candidates, points)
        useful = ((counts > 0) & at_point[base:]).any(axis=1)
        held = at_pose[base:].sum(axis=1)
        found = [(n, int(h)) for n, keep, h in zip(normals, useful, held, strict=True) if keep]
        tight = tuple(n for n, _ in found if _tight(scenario, rect, n))
        kept.append((rect, tight + _binned([(n, h) for n, h in found if n not in tight])))
    return dataclasses.replace(grid, extra_normals=tuple(kept))
