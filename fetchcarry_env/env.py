"""``FetchCarryPushEnv``: the Gymnasium contract of the fetch-and-carry world with push-aside.

The environment composes three pieces and adds only the Gymnasium contract: the
scenario (what the world is: :mod:`fetchcarry_env.scenario`, or a family of them:
:mod:`fetchcarry_env.families`), the rules of what one phase may do
(:mod:`fetchcarry_env.rules`) and the PyBullet world that moves things
(:mod:`fetchcarry_env.sim`).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from fetchcarry_env.actions import Action, Lattice, Mode, action_nvec, action_vector
from fetchcarry_env.families import DEFAULT_FAMILY, Family, get_family
from fetchcarry_env.geometry import Rect, heading_vector
from fetchcarry_env.kinematics import (
    COLLISION_PENALTY,
    INVALID_ACTION_PENALTY,
    WAIT_COST,
    hand_offset,
    travel_cost,
)
from fetchcarry_env.observation import DELIVERY_TOLERANCE, Capacity, WorldState, encode, observation_space
from fetchcarry_env.observations import ImageObservations, get_mode
from fetchcarry_env.rules import ResolvedPhase, action_mask, check_action
from fetchcarry_env.scenario import Scenario, ScenarioError, check_rules
from fetchcarry_env.sim import CAMERAS, Simulation, Snapshot
from fetchcarry_env.sim.client import check_display, display_available
from fetchcarry_env.worlds.physics import ItemPhysics, PhysicsVariation, physics_variation

DEFAULT_RESOLUTION = 0.05  # metres between lattice points
DEFAULT_IMAGE_SIZE = (320, 240)  # pixels (width, height) of rgb_array frames
ACTION_COMPONENTS = ("x cell", "y cell", "heading", "posture", "mode")

ScenarioLike = Scenario | Mapping[str, Any] | str | Path


class FetchCarryPushEnv(gym.Env[dict[str, np.ndarray], np.ndarray]):
    """Fetch-and-carry with push-aside (Tsuji et al.'s MILP TAMP problem), one phase per step.

    ## Description

    A mobile manipulator with a round base (an HSR) must carry every delivery object
    (an upright cylinder standing on a table) to its goal on a table. A piece of
    clutter (a box) may stand on a goal: the robot then pushes it aside first. Tables
    and full-height obstacles (walls, shelves) block the base; obstacles and clutter
    also block the arm's line from the base to the hand (the paper's Eq. 19).

    One step is one phase of the paper's formulation: the base slides in a straight
    line to a point of a lattice over the floor, turns to a heading, and the arm, in
    one of the robot's postures, does nothing, picks, places or pushes. The rules of
    motion and of the arm are the MILP expert's model stated exactly
    (:mod:`fetchcarry_env.rules`, ``docs/design.md``), so that the expert's proven
    optima are optima of the env. The world is simulated in PyBullet: a picked object
    is lifted 5 cm and attached to the hand; a placed object is released standing on
    the table and settles; a push drives the hand through the stroke (1 cm per
    simulation step at most, with at most 30 N) and PyBullet moves the clutter, which
    may shove a neighbour, or jam (the stroke then stops where the hand is).

    The scenario is fixed (``scenario=``) or drawn at every reset from a family
    (``family=``, by default ``"push"``). The whole geometry is in the observation,
    so a planner can rebuild the problem from an observation alone
    (:func:`fetchcarry_env.observation.decode`).

    ## Action Space

    ``MultiDiscrete([nx, ny, 4, n_postures, 4])``: ``[i, j, heading, posture, mode]``.

    | index | meaning | values |
    |-------|---------|--------|
    | 0, 1 | the base's lattice point ``origin + (i, j) * resolution`` (push: stroke end) | ``i < nx``, ``j < ny`` |
    | 2 | heading at the end of the phase | 0 ``+x``, 1 ``+y``, 2 ``-x``, 3 ``-y`` |
    | 3 | arm posture: index into the scenario's ``robot.postures`` | ``k < capacity.postures`` |
    | 4 | mode | 0 move, 1 pick, 2 place, 3 push |

    The lattice covers the scenario's area (fixed scenario) or the family's extent, at
    ``resolution`` metres (5 cm by default). Semantics (``fetchcarry_env/actions.py``):
    pick takes the object within the posture's reach (nearest the middle of the
    ranges); place puts the held object at its goal; push strokes axis-aligned from
    where the base stands, with the heading along the stroke or at right angles to it,
    against the piece of clutter whose rear face the posture reaches (nearest the
    middle of the ranges). The hand may be empty or hold an object (the paper's push
    while carrying the object to be placed): the held object touches nothing, keeps
    its offset from the base and moves with it.

    The rules (``fetchcarry_env/rules.py``; lattice points are tested with exact integer
    bounds, other points such as the start in metres with a 5e-7 m tolerance):

    - a move of the base from ``p`` to ``q`` (a move, the move to a pick's or a place's
      pose, a push stroke) keeps the base disc in the area at both ends and, for every
      table and obstacle, has both ends in one common region of its *octagon*: the
      rectangle grown by the base's radius with its corners cut at 45 degrees (the four
      sides beyond it, ``x >= max_x + r`` and so on, and the four cut corners). Such a
      move touches nothing; any other move is refused (never stopped at a contact);
    - a pick or a place acts from a base on one side of every table and obstacle grown
      by the radius (not in a corner cut); a push stroke keeps both ends on one common side;
    - the arm (the paper's Eq. 19): for every obstacle and piece of clutter (but the one
      pushed) one side half-plane of its rectangle (``x >= max_x`` and so on) holds the
      base (both ends of a stroke) and the hand (both ends of a stroke);
    - reach: a posture reaches a point from a lattice base inside the planner's reach
      box (its exact ranges rounded to the lattice), from another base within its
      ranges widened by 5e-7 m.

    :meth:`action_masks` gives MaskablePPO's flat mask (length ``nx + ny + 4 +
    capacity.postures + 4``): lattice columns and rows where the base disc does not fit
    in the area, postures the robot does not have, pick with a full hand, place with an
    empty one and push without clutter are masked (push is allowed with either hand). An action outside the space
    raises ``ValueError``; an impossible one (masked or not) does nothing (see Rewards).

    ## Observation Space

    A ``Dict`` in the goal-env convention, float32, every coordinate in metres in the
    world frame; absent slots (fewer things than the capacity) are all zero:

    | key | size | content |
    |-----|------|---------|
    | ``observation`` | 4 | area ``min_x, min_y, max_x, max_y`` (m) |
    | | 7 | base ``x, y`` (m), base radius (m), heading one-hot (``+x, +y, -x, -y``) |
    | | 5 per posture | present, ``forward`` low/high (m), ``lateral`` low/high (m) |
    | | 11 per object | present, centre ``x, y, z``, goal centre ``x, y, z``, radius, height (m), held, delivered |
    | | 6 per clutter | present, footprint ``min_x, min_y, max_x, max_y`` (m), height (m) |
    | | 6 per table | present, ``min_x, min_y, max_x, max_y`` (m), height (m) |
    | | 5 per obstacle | present, ``min_x, min_y, max_x, max_y`` (m) |
    | ``achieved_goal`` | 3 per object | each object's centre ``x, y, z`` (m); a held one is lifted 5 cm |
    | ``desired_goal`` | 3 per object | each goal's centre ``x, y, z`` (m), the object standing there |

    The capacity fixes the sizes (``Capacity()``: 4 objects, 8 clutter, 6 tables, 12
    obstacles, 4 postures; by default the family's, which holds every scenario it draws:
    see ``capacity`` below); every bound is +-200 m, which holds every valid world: coordinates
    lie within 100 m of the origin (scenario rule 6) and a held object rides at the hand,
    up to a posture's reach (at most 100 m) from the base and 5 cm above its table.

    Images (``obs_mode``, :mod:`fetchcarry_env.observations`, ``docs/observations.md``)
    sit beside those keys, uint8 in ``[0, 255]``, channels first:

    | ``obs_mode`` | added keys | content |
    |---|---|---|
    | ``"state"`` (default) | none | the table above, bit for bit |
    | ``"topdown"`` | ``topdown`` ``(7, S, S)`` | a semantic map drawn from the geometry (no renderer) |
    | ``"rgbd"`` | ``head_rgbd``, ``overhead_rgbd`` ``(4, C, C)`` | RGB and linear depth, drawn by PyBullet |

    The map's channels: tables, obstacles and walls, objects, goals, clutter, the robot
    (disc 128, front half 255: its heading), the held object; a thing's pixels hold its
    slot level ``255 - 224 k // n`` (slot ``k`` of ``n``). The cameras: one on the robot's
    head (1.2 m up, 35 degrees down along the heading), one straight down over the extent.

    ``topdown_size`` S (64 by default) pixels cover ``topdown_span`` metres (by default
    the extent's longer side: 7 m for the families, 0.11 m a pixel), centred on the
    extent (``topdown_frame="world"``) or on the base (``"robot"``, axis-aligned), north
    up. ``camera_size`` C is 128 by default; ``renderer`` is ``"tiny"`` (PyBullet's CPU
    renderer, the default) or ``"egl"`` (its EGL plugin, when it loads).

    ## Rewards

    The task's cost, one phase at a time, negated: the paper's Eq. 1 counted over the
    whole episode (``docs/formulation.md``, "The task cost"). Each step costs ``10`` for
    every object that is not at its goal after it (its centre within 1 cm of its goal's,
    not held: ``W1`` of Eq. 1, the price of a late delivery), plus the travel cost of the
    base, ``|dx| + |dy| + 0.1 * ||dx| - |dy||`` metres actually travelled (a push stroke
    included), plus 1 when the base stops at a contact, plus 1 for an impossible action
    (masked, or failing a check: nothing in reach, the arm line blocked, a goal
    occupied...), which moves nothing. So the return of an episode is minus its cost:
    ``-(travel + 10 * sum over objects of the steps before it was delivered + penalties)``,
    the value the MILP expert's plans minimise (a plan's ``objective``), and an episode that
    leaves an object undelivered pays for it at every step until the time limit.
    :meth:`compute_reward` gives the same value from ``(achieved_goal, desired_goal,
    info)`` and works on batches (for HER).

    ## Starting State

    The scenario's start: the base at ``robot.start`` with ``robot.heading``, the hand
    empty, objects standing at their starts, clutter where the scenario puts it. With a
    family, the scenario is drawn from ``self.np_random`` at every reset, so
    ``reset(seed=s)`` gives the same scenario and episode for the same ``s``.
    ``reset(options={"scenario": ...})`` starts a given scenario instead (it must lie in
    the lattice's extent and fit the capacity).

    ## Episode End

    ``terminated`` when every object stands at its goal and the hand is empty.
    ``truncated`` after ``max_episode_steps`` phases (50 for ``FetchCarryPush-v0``, set
    by the registration's ``TimeLimit``).

    ``info`` (reset and step): ``is_success`` (bool), ``delivered`` (objects at their
    goals), ``path_length`` (metres the base has travelled this episode),
    ``travel_cost`` (the paper's cost of those moves so far: Manhattan plus the diagonal term),
    ``task_cost`` (the task's cost so far: minus the return, see Rewards),
    ``collisions`` (contacts so far: always 0 under the rules, kept for the interface),
    ``invalid_action`` (a short reason, or None; a refused move names the table or
    obstacle whose octagon it breaks), ``contact`` (what the base touched this step:
    always None, as no accepted move touches anything), ``travel`` and
    ``penalty`` (this step's travel cost and penalties), ``previous_achieved_goal``
    (the objects' centres before the step) and ``push`` (after a push: the clutter's id, the
    stroke asked and travelled in metres, whether it jammed).

    ## Arguments

    ```python
    gym.make("FetchCarryPush-v0", scenario=None, family=None, resolution=0.05, capacity=None,
             physics=None, render_mode=None, camera="perspective", width=320, height=240,
             obs_mode="state", topdown_size=64, topdown_frame="world", topdown_span=None,
             camera_size=128, renderer="tiny")
    ```

    - ``scenario``: a :class:`~fetchcarry_env.scenario.Scenario`, a scenario mapping or
      the path of a scenario file (``fetchcarry-scenario/1``); a scenario that breaks a
      rule raises :class:`~fetchcarry_env.scenario.ScenarioError`.
    - ``family``: the name of a scenario family (``basic``, ``push``, ``corridor``,
      ``multi``, ``mixed``); give at most one of ``scenario`` and ``family``.
    - ``resolution``: metres between lattice points.
    - ``capacity``: the observation's slots: a :class:`~fetchcarry_env.observation.Capacity`,
      a mapping of its counts or a text ``"objects=8,clutter=12"`` (the other counts
      the default's). By default the family's (:attr:`Family.capacity`, which holds every
      scenario it draws), or for a fixed scenario the default grown to hold it.
    - ``physics``: a physics variation (:mod:`fetchcarry_env.worlds.physics`): a name
      (``"home"``), a ``PhysicsVariation``, or ``"none"``; by default the family's
      (``perturbed``: ``"home"``; a fixed scenario: none). Each piece of clutter's mass
      and friction are then drawn from ``np_random`` at every reset, after the scenario.
    - ``render_mode``: ``"rgb_array"`` (headless, PyBullet's tiny renderer) or
      ``"human"`` (a PyBullet window). ``"human"`` needs a display: without one it
      raises :class:`~fetchcarry_env.errors.InputError`, and the instance's
      ``metadata["render_modes"]`` lists only ``"rgb_array"``.
    - ``camera``: ``"perspective"`` or ``"top_down"`` for ``rgb_array`` frames of
      ``width`` x ``height`` pixels.
    - ``obs_mode``: ``"state"``, ``"topdown"`` or ``"rgbd"`` with its image options (see
      Observation Space); an image option without an image mode raises ``TypeError``.

    The unwrapped env exposes ``scenario``, ``state`` (a
    :class:`~fetchcarry_env.observation.WorldState`), ``lattice``, ``capacity`` and
    ``action_masks()``. Copies (``copy.copy``, ``copy.deepcopy``, ``pickle``) are
    independent envs in the same state, with their own PyBullet world, that continue
    exactly (bit for bit) as the original would; an env with ``render_mode="human"``
    refuses to be copied (``TypeError``). ``close()`` disconnects from PyBullet (twice
    is safe); an env used after ``close()`` reconnects and continues where it was.

    ## Version History

    - v0: first version; a push may be made while holding an object (the paper's
      push-aside while carrying), masks allow it.
    - v0, the rules become the planner's model (the id stays v0, as the project's
      interface requires): a move is allowed when each table's and obstacle's octagon has
      a region holding both its ends, else refused as an invalid action (it was stopped at
      its first contact, with the contact penalty); acting poses lie on a side of each
      table and obstacle; the arm rule is the common side half-plane; reach is the
      planner's (it had 1 mm of tolerance). No accepted move touches anything, so
      ``contact`` is None and ``collisions`` 0.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array", "human"], "render_fps": 2}

    def __init__(
        self,
        scenario: ScenarioLike | None = None,
        family: str | None = None,
        resolution: float = DEFAULT_RESOLUTION,
        capacity: Capacity | Mapping[str, int] | str | None = None,
        physics: str | PhysicsVariation | None = None,
        render_mode: str | None = None,
        camera: str = "perspective",
        width: int = DEFAULT_IMAGE_SIZE[0],
        height: int = DEFAULT_IMAGE_SIZE[1],
        obs_mode: str = "state",
        **image_options: Any,
    ) -> None:
        self._check_arguments(scenario, family, render_mode, camera, width, height)
        images = bool(get_mode(obs_mode).keys)  # get_mode: ValueError for an unknown mode
        if not images and image_options:
            raise TypeError(f"image options {sorted(image_options)} need an obs_mode with images, not {obs_mode!r}")
        # "human" is offered only where a window can open (Gymnasium's checker tries every mode listed).
        modes = ["rgb_array", "human"] if display_available() else ["rgb_array"]
        self.metadata = {**type(self).metadata, "render_modes": modes}
        self._fixed: Scenario | None = None
        self._family_name: str | None = None
        if scenario is not None:
            self._fixed = _as_scenario(scenario)
            extent = self._fixed.area
            self.capacity = _as_capacity(capacity, Capacity().holding(self._fixed))
        else:
            self._family_name = family if family is not None else DEFAULT_FAMILY
            extent = self._family.extent
            self.capacity = _as_capacity(capacity, self._family.capacity)
        default_physics = self._family.physics if self._family_name is not None else None
        self.physics = physics_variation(physics) if physics is not None else default_physics
        self._item_physics: dict[str, ItemPhysics] = {}  # this episode's clutter masses and frictions
        self.lattice = Lattice.over(extent, resolution)
        self._extent: Rect = extent
        if self._fixed is not None:
            self._check_fits(self._fixed)
        self.render_mode = render_mode
        self.camera = camera
        self.image_size = (width, height)
        self.action_space = spaces.MultiDiscrete(action_nvec(self.lattice, self.capacity.postures))
        self.observation_space = observation_space(self.capacity)
        self.obs_mode = obs_mode
        self._images: ImageObservations | None = None  # None: the state observation alone
        if images:
            self._images = ImageObservations(obs_mode, extent, self.capacity, image_options)
            self.observation_space = self._images.space(self.observation_space)
        self._sim = Simulation(gui=render_mode == "human")  # connects to PyBullet on first use
        self._sim_in_sync = False  # False until reset, and after close() or a copy: rebuilt on next use
        self._snapshot: Snapshot | None = None  # the world's exact poses to rebuild from (copies, close)
        self._scenario: Scenario | None = None
        self._state: WorldState | None = None
        self._achieved: np.ndarray | None = None
        self._path_length = 0.0
        self._travel_cost = 0.0
        self._task_cost = 0.0
        self._collisions = 0

    @classmethod
    def _check_arguments(
        cls, scenario: object, family: str | None, render_mode: str | None, camera: str, width: int, height: int
    ) -> None:
        """``ValueError`` for both a scenario and a family, an unknown mode or camera, or an empty image."""
        if scenario is not None and family is not None:
            raise ValueError("give a scenario or a family, not both")
        if render_mode is not None and render_mode not in cls.metadata["render_modes"]:
            modes = cls.metadata["render_modes"]
            raise ValueError(f"render_mode must be one of {modes} or None, got {render_mode!r}")
        if camera not in CAMERAS:
            raise ValueError(f"camera must be one of {', '.join(CAMERAS)}, got {camera!r}")
        if width < 1 or height < 1:
            raise ValueError(f"image size must be positive, got {width} x {height}")
        if render_mode == "human":
            check_display()

    # ------------------------------------------------------------------ public state
    @property
    def scenario(self) -> Scenario:
        """The scenario of the current episode."""
        if self._scenario is None:
            raise gym.error.ResetNeeded("call reset() before using the environment")
        return self._scenario

    @property
    def state(self) -> WorldState:
        """Where the base, the hand's object, the objects and the clutter are now."""
        if self._state is None:
            raise gym.error.ResetNeeded("call reset() before using the environment")
        return self._state

    # ------------------------------------------------------------------ Gymnasium API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        super().reset(seed=seed)
        options = options or {}
        unknown = set(options) - {"scenario"}
        if unknown:
            raise ValueError(f"unknown reset option(s) {sorted(unknown)}: the only option is 'scenario'")
        if options.get("scenario") is not None:
            scenario = _as_scenario(options["scenario"])
            self._check_fits(scenario)
        elif self._fixed is not None:
            scenario = self._fixed
        else:
            scenario = self._family.sample(self.np_random)
            self._check_fits(scenario)
        self._scenario = scenario
        self._state = WorldState.initial(scenario)
        self._item_physics = self.physics.draw(self.np_random, scenario) if self.physics is not None else {}
        self._sim.reset(scenario, self._state, item_physics=self._item_physics)
        self._sim_in_sync, self._snapshot = True, None
        self._path_length = 0.0
        self._travel_cost = 0.0
        self._task_cost = 0.0
        self._collisions = 0
        observation = encode(scenario, self._state, self.capacity)
        if self._images is not None:
            self._images.add(observation, scenario, self._state, self._sim)
        self._achieved = observation["achieved_goal"]
        info = self._info(observation, travel=0.0, penalty=0.0, invalid=None, contact=None)
        if self.render_mode == "human":
            self.render()
        return observation, info

    def step(self, action: np.ndarray) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        decoded = self._decode(action)
        scenario, state = self.scenario, self.state
        self._sync_sim()
        phase = check_action(scenario, state, self.lattice, decoded)
        contact: str | None = None  # an accepted move never touches anything (rules.move_refusal)
        push_report: dict[str, Any] | None = None
        if isinstance(phase, str):
            invalid, travel, penalty = phase, 0.0, INVALID_ACTION_PENALTY
        elif phase.mode == Mode.PUSH:
            invalid = None
            push_report = self._push(phase)
        else:
            invalid = None
            self._move_and_act(phase)
        if invalid is None:
            travel = travel_cost(state.base, self._state.base)
            penalty = COLLISION_PENALTY if contact is not None else 0.0
            self._path_length += math.dist(state.base, self._state.base)
            self._travel_cost += travel
            self._collisions += contact is not None
        observation = encode(scenario, self._state, self.capacity)
        if self._images is not None:
            self._images.add(observation, scenario, self._state, self._sim)
        info = self._info(observation, travel=travel, penalty=penalty, invalid=invalid, contact=contact)
        if push_report is not None:
            info["push"] = push_report
        reward = float(self.compute_reward(observation["achieved_goal"], observation["desired_goal"], info))
        self._task_cost -= reward
        info["task_cost"] = self._task_cost
        self._achieved = observation["achieved_goal"]
        terminated = bool(info["is_success"])
        if self.render_mode == "human":
            self.render()
        return observation, reward, terminated, False, info

    def compute_reward(
        self, achieved_goal: np.ndarray, desired_goal: np.ndarray, info: Mapping[str, Any] | Sequence | np.ndarray
    ) -> np.ndarray | float:
        """The step reward from the goals and ``info`` (one transition, or a batch as HER passes it).

        Minus ``10 * (objects not at their goals after the step)``, the step's travel cost
        and its penalties; ``info`` is one step's info dict, or a sequence (or object array)
        of them for a batch of ``achieved_goal`` / ``desired_goal`` rows.
        """
        achieved = np.asarray(achieved_goal, dtype=np.float64)
        desired = np.asarray(desired_goal, dtype=np.float64)
        if isinstance(info, Mapping):
            cost = float(info["travel"]) + float(info["penalty"])
        else:
            infos = list(np.asarray(info, dtype=object).reshape(-1))
            cost = np.array([float(i["travel"]) + float(i["penalty"]) for i in infos]).reshape(achieved.shape[:-1])
        waiting = achieved.shape[-1] // 3 - _count_at_goal(achieved, desired)  # absent slots count as at goal
        reward = -(WAIT_COST * waiting + cost)
        return float(reward) if np.ndim(reward) == 0 else reward

    def action_masks(self) -> np.ndarray:
        """MaskablePPO's flat boolean mask over the action components (length ``sum(nvec)``)."""
        return action_mask(self.scenario, self.state, self.lattice, self.capacity.postures)

    def render(self) -> np.ndarray | None:
        """An RGB frame (``rgb_array``), or None (``human``: the PyBullet window shows the world)."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode: pass render_mode='rgb_array' to gym.make")
            return None
        if self.render_mode == "human":
            return None
        self.scenario  # noqa: B018  (raises ResetNeeded before the first reset)
        self._sync_sim()
        return self._sim.render(self.camera, *self.image_size)

    def close(self) -> None:
        """Disconnect from PyBullet (safe to call twice).

        The episode is kept: using the env again reconnects and rebuilds the world where it was.
        """
        if self._sim_in_sync:
            self._snapshot = self._sim.snapshot()
        self._sim.close()
        self._sim_in_sync = False

    # ------------------------------------------------------------------ copying
    def __getstate__(self) -> dict[str, Any]:
        """What ``pickle`` and ``copy.deepcopy`` keep: everything but the PyBullet world, plus its exact poses."""
        if self.render_mode == "human":
            raise TypeError("an env with render_mode='human' cannot be copied: PyBullet allows one window per process")
        state = {k: v for k, v in self.__dict__.items() if k != "_sim"}
        state["_snapshot"] = self._sim.snapshot() if self._sim_in_sync else self._snapshot
        state["_sim_in_sync"] = False
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._sim = Simulation(gui=False)  # rebuilt from the snapshot on first use

    def __copy__(self) -> FetchCarryPushEnv:
        """A shallow copy would share the random generator and the PyBullet world: make an independent one."""
        return copy.deepcopy(self)

    # ------------------------------------------------------------------ internals
    def _move_and_act(self, phase: ResolvedPhase) -> None:
        """Execute a move, pick or place phase (the rules allowed the move: it touches nothing)."""
        state = self._state
        end = phase.base
        held = self._sim.move(end, phase.heading, state.holding)
        objects = dict(state.objects)
        if held is not None:
            objects[state.holding] = held
        self._state = state = replace(state, base=end, heading=phase.heading, objects=objects)
        if phase.mode == Mode.PICK:
            lifted = self._sim.pick(phase.target, end, phase.heading)
            self._state = replace(state, holding=phase.target, objects={**objects, phase.target: lifted})
        elif phase.mode == Mode.PLACE:
            poses = self._sim.place(phase.target, end, phase.heading, phase.hand)
            self._state = self._with_poses(replace(state, holding=None), poses)

    def _push(self, phase: ResolvedPhase) -> dict[str, Any]:
        """Execute a push phase (the rules allowed the stroke: the base touches nothing); report the stroke."""
        state = self._state
        length = math.dist(state.base, phase.base)
        report = {"clutter": phase.target, "stroke": phase.stroke, "travelled": 0.0, "stalled": False}
        offset = hand_offset(state.base, phase.heading, phase.hand)
        outcome = self._sim.push(phase.target, state.base, phase.heading, offset, phase.direction, length)
        ux, uy = heading_vector(phase.direction)
        base = (state.base[0] + ux * outcome.travelled, state.base[1] + uy * outcome.travelled)
        objects = state.objects if outcome.held is None else {**state.objects, state.holding: outcome.held}
        moved = replace(state, base=base, heading=phase.heading, objects=objects)
        self._state = self._with_poses(moved, self._sim.poses)
        report.update(travelled=outcome.travelled, stalled=outcome.stalled)
        return report

    def _with_poses(self, state: WorldState, poses: Mapping[str, tuple]) -> WorldState:
        """``state`` with every item that is not held where the simulation has it."""
        objects = dict(state.objects)
        clutter = dict(state.clutter)
        for name, (position, _orientation) in poses.items():
            if name in clutter:
                clutter[name] = (position[0], position[1])
            elif name in objects and name != state.holding:
                objects[name] = tuple(position)
        return replace(state, objects=objects, clutter=clutter)

    @property
    def _family(self) -> Family:
        """The family scenarios are drawn from (looked up by name, so that copies need not pickle it)."""
        return get_family(self._family_name)

    def _sync_sim(self) -> None:
        """Rebuild the simulation after a copy or close(), exactly where the world was."""
        if self._sim_in_sync:
            return
        self._sim.reset(self.scenario, self.state, self._snapshot, item_physics=self._item_physics)
        self._sim_in_sync, self._snapshot = True, None

    def _decode(self, action: Any) -> Action:
        """The action as an :class:`Action`; ``ValueError`` naming the problem if it is not in the space."""
        return Action.from_array(action_vector(action, self.action_space.nvec, ACTION_COMPONENTS))

    def _check_fits(self, scenario: Scenario) -> None:
        """Raise :class:`ScenarioError` if ``scenario`` does not fit the lattice's extent or the capacity."""
        problems = []
        if not self._extent.contains_rect(scenario.area, tol=1e-9):
            problems.append(
                f"env: the area {list(scenario.area.min)}-{list(scenario.area.max)} does not lie in the "
                f"action lattice's extent {list(self._extent.min)}-{list(self._extent.max)}"
            )
        try:
            self.capacity.check(scenario)
        except ValueError as error:
            problems.append(f"env: {error}")
        if problems:
            raise ScenarioError(problems, scenario.name)

    def _info(
        self,
        observation: dict[str, np.ndarray],
        *,
        travel: float,
        penalty: float,
        invalid: str | None,
        contact: str | None,
    ) -> dict[str, Any]:
        n_objects = len(self._scenario.objects)
        at_goal = _at_goal(observation["achieved_goal"], observation["desired_goal"])[:n_objects]
        delivered = int(at_goal.sum())
        return {
            "is_success": bool(delivered == n_objects and self._state.holding is None),
            "delivered": delivered,
            "path_length": self._path_length,
            "travel_cost": self._travel_cost,
            "task_cost": self._task_cost,
            "collisions": self._collisions,
            "invalid_action": invalid,
            "contact": contact,
            "travel": travel,
            "penalty": penalty,
            "previous_achieved_goal": (
                self._achieved if self._achieved is not None else observation["achieved_goal"]
            ).copy(),
        }


def _as_capacity(capacity: Capacity | Mapping[str, int] | str | None, default: Capacity) -> Capacity:
    """The env's capacity from its ``capacity`` argument (see the class docstring), ``default`` if None."""
    if capacity is None:
        return default
    if isinstance(capacity, Capacity):
        return capacity
    if isinstance(capacity, str):
        return Capacity.parse(capacity)
    if isinstance(capacity, Mapping):
        return Capacity.parse(",".join(f"{k}={v}" for k, v in capacity.items())) if capacity else Capacity()
    raise TypeError(f"capacity must be a Capacity, a mapping or a text, got {type(capacity).__name__}")


def _as_scenario(scenario: ScenarioLike) -> Scenario:
    """A validated scenario from a :class:`Scenario`, a mapping or a path; :class:`ScenarioError` names broken rules."""
    if isinstance(scenario, Scenario):
        violations = check_rules(scenario)  # the constructor trusts its input: check it here
        if violations:
            raise ScenarioError(violations, scenario.name)
        return scenario
    if isinstance(scenario, Mapping):
        return Scenario.from_dict(scenario)
    if isinstance(scenario, str | Path):
        return Scenario.load(scenario)
    raise TypeError(f"scenario must be a Scenario, a mapping or a path, got {type(scenario).__name__}")


def _at_goal(achieved: np.ndarray, desired: np.ndarray) -> np.ndarray:
    """Per object slot (last axis grouped by 3): True when within ``DELIVERY_TOLERANCE`` of its goal."""
    a = np.asarray(achieved, dtype=np.float64)
    d = np.asarray(desired, dtype=np.float64)
    gap = np.linalg.norm((a - d).reshape(*a.shape[:-1], -1, 3), axis=-1)
    return gap <= DELIVERY_TOLERANCE


def _count_at_goal(achieved: np.ndarray, desired: np.ndarray) -> np.ndarray:
    """How many object slots are at their goals (absent slots are zero in both and count alike)."""
    return _at_goal(achieved, desired).sum(axis=-1)
