"""Pure geometry: frames, rectangles, segments and the exact swept-disc contact test."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fetchcarry_env.geometry import (
    HEADINGS,
    Rect,
    first_contact,
    heading_of,
    segment_intersects_rect,
    segment_rect_distance,
    to_robot_frame,
    to_world_frame,
)
from fetchcarry_env.kinematics import push_contact, push_headings, push_stroke, swept_rect, travel_cost

coords = st.floats(-5, 5, allow_nan=False)


@given(st.sampled_from(HEADINGS), coords, coords)
def test_robot_frame_round_trip(heading, forward, lateral):
    dx, dy = to_world_frame(heading, forward, lateral)
    assert to_robot_frame(heading, dx, dy) == pytest.approx((forward, lateral), abs=1e-9)


def test_lateral_is_left_of_heading():
    assert to_world_frame("+x", 0.0, 1.0) == (0.0, 1.0)
    assert to_world_frame("+y", 0.0, 1.0) == (-1.0, 0.0)
    assert to_world_frame("-y", 1.0, 0.0) == (0.0, -1.0)


def test_heading_of_axis_directions_only():
    assert heading_of((0.3, 0.0)) == "+x"
    assert heading_of((0.0, -0.2)) == "-y"
    assert heading_of((0.1, 0.1)) is None
    assert heading_of((0.0, 0.0)) is None


def test_segment_through_and_past_a_rectangle():
    box = Rect(1.0, 1.0, 2.0, 2.0)
    assert segment_intersects_rect((0.0, 1.5), (3.0, 1.5), box)
    assert not segment_intersects_rect((0.0, 2.0), (3.0, 2.0), box)  # grazing an edge is not crossing
    assert not segment_intersects_rect((0.0, 0.0), (0.9, 3.0), box)
    assert segment_rect_distance((0.0, 3.0), (3.0, 3.0), box) == pytest.approx(1.0)
    assert segment_rect_distance((0.0, 0.0), (0.5, 0.5), box) == pytest.approx(math.hypot(0.5, 0.5))


@pytest.mark.parametrize(
    ("end", "radius", "wall", "travelled"),
    [
        pytest.param((4.0, 0.0), 0.2, Rect(2.0, -1.0, 2.5, 1.0), 1.8, id="stops-at-first-contact"),
        pytest.param((100.0, 0.0), 0.22, Rect(5.0, -10.0, 5.001, 10.0), 4.78, id="long-move-no-tunnel-thin-wall"),
    ],
)
def test_disc_stops_at_first_contact(end, radius, wall, travelled):
    """From the origin along +x the disc stops where it first touches the wall; a long move does not tunnel."""
    t = first_contact((0.0, 0.0), end, radius, [wall])
    assert end[0] * t == pytest.approx(travelled)


def test_disc_touching_a_corner_stops_there():
    box = Rect(1.0, 1.0, 2.0, 2.0)
    # Moving along y = 0.9 towards +x: the disc of radius 0.2 meets the corner (1, 1).
    t = first_contact((0.0, 0.9), (3.0, 0.9), 0.2, [box])
    x = 3.0 * t
    assert math.hypot(x - 1.0, 0.9 - 1.0) == pytest.approx(0.2, abs=1e-9)


def test_clear_move_and_move_away():
    box = Rect(1.0, 1.0, 2.0, 2.0)
    assert first_contact((0.0, 0.0), (0.0, 3.0), 0.2, [box]) == 1.0
    # Touching at the start but moving away is free.
    assert first_contact((0.8, 1.5), (0.0, 1.5), 0.2, [box]) == 1.0


@given(coords, coords, coords, coords)
def test_swept_disc_never_ends_inside(x0, y0, x1, y1):
    box = Rect(-0.5, -0.5, 0.5, 0.5)
    radius = 0.2
    if box.distance_to_point((x0, y0)) < radius:
        return
    t = first_contact((x0, y0), (x1, y1), radius, [box])
    stop = (x0 + t * (x1 - x0), y0 + t * (y1 - y0))
    assert box.distance_to_point(stop) >= radius - 1e-6
    assert segment_rect_distance((x0, y0), stop, box.inflate(0)) >= 0.0


def test_travel_cost_is_the_papers_objective():
    assert travel_cost((0, 0), (3, 0)) == pytest.approx(3 + 0.1 * 3)
    assert travel_cost((0, 0), (1, 1)) == pytest.approx(2.0)


def test_push_contact_behind_the_rear_face():
    block = Rect(3.9, 3.9, 4.1, 4.1)
    assert push_contact(block, "+x") == pytest.approx((3.88, 4.0))
    assert push_contact(block, "-y") == pytest.approx((4.0, 4.12))
    assert push_headings("+x") == ("+x", "+y", "-y")


def test_push_stroke_clears_the_goal_on_the_lattice():
    block = Rect(3.9, 3.9, 4.1, 4.1)
    stroke = push_stroke(block, "+x", [((4.0, 4.0), 0.035)], 0.05)
    assert stroke == pytest.approx(0.15)
    moved = block.translate(stroke, 0.0)
    assert not moved.overlaps_disc((4.0, 4.0), 0.035 + 0.01)
    assert swept_rect(block, "-y", 0.15) == Rect(3.9, 3.75, 4.1, 4.1)
