"""The octagon collision model (Eq. 18 with cut corners) against the paper's square-cornered rule.

The issue's example: two walls whose corners leave a diagonal gap of 0.495 m for the
0.44 m base. The square-cornered rule answered "infeasible"; the exact rule (the base
disc swept along each move) admits a plan, and so must the planner.
"""

from __future__ import annotations

import pytest

import expert.milp.collision as collision
import expert.milp.reach as reach
from expert.milp.grid import DiagonalPlane, IndexBox, move_regions
from expert.planner import plan
from expert.validate import validate_plan
from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import DeliveryObject, Obstacle, Robot, Scenario, Table, check_rules


def diagonal_gap() -> Scenario:
    """Walls top-left and bottom-right whose corners (2.0, 2.35) and (2.35, 2.0) are 0.495 m apart."""
    return Scenario(
        name="diagonal-gap",
        area=Rect(0.0, 0.0, 5.0, 5.0),
        robot=Robot((1.0, 1.0)),
        tables=(Table("table", Rect(3.2, 3.2, 3.8, 3.8)),),
        obstacles=(Obstacle("wall_a", Rect(0.0, 2.35, 2.0, 5.0)), Obstacle("wall_b", Rect(2.35, 0.0, 5.0, 2.0))),
        objects=(DeliveryObject("bottle", (3.25, 3.5), (3.75, 3.5)),),
    )


def test_diagonal_gap_is_passable():
    scenario = diagonal_gap()
    assert check_rules(scenario) == []
    result = plan(scenario)
    assert result.status == "optimal", result.stats
    assert validate_plan(scenario, result) == []


def test_square_cornered_rule_said_infeasible(monkeypatch):
    """Without the four corner regions the scenario has no plan (a false "infeasible")."""

    def four_regions(grid, rect, radius):
        return move_regions(grid, rect, radius)[:4]

    for module in (collision, reach):
        monkeypatch.setattr(module, "move_regions", four_regions)
    result = plan(diagonal_gap())
    assert result.status == "infeasible"
    assert "cannot get to" in result.stats["reason"]


def test_octagon_touches_the_rounded_rectangle():
    """Each corner plane is the 45-degree tangent of the corner's quarter circle, rounded to the lattice."""
    from expert.milp.grid import Grid
    from fetchcarry_env.actions import Lattice

    grid = Grid.for_area(Lattice.over(Rect(0.0, 0.0, 5.0, 5.0), 0.05), Rect(0.0, 0.0, 5.0, 5.0), 0.22)
    planes = move_regions(grid, Rect(2.0, 2.0, 3.0, 3.0), 0.22)
    assert len(planes) == 8 and all(isinstance(p, DiagonalPlane) for p in planes[4:])
    ne = planes[4]
    # x + y >= 6 + 0.22 sqrt(2) = 6.311 m: the smallest lattice sum of indices is ceil(6.311 / 0.05) = 127.
    assert (ne.su, ne.sv, ne.bound) == (1, 1, 127)
    box = IndexBox(0, 100, 0, 100)
    assert box.clip(ne) == IndexBox(27, 100, 27, 100)
    assert box.meets(ne) and not box.inside(ne)


@pytest.mark.parametrize("corner", [(1, 1), (-1, 1), (-1, -1), (1, -1)])
def test_corner_regions_keep_the_disc_clear(corner):
    """Every lattice point in a corner region is at least the radius from the rectangle (sampled exhaustively)."""
    from expert.milp.grid import Grid
    from fetchcarry_env.actions import Lattice

    area, rect, radius = Rect(0.0, 0.0, 5.0, 5.0), Rect(2.0, 2.0, 3.0, 3.0), 0.22
    grid = Grid.for_area(Lattice.over(area, 0.05), area, radius)
    plane = move_regions(grid, rect, radius)[4 + [(1, 1), (-1, 1), (-1, -1), (1, -1)].index(corner)]
    for i in range(grid.domain.i_lo, grid.domain.i_hi + 1):
        for j in range(grid.domain.j_lo, grid.domain.j_hi + 1):
            if plane.holds_at(i, j):
                assert rect.distance_to_point(grid.point(i, j)) >= radius - 1e-9


def test_clip_of_a_steep_plane_is_the_bounding_box_of_its_part():
    """``2 i + j >= 10`` on the box 0..10 x 0..10: i >= 0 (j = 10 allows it), j >= 0; on 0..10 x 0..4: i >= 3."""
    plane = DiagonalPlane(2, 1, 10)
    assert IndexBox(0, 10, 0, 10).clip(plane) == IndexBox(0, 10, 0, 10)
    assert IndexBox(0, 10, 0, 4).clip(plane) == IndexBox(3, 10, 0, 4)
    assert IndexBox(0, 2, 0, 10).clip(plane) == IndexBox(0, 2, 6, 10)
    mirrored = DiagonalPlane(-2, 1, -10)  # -2 i + j >= -10: i <= 5 + j / 2
    assert IndexBox(0, 10, 0, 4).clip(mirrored) == IndexBox(0, 7, 0, 4)
    assert plane.value_range(IndexBox(1, 3, 2, 5)) == (4, 11)
    assert mirrored.value_range(IndexBox(1, 3, 2, 5)) == (-4, 3)
