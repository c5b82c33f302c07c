"""The planner against an exhaustive lattice search written apart from it (``lattice_search.py``).

On single-object scenarios in a small room (a 0.1 m lattice, so the search can look at
every pair of points), the planner must find a plan exactly when the exhaustive search
does (no false "infeasible"), with at most one phase more (a straight move grazing a
rounded corner that the octagon splits in two), and with the same number of phases an
Eq. 1 no better than the search's (the search uses the exact swept-disc rule and the
exact arm line, which the MILP approximates from the safe side) and within the gap
measured before (60 such rooms, at most 0.58 m; ``docs/formulation.md``, "Collision model",
has the study of diagonal gaps and corridors, where the octagon loses phases).
"""

from __future__ import annotations

import numpy as np
import pytest
from lattice_search import search

from expert.planner import plan
from expert.validate import validate_plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import DeliveryObject, Obstacle, Robot, Scenario, Table, check_rules

RESOLUTION = 0.1  # metres: coarse, so the exhaustive search stays small
EQ1_GAP = 0.6  # metres: the largest Eq. 1 excess over the exact rule measured (0.58 m, docs/formulation.md)


def random_room(rng: np.random.Generator, name: str) -> Scenario:
    """A 3 x 3 m room, a 0.5 m table with the object moved across it, one to three walls, a random start."""
    area = Rect(0.0, 0.0, 3.0, 3.0)
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
            area=area,
            robot=Robot((sx, sy)),
            tables=(Table("table", Rect(tx - 0.25, ty - 0.25, tx + 0.25, ty + 0.25)),),
            obstacles=tuple(walls),
            objects=(obj,),
        )
        if not check_rules(scenario):
            return scenario


@pytest.mark.parametrize("seed", [*range(8), 16, 20])  # 16: the largest gap measured; 20: one phase more
def test_planner_agrees_with_the_exhaustive_search(seed):
    scenario = random_room(np.random.default_rng(seed), f"room-{seed}")
    lattice = Lattice.over(scenario.area, RESOLUTION)
    exact = search(scenario, lattice, max_phases=8)
    result = plan(scenario, lattice=lattice, time_limit=60.0)
    if exact.phases is None:
        assert result.status == "infeasible", result.stats
        return
    assert result.status == "optimal", result.stats
    assert validate_plan(scenario, result) == []
    assert exact.phases <= len(result.phases) <= exact.phases + 1
    if len(result.phases) == exact.phases:
        assert exact.objective - 1e-6 <= result.objective <= exact.objective + EQ1_GAP
