"""The high-level action: one phase of the paper's formulation.

An action says where the base goes (a point of a lattice over the floor), the heading
it has there, the arm posture, and what the arm does: nothing, pick, place or push.
It is a ``MultiDiscrete([nx, ny, 4, n_postures, 4])`` vector so that
stable-baselines3 trains on it as it is, and every phase of an expert plan is exactly
one such action (the planner puts its base positions on the same lattice).

Semantics (the environment executes them, the planner models them):

``move`` (mode 0)
    The base slides along the straight segment to the cell and turns to the heading
    (a round base turns in place, so turning never collides).
``pick`` (mode 1)
    As ``move``, then the hand, in the posture, grasps the object whose centre lies
    within the posture's ranges as seen from the new pose, and lifts it.
``place`` (mode 2)
    As ``move``, then the held object is put down at its goal, which must lie within
    the posture's ranges. As in the paper (Eq. 12), placing an object delivers it.
``push`` (mode 3)
    The base turns to the heading where it stands, the arm puts the hand against the
    rear face of a piece of clutter (the face away from the stroke), and the base
    strokes in a straight axis-aligned line to the cell, so the clutter moves by the
    stroke. The stroke runs along the heading (a forward push) or at right angles to
    it (a lateral push), never backwards. The hand may be empty or hold an object (the
    paper's push-aside while carrying the object to be placed): a held object stays in
    the hand, keeps its offset from the base and moves with it.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

import numpy as np

from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect
from fetchcarry_env.jsontext import describe


class Mode(IntEnum):
    """What the arm does at the end of the phase."""

    MOVE = 0
    PICK = 1
    PLACE = 2
    PUSH = 3


@dataclass(frozen=True)
class Lattice:
    """The points the base may be sent to: ``origin + (i, j) * resolution``.

    ``shape`` is ``(nx, ny)``; point ``(i, j)`` has ``0 <= i < nx`` and ``0 <= j < ny``.
    """

    origin: Point  # metres, the point (0, 0)
    resolution: float  # metres between neighbouring points
    shape: tuple[int, int]

    @classmethod
    def over(cls, extent: Rect, resolution: float = 0.05) -> Lattice:
        """The lattice covering ``extent`` from its min corner, ``resolution`` metres apart."""
        if resolution <= 0:
            raise ValueError(f"lattice resolution must be positive, got {resolution}")
        nx = math.floor((extent.max_x - extent.min_x) / resolution + 1e-9) + 1
        ny = math.floor((extent.max_y - extent.min_y) / resolution + 1e-9) + 1
        return cls((extent.min_x, extent.min_y), resolution, (nx, ny))

    def point(self, i: int, j: int) -> Point:
        """World coordinates (metres) of lattice point ``(i, j)``."""
        return (self.origin[0] + i * self.resolution, self.origin[1] + j * self.resolution)

    def index(self, p: Point) -> tuple[int, int]:
        """The nearest lattice point's ``(i, j)``, clipped to the lattice."""
        i = int(np.clip(round((p[0] - self.origin[0]) / self.resolution), 0, self.shape[0] - 1))
        j = int(np.clip(round((p[1] - self.origin[1]) / self.resolution), 0, self.shape[1] - 1))
        return (i, j)

    def snap(self, p: Point) -> Point:
        """The nearest lattice point to ``p`` (each coordinate moves at most half a cell)."""
        return self.point(*self.index(p))

    def on_lattice(self, p: Point, tol: float = 1e-6) -> bool:
        return math.dist(self.snap(p), p) <= tol

    def axis_points(self, axis: int) -> np.ndarray:
        """Coordinates (metres) of the lattice along ``axis`` (0: x, 1: y)."""
        return self.origin[axis] + self.resolution * np.arange(self.shape[axis])


@dataclass(frozen=True)
class Action:
    """One phase, decoded: the target lattice point, heading, posture index and mode."""

    cell: tuple[int, int]
    heading: Heading
    posture: int
    mode: Mode

    def to_array(self) -> np.ndarray:
        """The ``MultiDiscrete`` vector ``[i, j, heading, posture, mode]``."""
        return np.array(
            [self.cell[0], self.cell[1], HEADINGS.index(self.heading), self.posture, int(self.mode)],
            dtype=np.int64,
        )

    @classmethod
    def from_array(cls, vector: np.ndarray | list[int]) -> Action:
        i, j, heading, posture, mode = (int(v) for v in vector)
        return cls((i, j), HEADINGS[heading], posture, Mode(mode))


def action_nvec(lattice: Lattice, max_postures: int) -> np.ndarray:
    """``nvec`` of the ``MultiDiscrete`` action space for a lattice and a posture capacity."""
    return np.array([lattice.shape[0], lattice.shape[1], len(HEADINGS), max_postures, len(Mode)], dtype=np.int64)


_KIND_NAMES = {"U": "strings", "S": "bytes", "c": "complex numbers", "M": "dates", "m": "time spans", "V": "records"}


def action_vector(action: Any, nvec: np.ndarray, components: Sequence[str]) -> np.ndarray:
    """``action`` as an ``int64`` vector inside ``MultiDiscrete(nvec)``; ``ValueError`` naming the problem.

    Integers of any dtype, and floats or Python numbers that are whole, are accepted;
    strings, complex numbers, ragged or nested sequences, non-numbers in object arrays,
    NaN and infinities are refused, as is a value outside ``[0, nvec[i])`` (named by its
    component).
    """
    expected = f"{len(nvec)} integers ({', '.join(components)})"
    try:
        array = np.asarray(action)
    except (ValueError, TypeError):  # a ragged sequence
        raise ValueError(f"action must be an array of {expected}, got {describe(action)}") from None
    if array.shape != nvec.shape:
        raise ValueError(f"action must have shape {nvec.shape} ({', '.join(components)}), got {array.shape}")
    shown = describe(array.tolist())
    if array.dtype.kind in _KIND_NAMES:
        raise ValueError(f"action must hold integers, got {_KIND_NAMES[array.dtype.kind]}: {shown}")
    values = [_whole(v) for v in array.tolist()]
    if any(v is None for v in values):
        raise ValueError(f"action must hold integers, got {shown}")
    for name, value, size in zip(components, values, nvec.tolist(), strict=True):
        if not 0 <= value < size:
            raise ValueError(
                f"action {shown} is outside the action space: {name} = {describe(value)} is not in [0, {size})"
            )
    return np.array(values, dtype=np.int64)


def _whole(value: Any) -> int | None:
    """``value`` as an int if it is a whole real number (a bool counts as 0 or 1), else None."""
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real) and math.isfinite(value) and float(value).is_integer():
        return int(value)
    return None
