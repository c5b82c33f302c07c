"""The MILP's parts: lattice rounding, pose options, push preprocessing, bounds and the model itself."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from planner_cases import BLOCK, bar, one_table, push_scene

from expert.milp.bounds import counting_bound, min_travel, skeleton
from expert.milp.build import build
from expert.milp.collision import Infeasible
from expert.milp.grid import Condition, Grid, HalfPlane, IndexBox, split_box
from expert.milp.problem import prepare
from expert.milp.reach import reachable_mask, unreachable_reason
from expert.planner import plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.families import draw_paper_basic, draw_paper_corridor, draw_paper_multi, draw_paper_push
from fetchcarry_env.geometry import Rect
from fetchcarry_env.kinematics import arm_line_clear, push_contact, reaches, travel_cost
from fetchcarry_env.scenario import DeliveryObject

LATTICE_AREA = Rect(-1.0, -1.0, 6.0, 6.0)


def problem_of(scenario, resolution=0.05):
    return prepare(scenario, Lattice.over(scenario.area, resolution))


def sample_scenarios():
    rng = np.random.default_rng(5)
    return [
        draw_paper_basic(rng, "I"),
        draw_paper_basic(rng, "III"),
        draw_paper_push(rng, "C"),
        draw_paper_push(rng, "E"),
        draw_paper_corridor(rng),
        draw_paper_multi(rng, 2),
    ]


# ---------------------------------------------------------------------- lattice rounding
def test_rounding_is_exact_and_inwards():
    grid = Grid.for_area(Lattice.over(LATTICE_AREA, 0.05), LATTICE_AREA, 0.22)
    assert grid.index_at_most(0, 0.0) == 20  # exactly on a point
    assert grid.index_at_most(0, 0.049) == 20
    assert grid.index_at_least(0, 0.001) == 21
    assert grid.index_at_least(0, 1.45 - 1e-12) == 49  # float noise does not lose the point 1.45
    # The domain keeps the whole disc inside the area (Eq. 27): 0.22 m from each edge, rounded inwards.
    assert grid.domain == IndexBox(5, 135, 5, 135)
    assert grid.point(5, 5) == pytest.approx((-0.75, -0.75))


def test_continuous_bounds_round_to_the_same_points():
    lattice = Lattice.over(LATTICE_AREA, 0.05)
    integral = Grid.for_area(lattice, LATTICE_AREA, 0.22, integral=True)
    continuous = Grid.for_area(lattice, LATTICE_AREA, 0.22, integral=False)
    assert integral.upper(7) == 7 and integral.lower(7) == 7
    assert round(continuous.upper(7)) == 7 and round(continuous.lower(7)) == 7
    assert continuous.upper(7) > 7.4 and continuous.lower(7) < 6.6


def test_split_box_cuts_where_a_condition_changes():
    box = IndexBox(0, 9, 0, 9)
    left = HalfPlane(0, True, 3)  # i <= 3
    below = HalfPlane(1, True, 5)  # j <= 5
    pieces = split_box(box, [Condition((left, below))])  # outside the quadrant i > 3 and j > 5
    points = {
        (i, j)
        for piece, _ in pieces
        for i in range(piece.i_lo, piece.i_hi + 1)
        for j in range(piece.j_lo, piece.j_hi + 1)
    }
    expected = {(i, j) for i in range(10) for j in range(10) if i <= 3 or j <= 5}
    assert points == expected
    assert len(pieces) <= 2
    tagged = split_box(box, [Condition((left,), tag="state")])
    assert {tags for _, tags in tagged} == {frozenset(), frozenset({"state"})}
    assert split_box(box, [Condition((HalfPlane(0, True, -1),))]) == []


# ---------------------------------------------------------------------- pose options
@pytest.mark.parametrize("scenario", sample_scenarios(), ids=lambda s: s.name)
def test_every_point_of_every_option_is_a_valid_pose(scenario):
    """Soundness of the preprocessing: reach (Eq. 14-17), base clearance (Eq. 18), arm line (Eq. 19)."""
    problem = problem_of(scenario)
    radius = scenario.robot.radius
    blockers = [t.rect for t in scenario.tables] + [o.rect for o in scenario.obstacles]
    static_clutter = [c.rect for c in scenario.clutter if c.id not in problem.pushes.pushable]
    postures = {p.name: p for p in scenario.robot.postures}
    assert problem.options
    for option in problem.options:
        assert not option.box.empty
        posture = postures[option.posture]
        cells = option.push.cells if option.push else (0, 0)
        for i, j in itertools.product(
            range(option.box.i_lo, option.box.i_hi + 1), range(option.box.j_lo, option.box.j_hi + 1)
        ):
            base = problem.grid.point(i, j)
            end = problem.grid.point(i + cells[0], j + cells[1])
            assert reaches(posture, base, option.heading, option.hand, tol=1e-6), (option, base)
            for point in (base, end):
                assert scenario.area.contains_disc(point, radius, tol=1e-6)
                assert all(r.distance_to_point(point) >= radius - 1e-6 for r in blockers), (option, point)
            hand_end = (option.hand[0] + end[0] - base[0], option.hand[1] + end[1] - base[1])
            for a, b in ((base, option.hand), (end, hand_end)):
                assert arm_line_clear(a, b, [o.rect for o in scenario.obstacles] + static_clutter), (option, a, b)


def test_options_cover_every_reaching_pose_when_nothing_is_in_the_way():
    """Completeness: without obstacles or clutter, a lattice point is in a pick box iff it reaches and is clear."""
    scenario = draw_paper_basic(np.random.default_rng(0), "V")
    scenario = dataclasses.replace(scenario, obstacles=())
    problem = problem_of(scenario)
    obj = scenario.objects[0]
    table = scenario.tables[0].rect
    for heading in ("+x", "+y", "-x", "-y"):
        for posture in scenario.robot.postures:
            boxes = [
                o.box
                for o in problem.options
                if o.kind == "pick" and o.heading == heading and o.posture == posture.name
            ]
            covered = {(i, j) for b in boxes for i in range(b.i_lo, b.i_hi + 1) for j in range(b.j_lo, b.j_hi + 1)}
            wanted = set()
            for i in range(10, 80):
                for j in range(10, 80):
                    base = problem.grid.point(i, j)
                    if (
                        reaches(posture, base, heading, obj.start, tol=1e-9)
                        and table.distance_to_point(base) >= 0.22 - 1e-9
                    ):
                        wanted.add((i, j))
            assert covered == wanted, (heading, posture.name)


def test_arm_line_rules_out_options_behind_an_obstacle():
    """A wall between the west pose and the cup: no pick from the west (Eq. 19)."""
    scenario = one_table(area=Rect(0.0, 0.0, 4.0, 3.0))
    plain = {o.heading for o in problem_of(scenario).options if o.kind == "pick"}
    # A thin post right by the table's west edge, on the arm line y = 1.2 (the base stands 0.3 m away).
    walled = one_table(obstacles=(Rect(1.70, 1.15, 1.75, 1.25),))
    blocked = {o.heading for o in problem_of(walled).options if o.kind == "pick"}
    assert "+x" in plain and "+x" not in blocked and blocked


# ---------------------------------------------------------------------- push preprocessing
def test_stroke_is_a_whole_number_of_cells_that_clears_the_goal():
    scenario = push_scene("plain", {"block": BLOCK})
    problem = problem_of(scenario)
    obj = scenario.objects[0]
    assert problem.covers == {"bottle": ("block",)}
    assert {c.direction for c in problem.pushes.candidates} == {"+x", "+y", "-x", "-y"}
    for candidate in problem.pushes.candidates:
        assert candidate.stroke == pytest.approx(0.15)  # 0.07 + 0.035 + 0.01 = 0.115, rounded up to 0.15
        assert abs(candidate.cells[0]) + abs(candidate.cells[1]) == 3
        assert not candidate.end.overlaps_disc(obj.goal, obj.radius + 0.0099)
        assert candidate.contact == push_contact(BLOCK, candidate.direction)


def test_blocked_directions_say_why():
    scenario = push_scene("fig3", {"block": BLOCK, "n": bar("+y"), "w": Rect(3.82, 4.04, 3.88, 4.10)})
    scenario = dataclasses.replace(
        scenario, tables=(scenario.tables[0], dataclasses.replace(scenario.tables[1], rect=Rect(3.7, 3.86, 4.3, 4.3)))
    )
    blocked = problem_of(scenario).pushes.blocked
    assert "'n'" in blocked[("block", "+y")]
    assert "'w'" in blocked[("block", "-x")]
    assert "table" in blocked[("block", "-y")]
    assert ("block", "+x") not in blocked


def test_pushable_neighbours_give_precedence_and_exclusions():
    """Two blocks side by side on the goal: pushing one towards the other waits for it; colliding ends exclude."""
    scenario = push_scene("two", {"west": Rect(3.90, 3.93, 3.99, 4.07), "east": Rect(4.01, 3.93, 4.10, 4.07)})
    plan_ = problem_of(scenario).pushes
    assert plan_.pushable == ("east", "west")
    index = {c.key: n for n, c in enumerate(plan_.candidates)}
    assert (index[("west", "+x")], "east") in plan_.precedence
    assert (index[("east", "-x")], "west") in plan_.precedence
    # West pushed +x would slide into where east ends up after its own +x push.
    assert tuple(sorted((index[("west", "+x")], index[("east", "+x")]))) in plan_.exclusive
    assert tuple(sorted((index[("west", "+y")], index[("east", "+y")]))) not in plan_.exclusive


# ---------------------------------------------------------------------- bounds
def test_counting_bound():
    assert counting_bound(problem_of(one_table())) == 3
    assert counting_bound(problem_of(push_scene("p", {"block": BLOCK}))) == 4  # the start (0, 0) is a lattice point
    off_lattice = dataclasses.replace(
        push_scene("p", {"block": BLOCK}), robot=dataclasses.replace(push_scene("p", {}).robot, start=(0.01, 0.0))
    )
    # Phase 1 cannot be the push, but it can be the pick: the push may be made holding the object.
    assert counting_bound(problem_of(off_lattice)) == 4


@pytest.mark.parametrize("scenario", sample_scenarios()[:5], ids=lambda s: s.name)
def test_lower_bound_is_valid(scenario):
    """One phase fewer than the skeleton's bound is infeasible for the MILP itself."""
    problem = problem_of(scenario)
    bound = max(counting_bound(problem), skeleton(problem).phases)
    try:
        milp = build(problem, bound - 1)
    except Infeasible:  # building already proves it (a move no region of some rectangle allows)
        return
    milp.model.optimize()
    assert milp.model.getStatus() == "infeasible"


def test_skeleton_proves_three_phases_too_few_for_the_paper_layout():
    """Measured on SCIP: with tables at (2, 2) and (4, 4), 3 phases are infeasible."""
    scenario = dataclasses.replace(draw_paper_basic(np.random.default_rng(0), "V"), obstacles=())
    assert skeleton(problem_of(scenario)).phases == 4


@pytest.mark.parametrize("scenario", sample_scenarios(), ids=lambda s: s.name)
def test_travel_bound_is_below_the_optimal_plans_travel(scenario):
    problem = problem_of(scenario)
    bound = min_travel(problem)
    result = plan(scenario, time_limit=30.0)
    travel = sum(travel_cost(a.base, b.base) for a, b in itertools.pairwise(result.phases))
    assert 0.0 < bound <= travel + 1e-9
    assert bound >= 0.7 * travel  # and it is not a trivial bound on these layouts


def test_reachable_points_follow_the_corridor():
    scenario = draw_paper_corridor(np.random.default_rng(0))
    problem = problem_of(scenario)
    mask = reachable_mask(problem)
    domain = problem.grid.domain

    def at(x, y):
        return mask[problem.grid.index_at_most(0, x) - domain.i_lo, problem.grid.index_at_most(1, y) - domain.j_lo]

    assert at(0.5, 0.5) and at(5.5, 0.5) and at(5.5, 5.5)  # start, corner, top of the upper leg
    assert not at(2.5, 3.0)  # inside the wall
    assert unreachable_reason(problem) is None


@pytest.mark.parametrize(
    "scenario", [*sample_scenarios(), draw_paper_multi(np.random.default_rng(8), 3)], ids=lambda s: s.name
)
def test_bounds_and_cuts_keep_the_optimum(scenario):
    """The skeleton's N, the timing, travel and objective cuts and the phase windows cut off no optimum."""
    with_cuts = plan(scenario, time_limit=60.0)
    without = plan(scenario, time_limit=60.0, lower_bound=False)
    assert with_cuts.status == without.status == "optimal"
    assert len(with_cuts.phases) == len(without.phases)
    assert with_cuts.objective == pytest.approx(without.objective)


# ---------------------------------------------------------------------- model and decoding
def test_milp_objective_is_the_plans_objective():
    """With integer bases the MILP's optimum is the task cost of the decoded plan exactly (no snapping)."""
    scenario = draw_paper_multi(np.random.default_rng(6), 2)
    result = plan(scenario)
    assert result.objective == pytest.approx(result.stats["milp_objective"])


def test_objects_already_delivered_cost_nothing():
    """An object standing at its goal from the start waits no phase (Eq. 1 counts it W1 in all 3: a constant)."""
    scenario = one_table()
    done = DeliveryObject("done", (2.0, 1.5), (2.0, 1.5))
    scenario = dataclasses.replace(scenario, objects=(*scenario.objects, done))
    result = plan(scenario)
    assert result.objective == pytest.approx(11.21)  # the cup's plan alone (test_planner's hand-worked optimum)
    assert result.stats["milp_objective"] == pytest.approx(result.objective)


def test_model_names_its_groups_after_the_equations():
    milp = build(problem_of(push_scene("p", {"block": BLOCK})), 6)
    names = {c.name.split("_")[0] for c in milp.model.getConss()}
    assert {"eq2", "eq3", "eq4", "eq12", "eq13", "eq18", "eq20", "eq25"} <= names


# ---------------------------------------------------------------------- push while holding
def carry_push_scene():
    """The bottle is in reach of the start (reach_near); the block on its goal is pushed +y from the start.

    Start (0.6, 1.5) facing +x. Every direction of the block needs a stroke B = 0.10 m
    (its face must clear the goal disc by 1 cm), and a pure-axis move of B costs 1.1 B in
    Eq. 1, so every plan travels at least 0.11 m and has at least 4 phases (start, pick,
    push, place). Pick from the start, push +y holding the bottle (the contact (1.22, 1.5)
    is in reach_far from the start), place from the stroke's end (the goal is in reach
    there): 4 phases, 0.11 m, the bottle waits 2 (task cost 20.11), the optimum. With an empty hand the pick
    must come after the push, and the bottle is out of reach from the stroke's end: the
    base has to go back and forth.
    """
    from fetchcarry_env.scenario import Scenario

    return Scenario.from_dict(
        {
            "format": "fetchcarry-scenario/1",
            "name": "carry-push",
            "area": {"min": [0.0, 0.0], "max": [3.0, 3.0]},
            "robot": {"start": [0.6, 1.5], "heading": "+x"},
            "tables": [{"id": "table", "min": [1.0, 1.0], "max": [2.0, 2.0], "height": 0.7}],
            "obstacles": [],
            "objects": [{"id": "bottle", "start": [1.05, 1.5], "goal": [1.22, 1.57]}],
            "clutter": [{"id": "block", "min": [1.17, 1.52], "max": [1.27, 1.62], "height": 0.1}],
        }
    )


def test_the_planner_pushes_while_holding_where_that_is_cheaper():
    scenario = carry_push_scene()
    result = plan(scenario, lattice=Lattice.over(scenario.area, 0.05))
    assert result.status == "optimal"
    assert [p.action for p in result.phases] == ["start", "pick", "push", "place"]
    pick, push, place = result.phases[1:]
    assert pick.base == pytest.approx(scenario.robot.start) and push.holding == "bottle"
    assert push.base == pytest.approx((0.6, 1.6)) and place.base == push.base  # no move between stroke and place
    assert result.objective == pytest.approx(1.1 * 0.10 + 2 * 10.0)


def test_the_planner_pushes_with_an_empty_hand_where_that_is_cheaper():
    """The same block, the bottle on a table far in the stroke's direction (+y).

    Empty hand: push from the start (0.11), fetch the bottle (1.815) and come back to the
    stroke's end to place (1.815): 3.74. Holding, the base must come back further, to a
    stroke's start: +y from the start (3.96) or -y from (0.6, 1.65) (3.80). Either way the
    bottle waits two phases (20).
    """
    near = carry_push_scene()
    far = dataclasses.replace(near.tables[0], id="far", rect=Rect(1.0, 3.0, 2.0, 3.6))
    scenario = dataclasses.replace(
        near,
        area=Rect(0.0, 0.0, 3.0, 4.0),
        tables=(near.tables[0], far),
        objects=(dataclasses.replace(near.objects[0], start=(1.1, 3.3)),),
    )
    result = plan(scenario, lattice=Lattice.over(scenario.area, 0.05))
    assert result.status == "optimal"
    assert [p.action for p in result.phases] == ["start", "push", "pick", "place"]
    assert result.phases[1].holding is None
    assert result.objective == pytest.approx(2 * 10.0 + 0.11 + 2 * 1.815)


def test_an_object_held_at_the_start_may_have_a_covered_goal(spec_example):
    """Mid-episode with the bottle in the hand and the block still on its goal: push holding it, then place."""
    result = plan(spec_example, holding="bottle")
    assert result.status == "optimal"
    actions = [p.action for p in result.phases]
    assert "pick" not in actions and actions[-2:] == ["push", "place"]
    assert all(p.holding == "bottle" for p in result.phases[:-1])


def test_a_pick_base_is_kept_where_the_env_takes_the_target_even_with_another_object_in_reach():
    """The env takes the object in reach nearest the middle of the ranges: another object in reach but farther
    from the middle does not matter; nearer (or out of the target's way only by float noise) it does."""
    from expert.milp.options import ObjectAt, reach_box, split_by_choice
    from fetchcarry_env.scenario import DEFAULT_POSTURES

    lattice = Lattice.over(Rect(0.0, 0.0, 2.0, 2.0), 0.05)
    grid = Grid.for_area(lattice, Rect(0.0, 0.0, 2.0, 2.0), 0.2, True)
    far = DEFAULT_POSTURES[0]  # forward 0.55-0.70 m, middle 0.625
    target, other = (1.0, 1.0), (1.02, 1.0)
    box = reach_box(grid, target, "+x", far)  # bases x 0.30-0.45, y 0.95-1.05
    tag = ObjectAt("other", "start")
    parts = split_by_choice(grid, box, target, "+x", far, [(other, tag)])
    tagged_x = {round(lattice.point(i, 0)[0], 6) for b, tags in parts if tags for i in range(b.i_lo, b.i_hi + 1)}
    free_x = {round(lattice.point(i, 0)[0], 6) for b, tags in parts if not tags for i in range(b.i_lo, b.i_hi + 1)}
    # x 0.30: the other is out of reach (0.72 m); x 0.35: in reach (0.67) but farther from the middle than the
    # target (0.65); x 0.40 and 0.45: nearer. Only the last two depend on where the other object is.
    assert free_x == {0.30, 0.35} and tagged_x == {0.40, 0.45}
    assert all(tags in (frozenset(), frozenset({tag})) for _, tags in parts)
    static = split_by_choice(grid, box, target, "+x", far, [(other, None)])  # an object that never moves
    assert {round(lattice.point(i, 0)[0], 6) for b, _ in static for i in range(b.i_lo, b.i_hi + 1)} == {0.30, 0.35}
