"""How fast FetchCarryPush-v0 resets and steps, next to what PyBullet itself costs.

:func:`measure` runs, in this process, the format's example scenario
(``docs/scenario-format.md``) and the MILP expert's optimal plan for it (two moves, a
push, a move, a pick, a move, a place), episode after episode, and times every reset and
step. It returns, with the project's goal for each: reset of an unchanged layout, move,
pick and place steps per second, a push step as a multiple of the physics steps it
simulates, and a random masked policy's steps per second (``gym.make("FetchCarryPush-v0")``:
random scenarios of the default family, resets included), the plan's step in each
``obs_mode`` (what ``topdown`` and ``rgbd`` add to the state step, the modes taking turns
in one run) with the bytes of one observation, plus the peak memory. Next to
each figure it gives the cost of the PyBullet calls that step cannot avoid (posing the
bodies it moves, the physics steps it simulates), measured on the same world.

Per-step figures use the median of their samples (the machines are shared and noisy);
the policy's figure is its whole run's steps divided by its wall time.
"""

from __future__ import annotations

import itertools
import resource
import statistics
import sys
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from importlib import metadata
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm import tqdm

import fetchcarry_env  # noqa: F401  (registers the env)
from fetchcarry_env.actions import Action, Mode
from fetchcarry_env.families import DEFAULT_FAMILY
from fetchcarry_env.observations import get_mode, mode_names
from fetchcarry_env.scenario import Scenario

ENV_ID = "FetchCarryPush-v0"
DEFAULT_EPISODES = 200  # episodes of the expert's plan
DEFAULT_RESETS = 500  # resets per reset figure (the rebuilding ones use a tenth)
DEFAULT_RANDOM_STEPS = 3000  # steps of the random masked policy
DEFAULT_SEED = 0
FLOOR_REPEATS = 1000  # calls per PyBullet floor of a step

SCENARIO: dict[str, Any] = {  # docs/scenario-format.md's example
    "format": "fetchcarry-scenario/1",
    "name": "basic-area3-07",
    "area": {"min": [-1.0, -1.0], "max": [6.0, 6.0]},
    "robot": {"start": [0.0, 0.0], "heading": "+x", "radius": 0.22},
    "tables": [
        {"id": "table_src", "min": [1.7, 1.7], "max": [2.3, 2.3], "height": 0.70},
        {"id": "table_goal", "min": [3.7, 3.7], "max": [4.3, 4.3], "height": 0.70},
    ],
    "obstacles": [{"id": "box_1", "min": [2.8, 2.9], "max": [3.2, 3.3]}],
    "objects": [{"id": "bottle", "start": [2.0, 2.0], "goal": [4.0, 4.0], "radius": 0.035, "height": 0.20}],
    "clutter": [{"id": "block", "min": [3.9, 3.9], "max": [4.1, 4.1], "height": 0.10}],
}
PLAN: tuple[
    tuple[str, tuple[float, float], str, int], ...
] = (  # the expert's optimal plan: mode, base (metres), heading, posture
    ("move", (3.45, 1.45), "+x", 0),
    ("move", (3.95, 3.2), "+x", 0),
    ("push", (3.95, 3.35), "+y", 0),  # a 0.15 m stroke
    ("move", (3.45, 2.65), "+y", 0),
    ("pick", (2.7, 2.05), "-x", 0),
    ("move", (3.45, 2.65), "-x", 0),
    ("place", (3.95, 3.3), "+y", 0),
)


@dataclass(frozen=True)
class Figure:
    """One measured figure, its goal and the cost of what PyBullet must do for it."""

    name: str
    value: float
    unit: str
    goal: str | None = None  # the goal, in words
    met: bool | None = None
    floor: str | None = None  # the unavoidable PyBullet calls: what they cost on this world


@dataclass
class StepTimes:
    """Seconds of every step of the plan by mode, the seconds of its physics steps and their count."""

    step_s: dict[str, list[float]] = field(default_factory=lambda: defaultdict(list))
    physics_s: dict[str, list[float]] = field(default_factory=lambda: defaultdict(list))
    physics_steps: dict[str, int] = field(default_factory=dict)


# ---------------------------------------------------------------------- timing helpers
def _time_calls(call: Callable[[], Any], repeats: int) -> float:
    """Median seconds of ``call()`` over ``repeats`` calls."""
    samples = []
    for _ in range(repeats):
        started = time.perf_counter()
        call()
        samples.append(time.perf_counter() - started)
    return statistics.median(samples)


@contextmanager
def physics_timer(simulation: Any) -> Iterator[dict[str, float]]:
    """Time the ``stepSimulation`` calls of ``simulation`` (seconds and count) while the block runs.

    The client keeps its bound functions as attributes, so wrapping its ``stepSimulation``
    attribute catches every physics step the primitives make.
    """
    client = simulation.client
    step = client.stepSimulation
    spent = {"seconds": 0.0, "steps": 0}

    def timed_step() -> None:
        started = time.perf_counter()
        step()
        spent["seconds"] += time.perf_counter() - started
        spent["steps"] += 1

    client.stepSimulation = timed_step
    try:
        yield spent
    finally:
        client.stepSimulation = step


def _progress(total: int, description: str, enabled: bool) -> tqdm:
    return tqdm(total=total, desc=description, disable=None if enabled else True, leave=False, file=sys.stderr)


def _median_reset_s(reset: Callable[[int], Any], count: int, bar: tqdm | None = None) -> float:
    """Median seconds of ``reset(k)`` for ``k = 0 .. count - 1``."""
    samples = []
    for k in range(count):
        started = time.perf_counter()
        reset(k)
        samples.append(time.perf_counter() - started)
        if bar is not None:
            bar.update()
    return statistics.median(samples)


# ---------------------------------------------------------------------- resets
def bench_resets(env: Any, resets: int, progress: bool) -> list[Figure]:
    """Reset of the unchanged layout (goal under 2 ms), of a new layout (rebuild), and of a family."""
    unwrapped = env.unwrapped
    with _progress(resets, "resets", progress) as bar:
        same = _median_reset_s(lambda _k: unwrapped.reset(), resets, bar)
    floor = _pose_floor_s(unwrapped, resets)
    figures = [
        Figure(
            "reset, same layout",
            same * 1e3,
            "ms",
            "under 2 ms",
            same < 2e-3,
            f"{floor * 1e3:.3f} ms to pose the robot, the object and the clutter",
        )
    ]
    tables = [{**SCENARIO["tables"][0], "height": 0.71}, SCENARIO["tables"][1]]  # another layout
    moved = Scenario.from_dict({**SCENARIO, "tables": tables})
    original = unwrapped.scenario
    rebuilds = max(resets // 10, 2)
    rebuilt = _median_reset_s(
        lambda k: unwrapped.reset(options={"scenario": moved if k % 2 == 0 else original}), rebuilds
    )
    figures.append(Figure("reset, new layout (bodies rebuilt)", rebuilt * 1e3, "ms"))
    family_env = gym.make(ENV_ID)
    family_env.reset(seed=0)
    drawn = _median_reset_s(lambda k: family_env.reset(seed=k), rebuilds)
    family_env.close()
    figures.append(Figure(f"reset, a new '{DEFAULT_FAMILY}' scenario (draw, check, build)", drawn * 1e3, "ms"))
    unwrapped.reset(options={"scenario": original})
    return figures


def _pose_floor_s(unwrapped: Any, repeats: int) -> float:
    """Median seconds to pose the robot, the object and the clutter where they stand (a reset's floor)."""
    sim = unwrapped._sim
    client = sim.client
    bodies = [sim.body_id("robot"), *(sim.body_id(o["id"]) for o in SCENARIO["objects"])]
    bodies += [sim.body_id(c["id"]) for c in SCENARIO["clutter"]]
    poses = [client.getBasePositionAndOrientation(b) for b in bodies]

    def pose_every_body() -> None:
        for body, (position, orientation) in zip(bodies, poses, strict=True):
            client.resetBasePositionAndOrientation(body, position, orientation)

    return _time_calls(pose_every_body, repeats)


# ---------------------------------------------------------------------- the plan's steps
def _plan_actions(unwrapped: Any) -> list[tuple[str, np.ndarray]]:
    """The plan's steps as ``(mode, action vector)`` on the env's lattice."""
    lattice = unwrapped.lattice
    return [
        (mode, Action(lattice.index(base), heading, posture, Mode[mode.upper()]).to_array())
        for mode, base, heading, posture in PLAN
    ]


def time_plan_steps(env: Any, episodes: int, progress: bool) -> StepTimes:
    """Run the plan ``episodes`` times; ``RuntimeError`` if a step is refused or the object is not delivered."""
    unwrapped = env.unwrapped
    actions = _plan_actions(unwrapped)
    times = StepTimes()
    sim = unwrapped._sim
    with _progress(episodes, "episodes", progress) as bar:
        for _ in range(episodes):
            unwrapped.reset()
            for mode, vector in actions:
                with physics_timer(sim) as physics:
                    started = time.perf_counter()
                    _, _, _, _, info = unwrapped.step(vector)
                    times.step_s[mode].append(time.perf_counter() - started)
                if info["invalid_action"] is not None:
                    raise RuntimeError(f"the benchmark's plan was refused at {mode}: {info['invalid_action']}")
                times.physics_s[mode].append(physics["seconds"])
                times.physics_steps[mode] = physics["steps"]
            if not info["is_success"]:
                raise RuntimeError("the benchmark's plan did not deliver the object")
            bar.update()
    return times


def _step_floors_s(unwrapped: Any) -> dict[str, float]:
    """Median seconds of the PyBullet calls of a move step (pose the robot), a pick step (the arm, the object too)."""
    sim = unwrapped._sim
    client = sim.client
    robot = sim.robot
    base, _ = client.getBasePositionAndOrientation(robot.body)
    bottle = sim.body_id("bottle")
    bottle_pose = client.getBasePositionAndOrientation(bottle)

    def move_calls() -> None:
        client.resetBasePositionAndOrientation(robot.body, base, (0.0, 0.0, 0.0, 1.0))

    def pick_calls() -> None:
        move_calls()
        for joint in (1, 2, 3):  # forward, lateral, wrist: the hand onto the object
            client.resetJointState(robot.body, joint, 0.3)
        client.resetBasePositionAndOrientation(bottle, *bottle_pose)

    return {"move": _time_calls(move_calls, FLOOR_REPEATS), "pick": _time_calls(pick_calls, FLOOR_REPEATS)}


def bench_plan_steps(env: Any, episodes: int, progress: bool) -> list[Figure]:
    """Move, pick, place and push steps of the expert's plan, each next to its PyBullet floor."""
    times = time_plan_steps(env, episodes, progress)
    floors = _step_floors_s(env.unwrapped)
    figures = []
    for mode, goal_rate in (("move", 2000), ("pick", 2000)):
        rate = 1.0 / statistics.median(times.step_s[mode])
        what = ", the arm and the object" if mode == "pick" else ""
        floor = f"{floors[mode] * 1e6:.0f} us to pose the robot{what}"
        figures.append(Figure(f"{mode} step", rate, "per s", f"{goal_rate:,} or more", rate >= goal_rate, floor))
    return [*figures, _place_figure(times), _push_figure(times)]


def _place_figure(times: StepTimes) -> Figure:
    rate = 1.0 / statistics.median(times.step_s["place"])
    physics_ms = statistics.median(times.physics_s["place"]) * 1e3
    floor = f"{physics_ms:.2f} ms in {times.physics_steps['place']} physics steps (settling)"
    return Figure("place step", rate, "per s", "500 or more", rate >= 500, floor)


def _push_figure(times: StepTimes) -> Figure:
    ratio = statistics.median([s / p for s, p in zip(times.step_s["push"], times.physics_s["push"], strict=True)])
    floor = (
        f"{statistics.median(times.physics_s['push']) * 1e3:.1f} ms in {times.physics_steps['push']} physics steps; "
        f"the step takes {statistics.median(times.step_s['push']) * 1e3:.1f} ms"
    )
    return Figure(
        "push step (0.15 m stroke), time / its physics steps' time", ratio, "x", "1.5 or less", ratio <= 1.5, floor
    )


# ---------------------------------------------------------------------- observation modes
OBS_MODE_GOALS_MS = {"topdown": 0.3, "rgbd": 10.0}  # the most each mode may add to the state step
DEFAULT_OBS_EPISODES = 20  # episodes of the plan per observation mode


@contextmanager
def image_timer(unwrapped: Any) -> Iterator[list[float]]:
    """Seconds of each drawing of the images (``ImageObservations.add``) of ``unwrapped`` while the block runs."""
    images = unwrapped._images
    spent: list[float] = []
    if images is None:
        yield spent
        return
    add = images.add

    def timed_add(*args: Any) -> None:
        started = time.perf_counter()
        add(*args)
        spent.append(time.perf_counter() - started)

    images.add = timed_add
    try:
        yield spent
    finally:
        del images.add


def time_obs_modes(episodes: int, progress: bool) -> tuple[dict[str, dict[str, list[float]]], dict[str, list[float]]]:
    """Seconds of every plan step by kind, and of every drawing of the images, for each ``obs_mode``.

    The modes take turns episode by episode, so that they share the machine's load.
    """
    envs = {mode: gym.make(ENV_ID, scenario=SCENARIO, obs_mode=mode) for mode in mode_names()}  # default options
    times: dict[str, dict[str, list[float]]] = {mode: defaultdict(list) for mode in envs}
    drawing: dict[str, list[float]] = {mode: [] for mode in envs}
    for env in envs.values():
        env.reset(seed=0)
    actions = _plan_actions(envs["state"].unwrapped)
    with _progress(episodes * len(envs), "observation modes", progress) as bar:
        for _ in range(episodes):
            for mode, env in envs.items():
                unwrapped = env.unwrapped
                unwrapped.reset()
                with image_timer(unwrapped) as drawn:
                    for kind, vector in actions:
                        started = time.perf_counter()
                        unwrapped.step(vector)
                        times[mode][kind].append(time.perf_counter() - started)
                drawing[mode] += drawn[1:]  # the reset's drawing is not a step's
                bar.update()
    for env in envs.values():
        env.close()
    return times, drawing


def observation_bytes(mode: str) -> int:
    """Bytes of one observation of ``mode`` (every key's array)."""
    env = gym.make(ENV_ID, scenario=SCENARIO, obs_mode=mode)
    observation, _ = env.reset(seed=0)
    env.close()
    return sum(array.nbytes for array in observation.values())


def bench_obs_modes(episodes: int, progress: bool) -> list[Figure]:
    """What each image mode adds to the plan's step (its images' drawing, timed inside the step), in one run.

    Next to it: the mode's step time and its ratio to the state step's (each the mean over
    the plan's seven steps of the step's median), and the bytes of one observation.
    """
    times, drawing = time_obs_modes(episodes, progress)
    step_s = {mode: statistics.fmean(statistics.median(t) for t in kinds.values()) for mode, kinds in times.items()}
    state = step_s["state"]
    figures = [
        Figure(
            "plan step, obs_mode state",
            state * 1e3,
            "ms",
            floor=f"mean of the 7 steps' medians ({episodes} episodes)",
        )
    ]
    for mode, goal in OBS_MODE_GOALS_MS.items():
        added = statistics.median(drawing[mode]) * 1e3
        options = ", ".join(f"{v}" for v in get_mode(mode).resolved({}).values() if v is not None)
        figures.append(
            Figure(
                f"obs_mode {mode} ({options}): added to a step",
                added,
                "ms",
                f"{goal} ms or less",
                added <= goal,
                f"step {step_s[mode] * 1e3:.2f} ms, {step_s[mode] / state:.2f}x the state step",
            )
        )
    for mode in mode_names():
        figures.append(Figure(f"one observation, obs_mode {mode}", observation_bytes(mode) / 1024, "KiB"))
    return figures


# ---------------------------------------------------------------------- a random policy
def bench_random_policy(steps: int, seed: int, progress: bool) -> tuple[Figure, dict[str, int]]:
    """A random masked policy on ``gym.make("FetchCarryPush-v0")``: steps per second, resets included."""
    env = gym.make(ENV_ID)
    unwrapped = env.unwrapped
    rng = np.random.default_rng(seed)
    bounds = np.concatenate([[0], np.cumsum(env.action_space.nvec)])
    counts = {"episodes": 1, "invalid_actions": 0, "collisions": 0, "pushes": 0}  # the names of the env's info
    env.reset(seed=seed)
    started = time.perf_counter()
    with _progress(steps, "random policy", progress) as bar:
        for _ in range(steps):
            mask = unwrapped.action_masks()
            vector = np.array([rng.choice(np.flatnonzero(mask[a:b])) for a, b in itertools.pairwise(bounds)])
            _, _, terminated, truncated, info = env.step(vector)
            counts["invalid_actions"] += info["invalid_action"] is not None
            counts["collisions"] += info["contact"] is not None
            counts["pushes"] += "push" in info
            if terminated or truncated:
                env.reset()
                counts["episodes"] += 1
            bar.update()
    rate = steps / (time.perf_counter() - started)
    env.close()
    return Figure("random masked policy", rate, "steps per s", "500 or more", rate >= 500), counts


def measure(
    episodes: int = DEFAULT_EPISODES,
    resets: int = DEFAULT_RESETS,
    random_steps: int = DEFAULT_RANDOM_STEPS,
    seed: int = DEFAULT_SEED,
    progress: bool = True,
    obs_episodes: int = DEFAULT_OBS_EPISODES,
) -> dict[str, Any]:
    """Every figure of the benchmark, with the settings and the machine (a JSON-ready mapping; seconds, MB)."""
    env = gym.make(ENV_ID, scenario=SCENARIO)
    env.reset(seed=seed)
    started = time.perf_counter()
    figures = bench_resets(env, resets, progress)
    figures += bench_plan_steps(env, episodes, progress)
    env.close()
    policy, counts = bench_random_policy(random_steps, seed, progress)
    figures.append(policy)
    figures += bench_obs_modes(obs_episodes, progress)
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux reports kilobytes
    figures.append(Figure("peak memory of the process (resident)", peak_mb, "MB"))
    return {
        "env": ENV_ID,
        "pybullet": metadata.version("pybullet"),
        "scenario": SCENARIO["name"],
        "episodes": episodes,
        "resets": resets,
        "random_steps": random_steps,
        "obs_episodes": obs_episodes,
        "seed": seed,
        "random_policy": counts,
        "wall_s": time.perf_counter() - started,
        "figures": [asdict(f) for f in figures],
    }
