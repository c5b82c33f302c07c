"""Small hand-made worlds for the environment and simulation tests, and a helper to write actions.

Every world is a 3 x 3 m room with one 0.7 m table; the robot's postures are the
defaults (``reach_far`` forward 0.55-0.70 m, ``reach_near`` 0.35-0.50 m, lateral
+-5 cm) and its radius 0.22 m. Bases are on the default 5 cm lattice from (0, 0).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
from fetchcarry_env.actions import Action, Mode
from fetchcarry_env.scenario import Scenario

TABLE_HEIGHT = 0.7  # metres
CLUTTER_HEIGHT = 0.1  # metres
FAR, NEAR = 0, 1  # posture indices

Box = tuple[tuple[float, float], tuple[float, float]]


def room(
    *,
    start: tuple[float, float],
    heading: str = "+x",
    table: Box = ((1.0, 1.0), (2.0, 2.0)),
    clutter: dict[str, Box] | None = None,
    obstacles: dict[str, Box] | None = None,
    objects: Iterable[dict[str, Any]] = ({"id": "bottle", "start": [1.8, 1.2], "goal": [1.8, 1.8]},),
    name: str = "room",
) -> Scenario:
    """A validated scenario: the room, one table, the given clutter, obstacles and objects."""
    return Scenario.from_dict(
        {
            "format": "fetchcarry-scenario/1",
            "name": name,
            "area": {"min": [0.0, 0.0], "max": [3.0, 3.0]},
            "robot": {"start": list(start), "heading": heading},
            "tables": [{"id": "table", "min": list(table[0]), "max": list(table[1]), "height": TABLE_HEIGHT}],
            "obstacles": [{"id": k, "min": list(a), "max": list(b)} for k, (a, b) in (obstacles or {}).items()],
            "objects": [dict(o) for o in objects],
            "clutter": [
                {"id": k, "min": list(a), "max": list(b), "height": CLUTTER_HEIGHT}
                for k, (a, b) in (clutter or {}).items()
            ],
        }
    )


BLOCK = ((1.3, 1.45), (1.4, 1.55))  # a 10 cm block; its rear (-x) face is 0.3 m into the table


def push_pick_place() -> Scenario:
    """A block stands on the bottle's goal: push it 15 cm along +x, then carry the bottle there."""
    return room(
        start=(0.6, 1.5),
        clutter={"block": BLOCK},
        objects=[{"id": "bottle", "start": [1.3, 1.2], "goal": [1.35, 1.5]}],
        name="push-pick-place",
    )


PUSH_PICK_PLACE_PLAN = (
    ((0.75, 1.5), "+x", FAR, Mode.PUSH),  # forward push: the block moves from x 1.35 to 1.50
    ((0.7, 1.2), "+x", FAR, Mode.PICK),
    ((0.75, 1.5), "+x", FAR, Mode.PLACE),  # delivers the bottle: the episode ends
)


def shove() -> Scenario:
    """Block ``a`` with block ``b`` 5 cm in front of it (+x), free to slide."""
    return room(start=(0.6, 1.5), clutter={"a": BLOCK, "b": ((1.45, 1.45), (1.55, 1.55))}, name="shove")


def jam() -> Scenario:
    """As :func:`shove`, but ``b`` stands at the table's edge against a wall: a push along +x jams."""
    return room(
        start=(0.6, 1.5),
        table=((1.0, 1.0), (1.55, 2.0)),
        clutter={"a": BLOCK, "b": ((1.45, 1.45), (1.55, 1.55))},
        obstacles={"wall": ((1.55, 1.0), (1.65, 2.0))},
        objects=[{"id": "bottle", "start": [1.2, 1.2], "goal": [1.2, 1.8]}],
        name="jam",
    )


def lateral_push() -> Scenario:
    """The robot faces the table (+y) beside a block near its edge, to push it 30 cm along +x."""
    return room(start=(1.3, 0.6), heading="+y", clutter={"block": ((1.3, 1.15), (1.4, 1.25))}, name="lateral")


def thin_wall() -> Scenario:
    """A 2 cm wall across the room at x = 1.5 m; the table is behind it."""
    return room(
        start=(0.5, 1.5),
        table=((2.0, 2.0), (2.8, 2.8)),
        obstacles={"wall": ((1.5, 0.0), (1.52, 3.0))},
        objects=[{"id": "bottle", "start": [2.2, 2.2], "goal": [2.6, 2.6]}],
        name="thin-wall",
    )


def action(env: gym.Env, point: Sequence[float], heading: str, posture: int, mode: Mode) -> np.ndarray:
    """The action vector sending the base to the lattice point at ``point`` (metres)."""
    lattice = env.unwrapped.lattice
    cell = lattice.index((point[0], point[1]))
    assert np.allclose(lattice.point(*cell), point, atol=1e-9), f"{point} is not a lattice point"
    return Action(cell, heading, posture, mode).to_array()


def make(scenario: Scenario, **kwargs: Any) -> gym.Env:
    """``gym.make("FetchCarryPush-v0", scenario=...)``, reset with seed 0."""
    env = gym.make("FetchCarryPush-v0", scenario=scenario, **kwargs)
    env.reset(seed=0)
    return env


SPEC_EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"


def spec_example() -> Scenario:
    """The scenario of docs/scenario-format.md: a 20 cm block on the goal, an obstacle between the tables."""
    return Scenario.load(SPEC_EXAMPLE)


SPEC_EXAMPLE_PLAN = (  # the MILP expert's optimal plan for it
    ((3.45, 1.45), "+x", FAR, Mode.MOVE),
    ((3.95, 3.2), "+x", FAR, Mode.MOVE),
    ((3.95, 3.35), "+y", FAR, Mode.PUSH),  # off-centre: the hand is at the posture's lateral limit
    ((3.45, 2.65), "+y", FAR, Mode.MOVE),
    ((2.7, 2.05), "-x", FAR, Mode.PICK),
    ((3.45, 2.65), "-x", FAR, Mode.MOVE),
    ((3.95, 3.3), "+y", FAR, Mode.PLACE),
)
