"""The opt-in corner poses and pose tangents (``plan(..., corner_poses=True, pose_tangents=True)``).

Both only add what the exact rule allows: a pose option's lattice points keep the base
disc off every table and obstacle, and every region from a pose tangent is a radius or
more from its rectangle. On the study's cases where the octagon and the 48-gon keep a
phase more than the exhaustive search of the exact rule (``lattice_search.py``), they
reach its number of phases and its Eq. 1 (``docs/formulation.md``, "Poses in corner zones,
tangents from the poses").
"""

from __future__ import annotations

import numpy as np
import pytest
from collision_study import diagonal_room
from lattice_search import _travel, search
from test_lattice_search import RESOLUTION, random_room

from expert.milp.grid import Grid, move_regions, rect_normals
from expert.milp.pose_tangents import pose_grid
from expert.milp.problem import prepare
from expert.planner import plan
from expert.validate import validate_plan
from fetchcarry_env.actions import Lattice
from fetchcarry_env.kinematics import WAIT_COST


def test_corner_poses_keep_the_disc_clear_and_add_the_corner_zone():
    """room-105: its exact plan picks from (1.5, 1.3), 0.30 m from a wall's corner (0.21 m along each axis)."""
    scenario = random_room(np.random.default_rng(105), "room-105")
    lattice = Lattice.over(scenario.area, RESOLUTION)
    plain, corners = prepare(scenario, lattice), prepare(scenario, lattice, corner_poses=True)
    solid = [t.rect for t in scenario.tables] + [o.rect for o in scenario.obstacles]
    radius = scenario.robot.radius
    for option in corners.options:
        for i in range(option.box.i_lo, option.box.i_hi + 1):
            for j in range(option.box.j_lo, option.box.j_hi + 1):
                assert all(r.distance_to_point(corners.grid.point(i, j)) >= radius - 1e-9 for r in solid)
    i, j = lattice.index((1.5, 1.3))

    def offered(problem) -> bool:
        return any(o.kind == "pick" and o.box.contains(i, j) for o in problem.options)

    assert offered(corners) and not offered(plain)


def test_pose_tangent_regions_keep_the_disc_clear():
    """Every lattice point in a region from the poses' tangents is a radius or more from its rectangle."""
    scenario = diagonal_room(np.random.default_rng(3), "diagonal-3")
    lattice = Lattice.over(scenario.area, RESOLUTION)
    problem = prepare(scenario, lattice)
    grid = pose_grid(scenario, problem.grid, list(problem.options))
    radius = scenario.robot.radius
    assert isinstance(grid, Grid) and any(normals for _, normals in grid.extra_normals)
    for rect, _ in grid.extra_normals:
        planes = move_regions(grid, rect, radius)
        assert len(planes) == 4 + len(rect_normals(grid, rect))
        for plane in planes[8:]:  # after the sides and the octagon's four cuts
            for i in range(grid.domain.i_lo, grid.domain.i_hi + 1):
                for j in range(grid.domain.j_lo, grid.domain.j_hi + 1):
                    if plane.holds_at(i, j):
                        assert rect.distance_to_point(grid.point(i, j)) >= radius - 1e-9


@pytest.mark.parametrize(
    "scenario",
    [
        random_room(np.random.default_rng(105), "room-105"),  # a pose in a corner zone
        diagonal_room(np.random.default_rng(3), "diagonal-3"),  # a 0.47 m gap: the octagon says infeasible
        diagonal_room(np.random.default_rng(8), "diagonal-8"),  # the octagon needs one phase more
    ],
    ids=lambda s: s.name,
)
def test_tight_corners_reach_the_exact_rule(scenario):
    lattice = Lattice.over(scenario.area, RESOLUTION)
    exact = search(scenario, lattice, max_phases=8)
    octagon = plan(scenario, lattice=lattice, time_limit=60.0)
    assert not octagon.found or len(octagon.phases) > exact.phases  # the default model keeps a phase more
    tight = plan(scenario, lattice=lattice, time_limit=60.0, corner_poses=True, pose_tangents=True)
    assert tight.status == "optimal" and validate_plan(scenario, tight) == []
    assert len(tight.phases) == exact.phases
    assert exact.objective - 1e-6 <= tight.objective <= exact.objective + 0.01 * abs(exact.objective)


def test_exact_path_is_a_plan_of_the_search():
    """The search's path has its number of phases, picks before it places, and its cost is its travel plus the waits."""
    scenario = diagonal_room(np.random.default_rng(8), "diagonal-8")
    exact = search(scenario, Lattice.over(scenario.area, RESOLUTION), max_phases=8)
    assert len(exact.path) + 1 == exact.phases
    actions = [a for _, a in exact.path if a]
    assert actions == ["pick", "place"] and exact.path[-1][1] == "place"
    bases = np.array([scenario.robot.start, *(base for base, _ in exact.path)])
    travel = float(_travel(bases[:-1], bases[1:]).sum())
    assert travel + WAIT_COST * (exact.phases - 2) == pytest.approx(exact.objective, abs=1e-9)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_corner_poses_of_pushes_keep_the_swept_disc_clear(seed):
    """A push's pose with ``corner_poses``: the base disc swept along the stroke stays off every table and obstacle."""
    from fetchcarry_env.families import get_family
    from fetchcarry_env.geometry import segment_rect_distance

    scenario = get_family("push").sample(np.random.default_rng(seed))
    problem = prepare(scenario, Lattice.over(scenario.area, 0.05), corner_poses=True)
    solid = [t.rect for t in scenario.tables] + [o.rect for o in scenario.obstacles]
    radius, grid = scenario.robot.radius, problem.grid
    pushes = [o for o in problem.options if o.kind == "push"]
    assert pushes
    for option in pushes:
        di, dj = option.push.cells
        for i in range(option.box.i_lo, option.box.i_hi + 1):
            for j in range(option.box.j_lo, option.box.j_hi + 1):
                a, b = grid.point(i, j), grid.point(i + di, j + dj)
                assert all(segment_rect_distance(a, b, r) >= radius - 1e-9 for r in solid)


def _family(name: str, seed: int):
    from fetchcarry_env.families import get_family

    return get_family(name).sample(np.random.default_rng(seed))


@pytest.mark.parametrize(
    "make",
    [
        lambda: diagonal_room(np.random.default_rng(3), "diagonal-3"),
        lambda: random_room(np.random.default_rng(105), "room-105"),
        lambda: _family("corridor", 1),
        lambda: _family("push", 0),
    ],
    ids=["diagonal-3", "room-105", "corridor-1", "push-0"],
)
def test_tight_plans_are_valid_and_the_env_refuses_the_phases_the_validator_notes(make):
    """A plan with both options is a valid plan file; the env's rules are the default model's (no corner-zone poses,
    no tangents), so it refuses the phases that leave them: the first one it refuses is the validator's first note."""
    import gymnasium as gym

    import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
    from expert.to_actions import plan_to_actions
    from expert.validate import env_refusals

    scenario = make()
    env = gym.make("FetchCarryPush-v0", scenario=scenario)
    try:
        env.reset(seed=0)
        lattice = env.unwrapped.lattice
        result = plan(scenario, lattice=lattice, time_limit=60.0, corner_poses=True, pose_tangents=True)
        assert result.found and validate_plan(scenario, result) == []
        noted = env_refusals(scenario, result, lattice=lattice)
        for k, action in enumerate(plan_to_actions(result, scenario, lattice), start=1):
            _, _, terminated, _truncated, info = env.step(action.to_array())
            if info["invalid_action"] is not None:
                assert noted and noted[0].startswith(f"env rules: phase {k} "), (k, info["invalid_action"], noted)
                break
        else:
            assert not noted and terminated and info["is_success"]
    finally:
        env.close()
