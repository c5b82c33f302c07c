"""The PyBullet world of one environment: builds a scenario's bodies and runs the phase primitives.

:class:`Simulation` owns one private physics server (made lazily, closed by
:meth:`Simulation.close`), keeps the bodies of the current layout across resets and
rebuilds them only when the layout changes (``Scenario.layout_key``). It knows nothing
about actions, masks or rewards: the environment decides what is possible (with the
pure rules of :mod:`fetchcarry_env.rules`) and calls a primitive, which moves the
bodies and reports where things ended up.

Between phases the world is at rest. Each primitive that runs the physics (place,
push) starts from the recorded poses with zero velocities and fresh contacts, so its
outcome is a function of those poses alone: a copy of an environment, or a replay
from the same state, gives bit-for-bit the same result.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

import fetchcarry_env.sim.physics as physics
from fetchcarry_env.geometry import Heading, Point, heading_vector, to_world_frame
from fetchcarry_env.kinematics import HAND_HALF_SIZE, hand_offset
from fetchcarry_env.observation import LIFT_HEIGHT, Point3, WorldState
from fetchcarry_env.scenario import Scenario
from fetchcarry_env.sim.bodies import IDENTITY, LayoutBodies, build_layout, table_top
from fetchcarry_env.sim.camera import Camera, render_image
from fetchcarry_env.sim.client import QuietClient, connect
from fetchcarry_env.sim.robot import HandPose, RobotBody

Quaternion = tuple[float, float, float, float]
Pose = tuple[Point3, Quaternion]
"""A body's position (metres) and orientation (quaternion x, y, z, w)."""

PARKING_DISTANCE = 1000.0  # metres: where bodies are parked for a moment to drop their cached contacts
PARKING_SPACING = 10.0  # metres between parked bodies
HAND_LIFT = 0.001  # metres between the table top and the hand's underside when pushing low clutter


@dataclass(frozen=True)
class PushOutcome:
    """What a push stroke did: how far the hand (and the base) went, and whether the clutter jammed."""

    travelled: float  # metres along the stroke, at most the length asked for
    stalled: bool  # True when the pushed clutter stopped moving with the hand (jammed)
    simulation_steps: int  # stepSimulation calls the stroke and its settling took
    held: Point3 | None = None  # the held object's centre after the stroke (metres), if the hand holds one


@dataclass(frozen=True)
class Snapshot:
    """What a rebuilt world needs to continue exactly as this one: every free item's pose, and the hand.

    ``poses`` holds each object and piece of clutter that is not held (position in metres,
    orientation as a quaternion); ``hand`` is the hand's pose relative to the base (it
    carries the held object, if any, at exactly that offset).
    """

    poses: dict[str, Pose]
    hand: HandPose


class Simulation:
    """One PyBullet world for one environment: bodies of the current layout and the phase primitives."""

    def __init__(self, gui: bool = False) -> None:
        self._gui = gui
        self._client: QuietClient | None = None
        self._layout_key: tuple | None = None
        self._bodies: LayoutBodies | None = None
        self._robot: RobotBody | None = None
        self._scenario: Scenario | None = None
        self._poses: dict[str, Pose] = {}
        self._held: str | None = None
        self._varied = False  # some clutter has a mass or friction of its own (see reset's item_physics)
        self._built_dynamics: dict[int, tuple[float, tuple[float, ...], float]] = {}  # body -> as built
        self.builds = 0  # how many times bodies were (re)built, for tests and the benchmark

    # ------------------------------------------------------------------ lifecycle
    @property
    def client(self) -> QuietClient:
        """The physics client, connected on first use."""
        if self._client is None or not self._client.connected:
            self._client = connect(self._gui)
            self._layout_key = None
        return self._client

    @property
    def connected(self) -> bool:
        """True while this simulation has a physics server (it connects on first use)."""
        return self._client is not None and self._client.connected

    def close(self) -> None:
        """Disconnect from the physics server (safe to call twice; the next use reconnects)."""
        if self._client is not None:
            self._client.close()
        self._client = None
        self._layout_key = None
        self._bodies = None
        self._robot = None

    def __getstate__(self):
        raise TypeError(
            "a Simulation owns a PyBullet server and cannot be pickled or copied; "
            "copy the environment instead (it rebuilds its simulation from the recorded poses)"
        )

    # ------------------------------------------------------------------ scenario and state
    def reset(
        self,
        scenario: Scenario,
        state: WorldState,
        snapshot: Snapshot | None = None,
        item_physics: Mapping[str, tuple[float, float]] | None = None,
    ) -> None:
        """Show ``scenario`` at ``state``: rebuild the bodies if the layout changed, then pose everything.

        Items stand upright where ``state`` puts them, or take the exact poses of ``snapshot``
        (taken from another world in the same state: a copied environment continues with it).
        ``item_physics`` gives some pieces of clutter their own ``(mass kg, friction)``; the
        others get :data:`physics.CLUTTER_MASS` and :data:`physics.FRICTION`.
        """
        client = self.client
        if self._layout_key != scenario.layout_key:
            self._build(scenario)
        self._scenario = scenario
        self._set_clutter_physics(scenario, item_physics or {})
        robot = self._robot_body
        for obj in scenario.objects:
            marker = (obj.goal[0], obj.goal[1], table_top(scenario, obj.goal))
            client.resetBasePositionAndOrientation(self._layout.goal_markers[obj.id], marker, IDENTITY)
        if self._held is not None:
            self._release(self._held)
        robot.set_base(state.base, state.heading)
        if snapshot is not None:
            self._poses = {name: (tuple(p), tuple(q)) for name, (p, q) in snapshot.poses.items()}
            robot.set_hand(snapshot.hand)
        else:
            self._poses = self._standing_poses(scenario, state)
            if state.holding is None:
                robot.set_hand(robot.rest_hand)
            else:
                held = state.objects[state.holding]
                robot.set_hand(HandPose(*hand_offset(state.base, state.heading, held[:2]), held[2]))
        if state.holding is not None:
            self._grasp(state.holding, self._hand_world_position())
        self._fresh_contacts()

    def _set_clutter_physics(self, scenario: Scenario, values: Mapping[str, tuple[float, float]]) -> None:
        """Give the clutter in ``values`` its mass (inertia scaled alike) and friction, the rest the built ones.

        Nothing is called while no variation was ever set on these bodies, so worlds
        without one step exactly as before variations existed.
        """
        if not values and not self._varied:
            return
        client = self.client
        for item in scenario.clutter:
            body = self._layout.clutter[item.id]
            if body not in self._built_dynamics:
                info = client.getDynamicsInfo(body, -1)
                self._built_dynamics[body] = (info[0], tuple(info[2]), info[1])  # mass, inertia, friction
            mass, inertia, friction = self._built_dynamics[body]
            if item.id in values:
                new_mass, friction = values[item.id]
                inertia, mass = tuple(v * new_mass / mass for v in inertia), new_mass
            client.changeDynamics(body, -1, mass=mass, localInertiaDiagonal=inertia, lateralFriction=friction)
        self._varied = bool(values)

    def snapshot(self) -> Snapshot:
        """The exact state of this world between phases (see :class:`Snapshot`)."""
        return Snapshot(dict(self._poses), self._robot_body.hand)

    def rebuild(self, state: WorldState) -> None:
        """Build the bodies again exactly where they are (``state``: the world's state now).

        A renderer plugin loaded after the bodies were made (PyBullet's EGL) sees only bodies made after it.
        """
        snapshot = self.snapshot()
        self._layout_key = None
        self.reset(self._scenario, state, snapshot)

    @property
    def poses(self) -> dict[str, Pose]:
        """The recorded pose of every item that is not held."""
        return dict(self._poses)

    @staticmethod
    def _standing_poses(scenario: Scenario, state: WorldState) -> dict[str, Pose]:
        """Upright poses of every item not held, as ``state`` places them (clutter on its table)."""
        poses: dict[str, Pose] = {}
        for obj in scenario.objects:
            if obj.id != state.holding:
                poses[obj.id] = (tuple(state.objects[obj.id]), IDENTITY)
        for item in scenario.clutter:
            x, y = state.clutter[item.id]
            poses[item.id] = ((x, y, table_top(scenario, (x, y)) + item.height / 2), IDENTITY)
        return poses

    # ------------------------------------------------------------------ primitives
    def move(self, base: Point, heading: Heading, holding: str | None) -> Point3 | None:
        """Teleport the base (the caller has checked the segment is free); a held object follows the hand.

        Returns the held object's new centre, or None.
        """
        self._robot_body.set_base(base, heading)
        if holding is None:
            return None
        position = self._hand_world_position()
        self.client.resetBasePositionAndOrientation(self._layout.objects[holding], position, IDENTITY)
        return position

    def pick(self, object_id: str, base: Point, heading: Heading) -> Point3:
        """Grasp ``object_id`` (within reach of the hand from this pose) and lift it by ``LIFT_HEIGHT``.

        Returns the object's new centre. The object is attached to the hand: it goes where
        the hand goes and touches nothing until it is placed.
        """
        robot = self._robot_body
        robot.set_base(base, heading)
        (x, y, z), _ = self._poses.pop(object_id)
        lifted = (x, y, z + LIFT_HEIGHT)
        robot.set_hand(HandPose(*hand_offset(base, heading, lifted[:2]), lifted[2]))
        self._grasp(object_id, lifted)
        return lifted

    def place(self, object_id: str, base: Point, heading: Heading, goal: Point) -> dict[str, Pose]:
        """Put the held object down standing at ``goal``, release it and let the world settle.

        The hand then goes back to its rest pose. Returns the pose of every item after settling.
        """
        obj = self._scenario.object(object_id)
        standing = (goal[0], goal[1], table_top(self._scenario, goal) + obj.height / 2)
        robot = self._robot_body
        robot.set_base(base, heading)
        self._release(object_id)
        self._poses[object_id] = (standing, IDENTITY)
        robot.set_hand(robot.rest_hand)
        self._fresh_contacts()
        step = self.client.stepSimulation
        for _ in range(physics.PLACE_SETTLE_STEPS):
            step()
        return self._read_poses()

    def push(
        self,
        clutter_id: str,
        base: Point,
        heading: Heading,
        hand: tuple[float, float],
        direction: Heading,
        length: float,
    ) -> PushOutcome:
        """Stroke the hand ``length`` metres along ``direction`` against ``clutter_id``; the base follows.

        The hand starts at the robot-frame offset ``hand`` (``(forward, lateral)``, touching
        the clutter's rear face), at the clutter's mid-height (at least just above the table
        top), and moves at most :data:`physics.MAX_HAND_STEP` per simulation step along a
        smooth speed profile (:func:`stroke_profile`). The arm holds the pusher with at most
        :data:`physics.PUSH_FORCE`; PyBullet moves the clutter and whatever it runs into. When
        the pusher falls :data:`physics.STALL_DEPTH` behind the hand's path, the push is jammed
        and the stroke stops where the pusher is. The hand then lets go, the world settles,
        every item's pose is read back (:attr:`poses`), and the base ends ``travelled`` metres
        along the stroke with the hand back at rest.

        A hand that holds an object pushes with the object in it (the paper's push while
        carrying): the object touches nothing (its contacts stay off) and, after the
        stroke, the hand goes back to the offset it carried the object at, so the object
        has moved with the base (:attr:`PushOutcome.held`).
        """
        robot = self._robot_body
        carry = robot.hand if self._held is not None else None
        ux, uy = heading_vector(direction)
        hand_z = self._push_hand_height(clutter_id)
        robot.set_base(base, heading)
        robot.set_hand(HandPose(hand[0], hand[1], hand_z))
        self._fresh_contacts()
        start_x, start_y = (b + d for b, d in zip(base, to_world_frame(heading, *hand), strict=True))
        robot.grip_pusher((start_x, start_y, hand_z))
        travelled, stalled, steps = self._stroke((start_x, start_y, hand_z), (ux, uy), length)
        robot.release_pusher()  # the hand lets go and the world settles
        for _ in range(physics.PUSH_SETTLE_STEPS):
            self.client.stepSimulation()
        steps += physics.PUSH_SETTLE_STEPS
        robot.set_base((base[0] + ux * travelled, base[1] + uy * travelled), heading)
        held = self._hand_back(carry)
        self._read_poses()
        return PushOutcome(travelled=max(travelled, 0.0), stalled=stalled, simulation_steps=steps, held=held)

    def _push_hand_height(self, clutter_id: str) -> float:
        """The hand's height for a push of ``clutter_id``: its mid-height, at least just above the table top."""
        (_, _, center_z), _ = self._poses[clutter_id]
        item_height = self._scenario.clutter_item(clutter_id).height
        return center_z - item_height / 2 + max(item_height / 2, HAND_HALF_SIZE + HAND_LIFT)

    def _stroke(self, start: Point3, unit: Point, length: float) -> tuple[float, bool, int]:
        """Drive the gripped pusher from ``start`` along ``unit`` (:func:`stroke_profile`) until done or jammed.

        Returns how far the pusher went along the stroke (``length`` unless it stalled),
        whether it stalled, and the simulation steps it took.
        """
        start_x, start_y, hand_z = start
        ux, uy = unit
        robot = self._robot_body
        step, drive, reached = self.client.stepSimulation, robot.drive_pusher, robot.pusher_position
        travelled, stalled, steps = 0.0, False, 0
        for s in stroke_profile(length):
            drive((start_x + ux * s, start_y + uy * s, hand_z))
            step()
            steps += 1
            x, y, _ = reached()
            travelled = (x - start_x) * ux + (y - start_y) * uy
            if s - travelled > physics.STALL_DEPTH:
                stalled = True
                break
        if not stalled:
            travelled = length
        return travelled, stalled, steps

    def _hand_back(self, carry: HandPose | None) -> Point3 | None:
        """After a stroke, the hand at rest, or back where it carried the object (then where the object is)."""
        robot = self._robot_body
        if carry is None:
            robot.set_hand(robot.rest_hand)
            return None
        # The held object fell freely through the stroke, touching nothing: back into the hand.
        robot.set_hand(carry)
        held = self._hand_world_position()
        self._grasp(self._held, held)
        return held

    # ------------------------------------------------------------------ reading back
    def item_position(self, name: str) -> Point3:
        """Where PyBullet has the centre of object or clutter ``name`` (metres)."""
        bodies = self._layout
        body = bodies.objects.get(name, bodies.clutter.get(name))
        if body is None:
            raise KeyError(f"no object or clutter named {name!r}")
        return tuple(self.client.getBasePositionAndOrientation(body)[0])

    def body_id(self, name: str) -> int:
        """PyBullet body id of a table, obstacle, object or clutter by scenario id (``"robot"`` for the robot)."""
        if name == "robot":
            return self._robot_body.body
        bodies = self._layout
        for group in (bodies.tables, bodies.obstacles, bodies.objects, bodies.clutter):
            if name in group:
                return group[name]
        raise KeyError(f"no body named {name!r}")

    @property
    def robot(self) -> RobotBody:
        return self._robot_body

    def render(self, camera: Camera, width: int, height: int) -> np.ndarray:
        """An RGB image (``height x width x 3``, uint8) of the world seen by ``camera``."""
        return render_image(self.client, self._scenario, camera, width, height)

    # ------------------------------------------------------------------ internals
    @property
    def _layout(self) -> LayoutBodies:
        if self._bodies is None:
            raise RuntimeError("the simulation has no scenario yet: call reset() first")
        return self._bodies

    @property
    def _robot_body(self) -> RobotBody:
        if self._robot is None:
            raise RuntimeError("the simulation has no scenario yet: call reset() first")
        return self._robot

    def _build(self, scenario: Scenario) -> None:
        client = self.client
        client.resetSimulation()
        client.setGravity(0.0, 0.0, -physics.GRAVITY)
        client.setPhysicsEngineParameter(
            fixedTimeStep=physics.TIME_STEP,
            numSolverIterations=physics.SOLVER_ITERATIONS,
            erp=physics.CONSTRAINT_ERP,
            deterministicOverlappingPairs=1,
            collisionFilterMode=0,  # AND: two shapes touch only when each one's group is in the other's mask
        )
        self._bodies = build_layout(client, scenario)
        tops = [t.height for t in scenario.tables] or [0.0]
        standing = [o.height for o in scenario.objects] + [c.height for c in scenario.clutter]
        arm_height = max(max(tops) + max(standing) + physics.ARM_CLEARANCE, physics.BASE_HEIGHT + 0.1)
        self._robot = RobotBody(client, scenario.robot.radius, arm_height, lowest_hand=min(tops))
        self._layout_key = scenario.layout_key
        self._held = None
        self._varied = False
        self._built_dynamics = {}
        self.builds += 1

    def _hand_world_position(self) -> Point3:
        """Where the hand's centre is in the world (metres), from the base pose and the hand's offset."""
        robot = self._robot_body
        (x, y), heading = robot.pose
        dx, dy = to_world_frame(heading, robot.hand.forward, robot.hand.lateral)
        return (x + dx, y + dy, robot.hand.z)

    def _grasp(self, object_id: str, position: Point3) -> None:
        """Attach an object to the hand: it touches nothing and goes where the hand goes.

        Its contacts are switched off and it keeps its mass: while physics runs with the
        hand full (a push while carrying) it falls freely, touching nothing, and the push
        puts it back into the hand afterwards; a place lets go first.
        """
        client = self.client
        body = self._layout.objects[object_id]
        client.setCollisionFilterGroupMask(body, -1, physics.GROUP_ITEM, physics.MASK_NONE)
        client.resetBasePositionAndOrientation(body, position, IDENTITY)
        client.resetBaseVelocity(body, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        self._held = object_id

    def _release(self, object_id: str) -> None:
        self.client.setCollisionFilterGroupMask(
            self._layout.objects[object_id], -1, physics.GROUP_ITEM, physics.MASK_ITEM
        )
        self._held = None

    def _item_bodies(self) -> dict[str, int]:
        bodies = self._layout
        return {**bodies.objects, **bodies.clutter}

    def _fresh_contacts(self) -> None:
        """Pose every item from the record, at rest, with no cached contacts (see the module docstring).

        PyBullet keeps contact manifolds (and their warm-start impulses) across a teleport;
        parking the bodies far apart for one collision pass drops them, so the next steps
        start exactly as in a newly built world.
        """
        client = self.client
        items = self._item_bodies()
        self._robot_body.release_pusher()
        robot = self._robot_body.body
        parked = [robot, *(items[name] for name in self._poses)]
        for k, body in enumerate(parked):
            spot = (PARKING_DISTANCE + PARKING_SPACING * k, PARKING_DISTANCE, PARKING_DISTANCE)
            client.resetBasePositionAndOrientation(body, spot, IDENTITY)
        client.performCollisionDetection()
        self._robot_body.set_base(*self._robot_body.pose)
        zero = (0.0, 0.0, 0.0)
        for name, (position, orientation) in self._poses.items():
            body = items[name]
            client.resetBasePositionAndOrientation(body, position, orientation)
            client.resetBaseVelocity(body, zero, zero)

    def _read_poses(self) -> dict[str, Pose]:
        get_pose = self.client.getBasePositionAndOrientation
        items = self._item_bodies()
        self._poses = {name: get_pose(items[name]) for name in self._poses}
        return dict(self._poses)


def stroke_profile(length: float) -> list[float]:
    """Distances (metres) of the hand along a push stroke after each simulation step.

    A trapezoidal speed profile: accelerate at :data:`physics.PUSH_ACCELERATION` up to
    :data:`physics.PUSH_SPEED`, decelerate so as to arrive at ``length`` no faster than
    :data:`physics.PUSH_MIN_SPEED`. The deceleration stays below what friction gives the
    clutter, so it stops with the hand instead of sliding on.
    """
    dt, accel = physics.TIME_STEP, physics.PUSH_ACCELERATION
    positions: list[float] = []
    s, v = 0.0, 0.0
    while s < length - 1e-12:
        if v * v / (2 * accel) >= length - s:
            v = max(v - accel * dt, physics.PUSH_MIN_SPEED)
        else:
            v = min(v + accel * dt, physics.PUSH_SPEED)
        s = min(s + min(v * dt, physics.MAX_HAND_STEP), length)
        positions.append(s)
    return positions
