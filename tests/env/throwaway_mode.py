"""A throwaway observation mode: an occupancy grid of the floor with the robot on it, one module and one entry.

The test beside it registers :data:`OCCUPANCY` and uses it everywhere a mode is read: the
env, ``fetchcarry dataset render``, ``fetchcarry train bc --encoder cnn`` and the benchmark.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fetchcarry_env.geometry import Rect
from fetchcarry_env.observation import Capacity, WorldState
from fetchcarry_env.observations.modes import ObservationMode, image_side_option
from fetchcarry_env.scenario import Scenario
from fetchcarry_env.sim import Simulation


@dataclass
class OccupancyGrid:
    """One channel over ``extent``: 128 where a table or an obstacle stands, 255 at the robot's base, else 0."""

    extent: Rect
    side: int

    @property
    def shape(self) -> tuple[int, int, int]:
        return (1, self.side, self.side)

    def draw(self, scenario: Scenario, state: WorldState, sim: Simulation) -> dict[str, np.ndarray]:
        grid = np.zeros(self.shape, dtype=np.uint8)
        for rect in [t.rect for t in scenario.tables] + [o.rect for o in scenario.obstacles]:
            (i0, j0), (i1, j1) = self._cell(rect.min_x, rect.min_y), self._cell(rect.max_x, rect.max_y)
            grid[0, j0 : j1 + 1, i0 : i1 + 1] = 128
        i, j = self._cell(*state.base)
        grid[0, j, i] = 255
        return {"occupancy": grid}

    def _cell(self, x: float, y: float) -> tuple[int, int]:
        (width, height), n = self.extent.size, self.side
        column = int(np.clip((x - self.extent.min_x) / width * n, 0, n - 1))
        row = int(np.clip((y - self.extent.min_y) / height * n, 0, n - 1))
        return column, row


def make(extent: Rect, capacity: Capacity, options: dict[str, Any]) -> OccupancyGrid:
    return OccupancyGrid(extent, options["occupancy_size"])


OCCUPANCY = ObservationMode(
    "occupancy",
    "plus an occupancy grid of the floor with the robot (a test's throwaway mode)",
    keys=("occupancy",),
    channels=1,
    options=(image_side_option("occupancy_size", 16, "occupancy grid"),),
    side_option="occupancy_size",
    make=make,
)
