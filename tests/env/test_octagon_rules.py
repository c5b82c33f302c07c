"""The env's motion and arm rules are the planner's model (docs/design.md, "The env's rules are the planner's model").

Each hand-made case is a step that the exact physical rules accepted (a clear swept disc,
a clear arm line) and the planner's model refuses: the env refuses it too now, as an
invalid action that moves nothing. Then the properties: every move the rule accepts is
physically clear, and every waypoint candidate lies outside the octagon of its own
table or obstacle.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from sim_worlds import FAR, action, make, room

from fetchcarry_env.actions import Lattice, Mode
from fetchcarry_env.families import FAMILY_NAMES, get_family
from fetchcarry_env.phases import CORNERS, PhaseLayout, waypoint_cell
from fetchcarry_env.regions import octagon_bits
from fetchcarry_env.rules import move_blockers, move_refusal, move_stop
from fetchcarry_env.scenario import Scenario


def _refused(env: gym.Env, step: tuple, names: str) -> None:
    """Step ``env``; the step must be refused, naming ``names``, and move nothing, though it is physically clear."""
    u = env.unwrapped
    before = u.state
    _, _, _, _, info = env.step(action(env, *step))
    assert info["invalid_action"] is not None and names in info["invalid_action"], info["invalid_action"]
    assert u.state == before and info["travel"] == 0.0 and info["contact"] is None


def test_a_move_past_a_corner_with_no_common_region_of_the_octagon_is_refused():
    """From the table's +y side to its +x side past the rounded corner: clear by 3 cm, but no region holds both."""
    env = make(room(start=(0.6, 2.35)))
    assert move_stop(env.unwrapped.scenario, (0.6, 2.35), (2.75, 2.2))[1] is None  # physically clear
    _refused(env, ((2.75, 2.2), "+x", FAR, Mode.MOVE), "'table'")
    env.close()


def test_a_lattice_point_between_the_octagon_and_the_rounded_table_is_refused():
    """(2.2, 2.1) is 0.2236 m from the table's corner (clear of the 0.22 m disc) but inside its 45-degree cut."""
    env = make(room(start=(2.5, 2.5)))
    assert move_stop(env.unwrapped.scenario, (2.5, 2.5), (2.2, 2.1))[1] is None
    _refused(env, ((2.2, 2.1), "+x", FAR, Mode.MOVE), "'table'")
    env.close()


def test_a_pick_whose_base_and_hand_share_no_side_of_an_obstacle_is_refused():
    """The arm line passes 3 mm below a post's corner: clear, but the base is left of and below it, the hand right."""
    scenario = room(
        start=(0.5, 1.2),
        obstacles={"post": ((0.8, 1.23), (0.85, 1.28))},
        objects=[{"id": "bottle", "start": [1.15, 1.25], "goal": [1.8, 1.8]}],
    )
    env = make(scenario)
    _refused(env, ((0.5, 1.2), "+x", FAR, Mode.PICK), "'post'")
    env.close()


def test_a_pick_from_a_corner_zone_of_an_obstacle_is_refused():
    """The base stands 0.25 m diagonally off a post's corner: clear, outside its octagon, but on no side of it."""
    scenario = Scenario.from_dict(
        {
            "format": "fetchcarry-scenario/1",
            "name": "corner-pose",
            "area": {"min": [0.0, 0.0], "max": [3.0, 3.0]},
            "robot": {"start": [0.55, 0.5], "heading": "+x"},
            "tables": [{"id": "table", "min": [1.0, 0.2], "max": [2.0, 1.0], "height": 0.7}],
            "obstacles": [{"id": "post", "min": [0.3, 0.3], "max": [0.35, 0.35]}],
            "objects": [{"id": "bottle", "start": [1.2, 0.5], "goal": [1.8, 0.8]}],
        }
    )
    env = make(scenario)
    _refused(env, ((0.55, 0.5), "+x", FAR, Mode.PICK), "'post'")
    env.close()


def test_a_push_stroke_whose_ends_share_no_side_of_an_obstacle_is_refused():
    """The stroke ends 0.25 m diagonally off a post's corner: clear, in a common corner cut, but on no common side."""
    env = make(
        room(
            start=(0.45, 1.5),
            clutter={"block": ((1.1, 1.45), (1.2, 1.55))},
            obstacles={"post": ((0.70, 1.20), (0.75, 1.30))},
        )
    )
    assert move_stop(env.unwrapped.scenario, (0.45, 1.5), (0.55, 1.5))[1] is None
    _refused(env, ((0.55, 1.5), "+x", FAR, Mode.PUSH), "'post'")
    env.close()


def test_a_pick_half_a_millimetre_beyond_the_posture_s_range_is_refused():
    """The env's reach is the planner's (the exact ranges); its 1 mm tolerance took poses the planner does not have."""
    env = make(room(start=(2.45, 1.2), objects=[{"id": "bottle", "start": [1.7495, 1.2], "goal": [1.8, 1.8]}]))
    _refused(env, ((2.45, 1.2), "-x", FAR, Mode.PICK), "reach")  # forward 0.7005 m, the range 0.55-0.70 m
    env.close()


@pytest.mark.parametrize("family", ["basic", "corridor", "push", "apartment", "unseen-layouts"])
def test_every_move_the_rule_accepts_is_physically_clear(family):
    """Random moves between lattice points and from the start: accepted means the swept disc touches nothing."""
    env = gym.make("FetchCarryPush-v0", family=family)
    rng = np.random.default_rng(11)
    accepted = 0
    for seed in range(3):
        env.reset(seed=seed)
        scenario, lattice = env.unwrapped.scenario, env.unwrapped.lattice
        cells = rng.integers(0, lattice.shape, size=(600, 2))
        starts = [scenario.robot.start] * 100 + [lattice.point(*c) for c in cells[:500].tolist()]
        ends = [lattice.point(*c) for c in cells[100:].tolist()] + [lattice.point(*c) for c in cells[:100].tolist()]
        for start, end in zip(starts, ends, strict=True):
            if move_refusal(scenario, lattice, start, end) is None:
                accepted += 1
                assert move_stop(scenario, start, end)[1] is None, (start, end)
    assert accepted > 50
    env.close()


@pytest.mark.parametrize("resolution", [0.05, 0.1, 0.2])
def test_every_waypoint_lies_outside_the_octagon_of_its_table_or_obstacle(resolution):
    """Waypoints lie beyond both sides of their corner (grown by the radius): outside the octagon, never in its cut."""
    layout = PhaseLayout()
    checked = 0
    for family in FAMILY_NAMES:
        extent = get_family(family).extent
        lattice = Lattice.over(extent, resolution)
        scenario = get_family(family).sample(np.random.default_rng(3))
        radius = scenario.robot.radius
        for _name, rect in move_blockers(scenario):
            for corner in range(len(CORNERS)):
                for i in range(layout.corner_cells):
                    for j in range(layout.corner_cells):
                        point = lattice.point(*waypoint_cell(lattice, rect, radius, corner, i, j))
                        bits = octagon_bits(lattice, rect, radius, point)
                        assert bin(bits & 0b1111).count("1") == 2, (family, rect, corner, i, j, point)
                        checked += 1
    assert checked > 100
