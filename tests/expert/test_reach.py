"""Reachability before any MILP: the unreachable action, the narrowest gap on the way, the lattice gap rule."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from expert.milp.problem import prepare
from expert.milp.reach import narrowest_gap, unreachable_reason
from expert.planner import plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_multi
from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import DeliveryObject, Obstacle, Robot, Scenario, Table, check_rules

OFFSETS = [k * 0.005 for k in range(10)]  # metres: where the gap's middle falls between two 0.05 m lattice lines


def wall_with_gap(gap: float, offset: float) -> Scenario:
    """A wall at x = 2.0-2.3 with a ``gap`` (metres) centred at y = 2.5 + ``offset``; the table behind it."""
    middle = 2.5 + offset
    return Scenario(
        name="wall-with-gap",
        area=Rect(0.0, 0.0, 5.0, 5.0),
        robot=Robot((0.5, 0.5)),  # no first move reaches through the gap: the gap is passed between lattice points
        tables=(Table("table", Rect(3.5, 2.2, 4.1, 2.8)),),
        obstacles=(
            Obstacle("low", Rect(2.0, 0.0, 2.3, middle - gap / 2)),
            Obstacle("high", Rect(2.0, middle + gap / 2, 2.3, 5.0)),
        ),
        objects=(DeliveryObject("bottle", (3.6, 2.5), (4.0, 2.5)),),
    )


def passable(scenario: Scenario) -> bool:
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05))
    assert problem.infeasible is None
    return unreachable_reason(problem) is None


@pytest.mark.parametrize(("gap", "count"), [(0.435, 0), (0.44, 1), (0.45, 3), (0.47, 7), (0.485, 9), (0.49, 10)])
def test_gap_rule_on_the_lattice(gap, count):
    """A gap is passed where a lattice line lies a radius from both sides: of 10 alignments, ``count`` pass.

    Below 2 r (0.44 m) never, from 2 r + resolution (0.49 m) always, in between the share
    of alignments grows with the gap (``docs/formulation.md``, "Reachability").
    """
    assert sum(passable(wall_with_gap(gap, offset)) for offset in OFFSETS) == count


def ringed(count: int) -> Scenario:
    """``count`` objects of the multi family; table_2 (4, 4) ringed by walls with a 0.40 m gap in the west wall."""
    walls = (
        Obstacle("ring_s", Rect(3.0, 3.0, 5.0, 3.1)),
        Obstacle("ring_n", Rect(3.0, 4.9, 5.0, 5.0)),
        Obstacle("ring_e", Rect(4.9, 3.1, 5.0, 4.9)),
        Obstacle("ring_w_low", Rect(3.0, 3.1, 3.1, 3.8)),
        Obstacle("ring_w_high", Rect(3.0, 4.2, 3.1, 4.9)),
    )
    scenario = dataclasses.replace(draw_paper_multi(np.random.default_rng(5), count), obstacles=walls)
    assert check_rules(scenario) == []
    return scenario


@pytest.mark.parametrize("count", [1, 6, 10])
def test_unreachable_table_is_reported_before_any_milp(count):
    """At any size: no MILP is solved, the reason names the action's object and the 0.40 m gap between its sides."""
    result = plan(ringed(count), time_limit=60.0)
    assert result.status == "infeasible"
    assert result.stats["phases_tried"] == [] and "solves" not in result.stats
    reason = result.stats["reason"]
    assert "cannot get to any pose that" in reason and "'object_" in reason
    assert "0.400 m, between 'ring_w_low' and 'ring_w_high'" in reason


def test_narrowest_gap_of_a_closed_room_is_none_wide():
    """Walls with no gap at all: the widest way crosses a wall, so the gap is 0 m (the way is closed)."""
    scenario = wall_with_gap(0.0, 0.0)
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05))
    boxes = [o.box for o in problem.options if o.kind == "pick"]
    gap = narrowest_gap(problem, boxes)
    assert gap is not None and gap.width == 0.0 and set(gap.sides) == {"low", "high"}
    assert "closed" in unreachable_reason(problem)
