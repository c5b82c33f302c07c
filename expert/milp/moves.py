"""The least number of straight moves between two sets of lattice bases, exactly, under Eq. 18.

Eq. 18 (the octagon of every table and obstacle, :func:`expert.milp.grid.move_regions`, the
env's own rule) lets a base move straight from ``p`` to ``q`` when, for every rectangle, one
of its eight regions holds both. Which regions hold a lattice point is its *signature*
(one byte per rectangle, :func:`fetchcarry_env.regions.grid_bits`); points of one signature
reach exactly the same points in one move, and two signatures are joined by a move when, for
every rectangle, their bytes share a bit. A room's free lattice points have a few hundred
signatures (500-800 on the graded worlds' 7 x 7 m floors), so the least number of moves
between two sets of them is a breadth-first search on a small graph (:class:`LeastMoves`,
one search per source set, kept).

The skeleton's bounds (:mod:`expert.milp.bounds`) use it as the least phases of a step: it
is the exact least number of moves between two pose boxes, where the one-and-two-move test
it replaces counted every longer detour as three (ten phases against an optimum of fifteen
in an apartment).
"""

from __future__ import annotations

import functools

import numpy as np

from expert.milp.problem import Problem
from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import Point, Rect
from fetchcarry_env.regions import IndexBox, grid_bits, octagon_bits, octagon_rows

UNREACHABLE = 10_000  # moves: "no number of moves joins them" (larger than any plan's phases)
MAX_SIGNATURES = 4_000  # beyond this many (a thousand obstacles), no table: a step counts one move (a lower bound)


class LeastMoves:
    """All-pairs least moves between the signatures of one geometry (see the module docstring)."""

    def __init__(self, lattice: Lattice, domain: IndexBox, rects: tuple[Rect, ...], radius: float) -> None:
        self.domain = domain
        self.rects, self.radius, self.lattice = rects, radius, lattice
        width, height = domain.i_hi - domain.i_lo + 1, domain.j_hi - domain.j_lo + 1
        if rects:
            rows = np.array([octagon_rows(lattice, rect, radius) for rect in rects], dtype=np.int64)
            bits = grid_bits(rows, lattice.shape)[domain.i_lo : domain.i_hi + 1, domain.j_lo : domain.j_hi + 1]
        else:
            bits = np.full((width, height, 1), 0xFF, dtype=np.uint8)
        free = (bits != 0).all(axis=2)
        self.signatures, inverse = np.unique(bits[free], axis=0, return_inverse=True)
        self.cell = np.full((width, height), -1, dtype=np.int64)  # signature of each domain point, -1 where blocked
        self.cell[free] = inverse.reshape(-1)
        self._from_points: dict[Point, np.ndarray] = {}
        self._from_sets: dict[bytes, np.ndarray] = {}
        self.joined = self._joined(self.signatures) if len(self.signatures) <= MAX_SIGNATURES else None

    def _joined(self, signatures: np.ndarray) -> np.ndarray:
        """``[s, t]``: one move joins signatures ``s`` and ``t`` (every rectangle has a region holding both)."""
        out = np.ones((len(signatures), len(self.signatures)), dtype=bool)
        for r in range(self.signatures.shape[1]):
            out &= (signatures[:, None, r] & self.signatures[None, :, r]) != 0
        return out

    def signatures_in(self, box: IndexBox) -> np.ndarray:
        """The signatures of the free lattice points of ``box`` (none when it misses the domain)."""
        part = box.intersect(self.domain)
        if part.empty:
            return np.zeros(0, dtype=np.int64)
        d = self.domain
        cells = self.cell[part.i_lo - d.i_lo : part.i_hi - d.i_lo + 1, part.j_lo - d.j_lo : part.j_hi - d.j_lo + 1]
        return np.unique(cells[cells >= 0])

    def from_point(self, point: Point) -> np.ndarray:
        """``[t]``: the least moves from an off-lattice ``point`` (the start) to signature ``t`` (or UNREACHABLE)."""
        if point not in self._from_points:
            self._from_points[point] = self._from_point(point)
        return self._from_points[point]

    def _from_point(self, point: Point) -> np.ndarray:
        bits = np.array([octagon_bits(self.lattice, rect, self.radius, point) for rect in self.rects], dtype=np.uint8)
        if not len(self.rects):
            bits = np.array([0xFF], dtype=np.uint8)
        first = self._joined(bits[None, :])[0]  # the signatures one move from the point
        if not first.any():
            return np.full(len(self.signatures), UNREACHABLE, dtype=np.int64)
        if self.joined is None:
            return np.ones(len(self.signatures), dtype=np.int64)
        return 1 + self._search(first)

    def least_from(self, sources: np.ndarray) -> np.ndarray:
        """``[t]``: the least moves from a point of signatures ``sources`` to signature ``t`` (kept per set)."""
        key = sources.tobytes()
        if key not in self._from_sets:
            start = np.zeros(len(self.signatures), dtype=bool)
            start[sources] = True
            self._from_sets[key] = self._search(start)
        return self._from_sets[key]

    def _search(self, start: np.ndarray) -> np.ndarray:
        """Breadth-first search on the signatures from the set ``start`` (0 there); UNREACHABLE where none."""
        least = np.full(len(start), UNREACHABLE, dtype=np.int64)
        least[start] = 0
        frontier, moves = np.flatnonzero(start), 0
        while frontier.size:
            moves += 1
            reached = self.joined[frontier].any(axis=0) & (least == UNREACHABLE)
            least[reached] = moves
            frontier = np.flatnonzero(reached)
        return least

    def between(self, a: np.ndarray, b: np.ndarray) -> int:
        """The least moves from a point of signatures ``a`` to one of signatures ``b`` (0: a common signature)."""
        if not len(a) or not len(b):
            return UNREACHABLE
        if self.joined is None:
            return 0 if np.intersect1d(a, b).size else 1
        return int(self.least_from(a)[b].min())

    def steps(self, problem: Problem, where: IndexBox | None, entry: IndexBox) -> int:
        """The least moves from base set ``where`` (None: the scenario's start) to a point of ``entry``."""
        to = self.signatures_in(entry)
        if where is None:
            start = problem.start_index
            if start is None:
                return int(self.from_point(problem.scenario.robot.start)[to].min()) if len(to) else UNREACHABLE
            where = IndexBox(start[0], start[0], start[1], start[1])
        if not where.intersect(entry).empty:
            return 0
        return max(1, self.between(self.signatures_in(where), to))  # disjoint sets: one move at least


@functools.lru_cache(maxsize=8)
def geometry_moves(lattice: Lattice, domain: IndexBox, rects: tuple[Rect, ...], radius: float) -> LeastMoves:
    """The :class:`LeastMoves` of one geometry, shared by every problem on it (the decoupled plan's sub-problems,
    the expert's replanning within an episode)."""
    return LeastMoves(lattice, domain, rects, radius)


def problem_moves(problem: Problem) -> LeastMoves:
    """The :class:`LeastMoves` of ``problem``'s tables and obstacles on its lattice domain."""
    scenario = problem.scenario
    rects = tuple(t.rect for t in scenario.tables) + tuple(o.rect for o in scenario.obstacles)
    return geometry_moves(problem.grid.lattice, problem.grid.domain, rects, scenario.robot.radius)
