"""The octagon collision model (Eq. 18 with cut corners) against the paper's square-cornered rule.

The issue's example: two walls whose corners leave a diagonal gap of 0.495 m for the
0.44 m base. The square-cornered rule answered "infeasible"; the exact rule (the base
disc swept along each move) admits a plan, and so must the planner.
"""

from __future__ import annotations

import pytest

import expert.milp.bounds as bounds
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
    """Without the four corner regions (and the start's tangents) the scenario has no plan (a false "infeasible")."""

    def four_regions(grid, rect, radius):
        return move_regions(grid, rect, radius)[:4]

    for module in (collision, bounds, reach):
        monkeypatch.setattr(module, "move_regions", four_regions)
        monkeypatch.setattr(module, "start_tangents", lambda *args: ())  # the paper's rule: no start tangents
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


@pytest.mark.parametrize("detail", [2, 3, 4])
def test_finer_corner_tangents_keep_the_disc_clear(detail):
    """Every lattice point in a corner tangent's region (``corner_detail`` 2-4) is a radius or more from the rect."""
    from expert.milp.grid import Grid, corner_directions
    from fetchcarry_env.actions import Lattice

    area, rect, radius = Rect(0.0, 0.0, 5.0, 5.0), Rect(2.0, 2.0, 3.0, 3.0), 0.22
    grid = Grid.for_area(Lattice.over(area, 0.05), area, radius, corner_detail=detail)
    planes = move_regions(grid, rect, radius)
    assert len(planes) == 4 + 4 * len(corner_directions(detail))
    assert len(corner_directions(detail)) == {2: 3, 3: 7, 4: 11}[detail]
    for plane in planes[4:]:
        assert isinstance(plane, DiagonalPlane)
        for i in range(grid.domain.i_lo, grid.domain.i_hi + 1, 2):
            for j in range(grid.domain.j_lo, grid.domain.j_hi + 1, 2):
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


def diagonal_room_3() -> Scenario:
    """A diagonal gap of 0.467 m at 37 degrees between two walls' corners (``collision_study.diagonal_room`` seed 3)."""
    import numpy as np
    from collision_study import diagonal_room

    return diagonal_room(np.random.default_rng(3), "diagonal-3")


def test_finer_corners_find_a_plan_the_octagon_misses():
    """The octagon calls this layout infeasible (the exact search needs 4 phases); corner_detail=3 finds 5."""
    from fetchcarry_env.actions import Lattice

    scenario = diagonal_room_3()
    lattice = Lattice.over(scenario.area, 0.1)
    assert plan(scenario, lattice=lattice).status == "infeasible"
    finer = plan(scenario, lattice=lattice, corner_detail=3, time_limit=60.0)
    assert finer.status == "optimal" and len(finer.phases) == 5
    assert validate_plan(scenario, finer) == []


@pytest.mark.parametrize("bad", [0, 7, 1.5, True])
def test_corner_detail_is_checked(bad):
    with pytest.raises(ValueError, match="corner_detail"):
        plan(diagonal_gap(), corner_detail=bad)


@pytest.mark.parametrize("start", [(0.5, 0.7), (2.5, 0.4), (4.6, 4.5), (1.0, 2.5)])
def test_start_tangents_keep_the_first_move_clear(start):
    """Every lattice point beyond a start tangent is joined to the start by a segment a radius or more from the rect."""
    import numpy as np

    from expert.milp.grid import Grid, start_tangents
    from fetchcarry_env.actions import Lattice

    area, rect, radius = Rect(0.0, 0.0, 5.0, 5.0), Rect(2.0, 2.0, 3.0, 3.0), 0.22
    grid = Grid.for_area(Lattice.over(area, 0.05), area, radius)
    tangents = start_tangents(grid, start, rect, radius)
    assert len(tangents) == 2
    for plane in tangents:
        points = [grid.point(i, j) for i in range(0, 101, 3) for j in range(0, 101, 3) if plane.holds_at(i, j)]
        assert points
        for q in points:
            along = np.linspace(0.0, 1.0, 200)
            xs, ys = start[0] + along * (q[0] - start[0]), start[1] + along * (q[1] - start[1])
            assert min(rect.distance_to_point((x, y)) for x, y in zip(xs, ys, strict=True)) >= radius - 1e-9


def test_no_start_tangent_from_inside_the_grown_rectangle():
    from expert.milp.grid import Grid, start_tangents
    from fetchcarry_env.actions import Lattice

    area = Rect(0.0, 0.0, 5.0, 5.0)
    grid = Grid.for_area(Lattice.over(area, 0.05), area, 0.22)
    assert start_tangents(grid, (3.1, 2.5), Rect(2.0, 2.0, 3.0, 3.0), 0.22) == ()
