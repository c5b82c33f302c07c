"""The PyBullet world: one quiet, lazy client per env, layouts re-used, and each primitive in real physics."""

from __future__ import annotations

import ast
import math
import os
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from sim_worlds import (
    BLOCK,
    FAR,
    NEAR,
    PUSH_PICK_PLACE_PLAN,
    action,
    jam,
    lateral_push,
    make,
    push_pick_place,
    room,
    shove,
    thin_wall,
)

from fetchcarry_env.actions import Mode
from fetchcarry_env.geometry import Rect
from fetchcarry_env.kinematics import INVALID_ACTION_PENALTY, WAIT_COST, hand_offset
from fetchcarry_env.observation import LIFT_HEIGHT
from fetchcarry_env.sim import physics, stroke_profile
from fetchcarry_env.sim.client import pybullet, silenced_file_descriptors

SIM_DIR = Path(__file__).resolve().parents[2] / "fetchcarry_env" / "sim"
STANDING_Z = 0.7 + 0.2 / 2  # metres: centre of a 20 cm bottle standing on a 0.7 m table
BLOCK_Z = 0.7 + 0.1 / 2  # metres: centre of a 10 cm block on the table


def item_xyz(env, name: str) -> np.ndarray:
    """Where PyBullet has an object's or a piece of clutter's centre."""
    return np.array(env.unwrapped._sim.item_position(name))


def tilt_degrees(env, name: str) -> float:
    """Angle between the item's z axis and the vertical, from PyBullet's orientation."""
    sim = env.unwrapped._sim
    _, quaternion = sim.client.getBasePositionAndOrientation(sim.body_id(name))
    z_axis = np.array(sim.client.getMatrixFromQuaternion(quaternion)).reshape(3, 3)[:, 2]
    return math.degrees(math.acos(min(1.0, z_axis[2])))


def footprint(env, name: str) -> Rect:
    """The clutter's footprint where PyBullet has it (axis-aligned: pushes barely turn blocks)."""
    x, y, _ = item_xyz(env, name)
    size_x, size_y = env.unwrapped.scenario.clutter_item(name).rect.size
    return Rect.around((x, y), size_x / 2, size_y / 2)


def overlap_depth(a: Rect, b: Rect) -> float:
    """How far two rectangles interpenetrate (metres, 0 when apart)."""
    return max(0.0, min(min(a.max_x, b.max_x) - max(a.min_x, b.min_x), min(a.max_y, b.max_y) - max(a.min_y, b.min_y)))


# ---------------------------------------------------------------------- the client
def test_the_simulation_prints_nothing_on_stdout_or_stderr():
    """``import pybullet`` prints its build time; connecting with options prints argv[0]: both are silenced."""
    script = (
        "import gymnasium as gym, fetchcarry_env\n"
        "env = gym.make('FetchCarryPush-v0', render_mode='rgb_array')\n"
        "env.reset(seed=0); env.step(env.action_space.sample()); env.render(); env.close()\n"
    )
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""
    assert result.stderr == ""


def test_silenced_descriptors_come_back_even_when_the_block_raises(capfd):
    with pytest.raises(RuntimeError, match="inside"), silenced_file_descriptors(1, 2):
        os.write(1, b"hidden out\n")
        os.write(2, b"hidden err\n")
        raise RuntimeError("inside")
    os.write(1, b"visible out\n")
    os.write(2, b"visible err\n")
    captured = capfd.readouterr()
    assert captured.out == "visible out\n"
    assert captured.err == "visible err\n"


def _pybullet_calls(path: Path) -> list[str]:
    """``pybullet.<function>(...)`` calls in a module (the module-level client, not a BulletClient)."""
    tree = ast.parse(path.read_text())
    return [
        node.func.attr
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and isinstance(node.func.value, ast.Name)
        and node.func.value.id == "pybullet"
    ]


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    names = {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
    return names | {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.module}


def test_only_the_client_module_imports_pybullet_and_nothing_calls_its_module_level_functions():
    client = SIM_DIR / "client.py"
    assert '_import_quietly("pybullet")' in client.read_text()  # the one import, silenced
    assert sorted(set(_pybullet_calls(client))) == ["connect", "disconnect"]
    for path in sorted(set(SIM_DIR.parent.rglob("*.py")) - {client}):
        assert not any(name.split(".")[0] in ("pybullet", "pybullet_utils") for name in _imports(path)), path
        assert _pybullet_calls(path) == [], path


def test_the_client_is_made_lazily_closed_safely_twice_and_remade_on_use():
    env = make(push_pick_place())
    sim = env.unwrapped._sim
    assert sim.connected
    env.close()
    assert not sim.connected
    env.close()  # safe twice
    assert not sim.connected
    # Used again, the env reconnects and continues the episode where it was.
    _, _, _, _, info = env.step(action(env, *PUSH_PICK_PLACE_PLAN[0]))
    assert info["invalid_action"] is None
    assert sim.connected
    env.close()

    lazy = gym.make("FetchCarryPush-v0", scenario=push_pick_place()).unwrapped
    assert not lazy._sim.connected  # nothing connects before the first reset
    lazy.close()


def test_each_env_has_its_own_physics_server():
    a, b = make(push_pick_place()), make(shove())
    try:
        assert a.unwrapped._sim.client.client_id != b.unwrapped._sim.client.client_id
    finally:
        a.close()
        b.close()


def test_a_closed_client_refuses_calls_instead_of_reaching_another_server():
    env = make(push_pick_place())
    client = env.unwrapped._sim.client
    client.stepSimulation()  # bound once, kept while connected
    env.close()
    other = make(shove())  # may get the same server id
    try:
        with pytest.raises(pybullet.error):
            client.stepSimulation()
    finally:
        other.close()


# ---------------------------------------------------------------------- layouts
def test_bodies_are_reused_across_resets_of_one_layout_and_rebuilt_when_it_changes():
    scenario = push_pick_place()
    env = make(scenario)
    sim = env.unwrapped._sim
    table_body = sim.body_id("table")
    for seed in range(3):
        env.reset(seed=seed)
    assert sim.builds == 1
    assert sim.body_id("table") == table_body

    moved = room(
        start=(0.6, 1.5),
        clutter={"block": BLOCK},
        objects=[{"id": "bottle", "start": [1.2, 1.8], "goal": [1.35, 1.5]}],
    )  # same layout: only the bottle's start differs
    env.reset(options={"scenario": moved})
    assert sim.builds == 1
    assert np.allclose(item_xyz(env, "bottle"), (1.2, 1.8, STANDING_Z), atol=1e-9)

    env.reset(options={"scenario": shove()})  # another layout: rebuilt
    assert sim.builds == 2
    env.reset(options={"scenario": shove()})
    assert sim.builds == 2
    env.close()


def test_reset_puts_every_body_back_after_an_episode():
    env = make(push_pick_place())
    for step in PUSH_PICK_PLACE_PLAN:
        env.step(action(env, *step))
    env.reset(seed=1)
    assert np.allclose(item_xyz(env, "bottle"), (1.3, 1.2, STANDING_Z), atol=1e-12)
    assert np.allclose(item_xyz(env, "block"), (1.35, 1.5, BLOCK_Z), atol=1e-12)
    assert env.unwrapped._sim.robot.base_position() == (0.6, 1.5)
    env.close()


# ---------------------------------------------------------------------- the robot
def test_the_robot_base_is_round_with_the_scenario_radius():
    env = make(push_pick_place())
    sim = env.unwrapped._sim
    shape = sim.client.getCollisionShapeData(sim.body_id("robot"), -1)[0]
    assert shape[2] == pybullet.GEOM_CYLINDER
    assert shape[3][1] == pytest.approx(env.unwrapped.scenario.robot.radius)
    env.close()


@pytest.mark.parametrize(("posture", "base_x"), [(FAR, 0.7), (NEAR, 0.75)])
def test_the_hand_reaches_an_object_within_each_posture(posture, base_x):
    """PyBullet's forward kinematics put the hand on the object, at an offset the posture states."""
    scenario = room(
        start=(0.5, 1.5), objects=[{"id": "bottle", "start": [1.2 if posture else 1.3, 1.5], "goal": [1.8, 1.8]}]
    )
    env = make(scenario)
    _, _, _, _, info = env.step(action(env, (base_x, 1.5), "+x", posture, Mode.PICK))
    assert info["invalid_action"] is None
    robot = env.unwrapped._sim.robot
    hand = np.array(robot.hand_position())
    assert np.allclose(hand, item_xyz(env, "bottle"), atol=1e-9)
    forward, lateral = hand_offset((base_x, 1.5), "+x", tuple(hand[:2]))
    assert env.unwrapped.scenario.robot.postures[posture].reaches(forward, lateral, tol=0.0)
    env.close()


# ---------------------------------------------------------------------- pick and place
def test_pick_lifts_the_object_and_the_hand_carries_it():
    env = make(push_pick_place())
    env.step(action(env, *PUSH_PICK_PLACE_PLAN[0]))
    standing = item_xyz(env, "bottle")
    assert np.allclose(standing, (1.3, 1.2, STANDING_Z), atol=1e-4)  # it stood through the push
    _, _, _, _, info = env.step(action(env, *PUSH_PICK_PLACE_PLAN[1]))
    assert info["invalid_action"] is None
    assert np.allclose(item_xyz(env, "bottle"), standing + np.array([0.0, 0.0, LIFT_HEIGHT]), atol=1e-12)
    env.step(action(env, (0.5, 0.5), "+y", FAR, Mode.MOVE))  # carry it away, turning
    robot = env.unwrapped._sim.robot
    assert np.allclose(item_xyz(env, "bottle"), robot.hand_position(), atol=1e-9)
    assert env.unwrapped.state.holding == "bottle"
    env.close()


def test_place_releases_the_object_standing_at_its_goal_and_it_stays_there():
    env = make(push_pick_place())
    rewards = [env.step(action(env, *step))[1] for step in PUSH_PICK_PLACE_PLAN]
    position = item_xyz(env, "bottle")
    assert np.linalg.norm(position - (1.35, 1.5, STANDING_Z)) <= 0.01
    assert tilt_degrees(env, "bottle") < 1.0
    assert rewards[-1] > -1.0  # delivered: no waiting cost, only the place's short move
    sim = env.unwrapped._sim
    body = sim.body_id("bottle")
    assert sim.client.getDynamicsInfo(body, -1)[0] == pytest.approx(physics.OBJECT_MASS)  # dynamic again
    for _ in range(240):  # a second more of physics: a bottle put down upright stays put
        sim.client.stepSimulation()
    assert np.linalg.norm(item_xyz(env, "bottle") - position) < 1e-3
    assert tilt_degrees(env, "bottle") < 1.0
    assert sim.client.getContactPoints(body, sim.body_id("table"))  # it stands on the table
    env.close()


# ---------------------------------------------------------------------- push
def test_the_hand_moves_at_most_a_centimetre_per_simulation_step():
    for length in (0.05, 0.15, 0.3, 2.0):
        profile = np.array(stroke_profile(length))
        steps = np.diff(np.concatenate([[0.0], profile]))
        assert profile[-1] == length
        assert np.all(steps > 0)
        assert steps.max() <= physics.MAX_HAND_STEP + 1e-12


@pytest.mark.parametrize(
    ("world", "start", "end", "heading", "name"),
    [
        (push_pick_place, (0.6, 1.5), (0.75, 1.5), "+x", "block"),  # forward push
        (lateral_push, (1.3, 0.6), (1.6, 0.6), "+y", "block"),  # lateral push
    ],
)
def test_a_push_moves_the_clutter_by_the_stroke(world, start, end, heading, name):
    env = make(world())
    before = item_xyz(env, name)
    _, _, _, _, info = env.step(action(env, end, heading, FAR, Mode.PUSH))
    assert info["invalid_action"] is None
    assert info["push"]["stalled"] is False
    stroke = np.subtract(end, start)
    moved = item_xyz(env, name) - before
    assert np.linalg.norm(moved[:2] - stroke) <= 0.02
    assert abs(moved[2]) < 1e-3 and tilt_degrees(env, name) < 2.0
    assert np.allclose(env.unwrapped.state.base, end)
    assert np.allclose(env.unwrapped.state.clutter[name], item_xyz(env, name)[:2])  # the env reads physics back
    env.close()


def test_a_push_into_a_free_neighbour_shoves_it_and_never_passes_through():
    env = make(shove())
    _, _, _, _, info = env.step(action(env, (0.75, 1.5), "+x", FAR, Mode.PUSH))
    assert info["push"]["stalled"] is False
    a, b = footprint(env, "a"), footprint(env, "b")
    assert a.center[0] == pytest.approx(1.5, abs=0.02)  # the pushed block went the whole stroke
    assert b.center[0] > 1.55  # and shoved its neighbour ahead of it
    assert overlap_depth(a, b) < 1e-3
    env.close()


def test_a_push_against_a_neighbour_that_cannot_move_stops():
    env = make(jam())
    _, _, _, _, info = env.step(action(env, (0.75, 1.5), "+x", FAR, Mode.PUSH))
    assert info["invalid_action"] is None
    assert info["push"]["stalled"] is True
    assert info["push"]["travelled"] < 0.08 < info["push"]["stroke"]
    a, b = footprint(env, "a"), footprint(env, "b")
    wall = env.unwrapped.scenario.obstacles[0].rect
    assert overlap_depth(a, b) < 1e-3  # the block stopped at its neighbour
    assert b.max_x - wall.min_x < 1e-3  # which stayed out of the wall
    assert abs(b.center[0] - 1.5) < 0.01 and tilt_degrees(env, "b") < 2.0
    assert env.unwrapped.state.base[0] == pytest.approx(0.6 + info["push"]["travelled"])
    env.close()


HOLDING_PUSH_PLAN = (  # the paper's push-aside while carrying: pick, go behind the block, push, place
    ((0.7, 1.2), "+x", FAR, Mode.PICK),
    ((0.6, 1.5), "+x", FAR, Mode.MOVE),
    ((0.75, 1.5), "+x", FAR, Mode.PUSH),  # the bottle, in the hand, ends right over its goal
    ((0.75, 1.5), "+x", FAR, Mode.PLACE),  # no move between the stroke's end and the place
)


def test_a_push_while_holding_moves_the_clutter_and_the_held_object_with_the_base():
    env = make(push_pick_place())
    u = env.unwrapped
    env.step(action(env, *HOLDING_PUSH_PLAN[0]))
    env.step(action(env, *HOLDING_PUSH_PLAN[1]))
    assert u.state.holding == "bottle"
    assert list(u.action_masks()[-4:]) == [True, False, True, True]  # full hand: move, place, push
    grip = hand_offset(u.state.base, u.state.heading, u.state.objects["bottle"][:2])
    block = item_xyz(env, "block")
    _, _, _, _, info = env.step(action(env, *HOLDING_PUSH_PLAN[2]))
    assert info["invalid_action"] is None and info["push"]["stalled"] is False
    assert np.linalg.norm(item_xyz(env, "block")[:2] - block[:2] - (0.15, 0.0)) <= 0.02  # physics as without
    assert u.state.holding == "bottle" and np.allclose(u.state.base, (0.75, 1.5))
    held = np.array(u.state.objects["bottle"])
    assert np.allclose(held, item_xyz(env, "bottle"), atol=1e-12)  # the env reads the hand back
    assert np.allclose(held, u._sim.robot.hand_position(), atol=1e-9)  # it is in the hand
    assert np.allclose(hand_offset(u.state.base, u.state.heading, held[:2]), grip, atol=1e-9)  # at the same offset
    assert held[2] == pytest.approx(STANDING_Z + LIFT_HEIGHT)
    _, reward, terminated, _, info = env.step(action(env, *HOLDING_PUSH_PLAN[3]))
    assert info["invalid_action"] is None and terminated and reward > -1.0  # delivered: no waiting cost
    assert np.linalg.norm(item_xyz(env, "bottle") - (1.35, 1.5, STANDING_Z)) <= 0.01
    env.close()


def test_a_push_while_holding_is_deterministic_and_copies_continue_bit_for_bit():
    import copy
    import pickle

    def run(env, steps):
        for step in steps:
            env.step(action(env, *step))
        return env.unwrapped.state, {n: tuple(item_xyz(env, n)) for n in ("block", "bottle")}

    env = make(push_pick_place())
    run(env, HOLDING_PUSH_PLAN[:2])
    copies = [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]
    reference = run(env, HOLDING_PUSH_PLAN[2:])  # the push, then the place (physics settles the bottle)
    for other in copies:
        assert run(other, HOLDING_PUSH_PLAN[2:]) == reference
        other.close()
    again = make(push_pick_place())
    assert run(again, HOLDING_PUSH_PLAN) == reference
    again.close()
    env.close()


# ---------------------------------------------------------------------- the base
def test_a_move_through_a_wall_is_refused_and_nothing_moves():
    """No move is stopped at a contact: one that breaks the move rule (here: through a wall) does nothing."""
    env = make(thin_wall())
    before = env.unwrapped.state
    _, reward, _, _, info = env.step(action(env, (2.5, 1.5), "+x", FAR, Mode.MOVE))
    assert "'wall'" in info["invalid_action"] and info["contact"] is None and info["collisions"] == 0
    assert env.unwrapped.state == before and info["travel"] == 0.0
    waiting = WAIT_COST * (len(env.unwrapped.scenario.objects) - info["delivered"])
    assert reward == pytest.approx(-INVALID_ACTION_PENALTY - waiting)
    sim = env.unwrapped._sim
    assert sim.robot.base_position() == pytest.approx(before.base)
    env.close()


def test_a_move_along_a_table_at_exactly_the_radius_is_allowed_and_closer_is_refused():
    """The move rule's side of the table grown by the radius, with its 5e-7 m tolerance; no move touches anything."""
    for closer, allowed in ((0.0, True), (4e-7, True), (1e-4, False)):
        table = ((1.0, 1.0), (2.0, 2.03 + closer))  # the path at y = 2.25 passes its edge at 0.22 - closer
        env = make(room(start=(0.5, 2.25), table=table))
        _, _, _, _, info = env.step(action(env, (2.5, 2.25), "+x", FAR, Mode.MOVE))
        assert (info["invalid_action"] is None) is allowed, closer
        assert info["contact"] is None and info["collisions"] == 0
        env.close()
