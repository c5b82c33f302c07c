"""The HSR-like mobile manipulator, authored here with ``createMultiBody``.

A round base of the scenario's radius carries a lift (prismatic, z), a horizontal arm
that sits above everything standing on the tables and slides forward (prismatic, the
robot's x) and sideways (prismatic, the robot's y), and a wrist that drops the hand
(prismatic, z). The hand is a cube of half-size :data:`~fetchcarry_env.kinematics.HAND_HALF_SIZE`.

Every link has mass 0 and touches nothing: the robot is kinematic, posed by resetting
its base pose and its joint positions, and asleep for the physics engine from its
creation (nothing ever wakes it). The base is kept off tables and obstacles by the
exact swept-disc test of :func:`fetchcarry_env.geometry.first_contact` before it moves.

What the hand touches during a push stroke is the *pusher*, a separate dynamic block the
size of the hand, held at the hand's place by a force-limited constraint: the arm's
strength (:data:`~fetchcarry_env.sim.physics.PUSH_FORCE`). PyBullet's contact solver
then decides what moves: the pushed clutter slides, shoves a neighbour, or jams, and
a jammed pusher falls behind the hand's path (:meth:`RobotBody.pusher_position`).
Between strokes the pusher is parked far away. It never sleeps: a body's sleeping state
is history that a rebuilt world would not have (copies must continue exactly).
"""

from __future__ import annotations

from dataclasses import dataclass

import fetchcarry_env.sim.physics as physics
from fetchcarry_env.geometry import HEADINGS, Heading, Point, heading_yaw
from fetchcarry_env.kinematics import HAND_HALF_SIZE
from fetchcarry_env.sim.client import QuietClient, pybullet

BASE_COLOR = (0.92, 0.92, 0.92, 1.0)
LINK_COLOR = (0.18, 0.18, 0.20, 1.0)
HAND_COLOR = (1.0, 0.55, 0.0, 1.0)
MAST_HALF_SIZE = 0.04  # metres: the lift column's cross-section half-size
ARM_HALF_WIDTH = 0.025  # metres: the arm's cross-section half-size
ARM_VISUAL_LENGTH = 0.5  # metres: the arm drawn behind the wrist (it slides out of the lift)
WRIST_RADIUS = 0.012  # metres

LIFT, FORWARD, LATERAL, WRIST = 0, 1, 2, 3  # joint (and link) indices; the hand is the wrist link
PUSHER_PARKING = (-1000.0, -1000.0, -1000.0)  # metres: where the pusher waits between strokes, far from all
IDENTITY = (0.0, 0.0, 0.0, 1.0)  # quaternion (x, y, z, w)
ZERO = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class HandPose:
    """Where the hand is relative to the base: robot-frame ``forward``/``lateral`` and world height ``z`` (metres)."""

    forward: float
    lateral: float
    z: float


class RobotBody:
    """The robot's multibody in one PyBullet world, posed kinematically."""

    def __init__(self, client: QuietClient, radius: float, arm_height: float, lowest_hand: float) -> None:
        """Build the robot for a base ``radius``, with the arm at ``arm_height`` and a wrist that reaches
        down to ``lowest_hand`` (world heights, metres)."""
        self._client = client
        self.radius = radius
        self.arm_height = arm_height
        wrist_length = max(arm_height - lowest_hand, 2 * HAND_HALF_SIZE)
        self.body, hand_collision = _build_robot(client, radius, arm_height, wrist_length)
        client.setCollisionFilterGroupMask(self.body, -1, physics.GROUP_ROBOT, physics.MASK_NONE)
        # Asleep from the start, the robot costs the physics engine nothing (a third of a step); it is
        # only ever teleported and touches nothing, so it never wakes, in this world or a rebuilt one.
        client.changeDynamics(self.body, -1, activationState=pybullet.ACTIVATION_STATE_ENABLE_SLEEPING)
        client.changeDynamics(self.body, -1, activationState=pybullet.ACTIVATION_STATE_SLEEP)
        self.pusher = client.createMultiBody(physics.PUSHER_MASS, hand_collision, -1, PUSHER_PARKING)
        self._grip: int | None = None  # the constraint that holds the pusher during a stroke
        client.setCollisionFilterGroupMask(self.pusher, -1, physics.GROUP_HAND, physics.GROUP_ITEM)
        client.changeDynamics(
            self.pusher,
            -1,
            lateralFriction=physics.FRICTION,
            restitution=physics.RESTITUTION,
            activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING,
        )
        self.release_pusher()
        client.resetJointState(self.body, LIFT, arm_height - physics.BASE_HEIGHT)
        self.pose: tuple[Point, Heading] = ((0.0, 0.0), "+x")
        self._yaw_quaternion = {h: client.getQuaternionFromEuler([0.0, 0.0, heading_yaw(h)]) for h in HEADINGS}
        self.set_hand(self.rest_hand)

    @property
    def rest_hand(self) -> HandPose:
        """Where the empty hand waits between phases: over the front edge of the base, at the arm's height."""
        return HandPose(self.radius, 0.0, self.arm_height)

    def set_base(self, base: Point, heading: Heading) -> None:
        """Put the base centre at ``base`` facing ``heading`` (the arm follows)."""
        self._client.resetBasePositionAndOrientation(
            self.body, (base[0], base[1], physics.BASE_HEIGHT / 2), self._yaw_quaternion[heading]
        )
        self.pose = (base, heading)

    def set_hand(self, hand: HandPose) -> None:
        """Put the hand at a robot-frame offset and world height (the arm stays at its height)."""
        self._client.resetJointState(self.body, FORWARD, hand.forward)
        self._client.resetJointState(self.body, LATERAL, hand.lateral)
        self._client.resetJointState(self.body, WRIST, hand.z - self.arm_height)
        self.hand = hand

    def grip_pusher(self, position: tuple[float, float, float]) -> None:
        """Start a stroke: the pusher, at rest at ``position`` (world, metres), held there with the arm's force.

        The arm's grip is a fixed constraint, at most :data:`physics.PUSH_FORCE` strong, between
        the pusher and a point of the world that :meth:`drive_pusher` moves along the hand's
        path. It is made afresh for every stroke (a constraint keeps its impulses to
        warm-start the next step: a stroke must not depend on the previous one).
        """
        client = self._client
        self._pose_pusher(position)
        self._grip = client.createConstraint(self.pusher, -1, -1, -1, pybullet.JOINT_FIXED, ZERO, ZERO, position)
        client.changeConstraint(self._grip, maxForce=physics.PUSH_FORCE)

    def drive_pusher(self, position: tuple[float, float, float]) -> None:
        """Move the point the arm holds the pusher at (world, metres); PyBullet pulls the pusher there."""
        self._client.changeConstraint(self._grip, position)

    def pusher_position(self) -> tuple[float, float, float]:
        """Where the pusher's centre is (world, metres), as PyBullet has it."""
        return self._client.getBasePositionAndOrientation(self.pusher)[0]

    def release_pusher(self) -> None:
        """End a stroke (or make sure none is under way): the grip goes, the pusher is parked far from everything.

        A parked pusher falls freely and touches nothing; every primitive parks it again first.
        """
        client = self._client
        if self._grip is not None:
            client.removeConstraint(self._grip)
            self._grip = None
        self._pose_pusher(PUSHER_PARKING)

    def _pose_pusher(self, position: tuple[float, float, float]) -> None:
        self._client.resetBasePositionAndOrientation(self.pusher, position, IDENTITY)
        self._client.resetBaseVelocity(self.pusher, ZERO, ZERO)

    def hand_position(self) -> tuple[float, float, float]:
        """World position (metres) of the hand's centre, as PyBullet has it."""
        return tuple(self._client.getLinkState(self.body, WRIST, computeForwardKinematics=True)[4])

    def base_position(self) -> Point:
        """World ``(x, y)`` (metres) of the base centre, as PyBullet has it."""
        position, _ = self._client.getBasePositionAndOrientation(self.body)
        return (position[0], position[1])


def _build_robot(client: QuietClient, radius: float, arm_height: float, wrist_length: float) -> tuple[int, int]:
    """The robot's multibody (base, lift, forward and lateral links, wrist) and the hand's collision shape."""
    half_base = physics.BASE_HEIGHT / 2
    mast_length = arm_height - physics.BASE_HEIGHT
    base_collision = client.createCollisionShape(pybullet.GEOM_CYLINDER, radius=radius, height=physics.BASE_HEIGHT)
    base_visual = client.createVisualShape(
        pybullet.GEOM_CYLINDER, radius=radius, length=physics.BASE_HEIGHT, rgbaColor=BASE_COLOR
    )
    mast_visual, arm_visual, hand_collision, hand_visual = _link_shapes(client, mast_length, wrist_length)
    body = client.createMultiBody(
        baseMass=0.0,
        baseCollisionShapeIndex=base_collision,
        baseVisualShapeIndex=base_visual,
        basePosition=[0.0, 0.0, half_base],
        linkMasses=[0.0] * 4,
        linkCollisionShapeIndices=[-1, -1, -1, -1],
        linkVisualShapeIndices=[mast_visual, arm_visual, -1, hand_visual],
        linkPositions=[[0, 0, half_base], [0, 0, 0], [0, 0, 0], [0, 0, 0]],
        linkOrientations=[[0, 0, 0, 1]] * 4,
        linkInertialFramePositions=[[0, 0, 0]] * 4,
        linkInertialFrameOrientations=[[0, 0, 0, 1]] * 4,
        linkParentIndices=[0, 1, 2, 3],
        linkJointTypes=[pybullet.JOINT_PRISMATIC] * 4,
        linkJointAxis=[[0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
    )
    return body, hand_collision


def _link_shapes(client: QuietClient, mast_length: float, wrist_length: float) -> tuple[int, int, int, int]:
    """The visual shapes of the mast, the arm and the hand with its wrist rod, and the hand's collision box."""
    # The lift link's frame is at the arm's height; its column is drawn down to the base.
    mast_visual = client.createVisualShape(
        pybullet.GEOM_BOX,
        halfExtents=[MAST_HALF_SIZE, MAST_HALF_SIZE, mast_length / 2],
        visualFramePosition=[0, 0, -mast_length / 2],
        rgbaColor=LINK_COLOR,
    )
    # The forward link's frame is at the wrist; the arm is drawn behind it.
    arm_visual = client.createVisualShape(
        pybullet.GEOM_BOX,
        halfExtents=[ARM_VISUAL_LENGTH / 2, ARM_HALF_WIDTH, ARM_HALF_WIDTH],
        visualFramePosition=[-ARM_VISUAL_LENGTH / 2, 0, 0],
        rgbaColor=LINK_COLOR,
    )
    # The wrist link's frame is the hand's centre; the wrist rod is drawn above it.
    hand_collision = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[HAND_HALF_SIZE] * 3)
    hand_visual = client.createVisualShapeArray(
        shapeTypes=[pybullet.GEOM_BOX, pybullet.GEOM_CYLINDER],
        halfExtents=[[HAND_HALF_SIZE] * 3, [0, 0, 0]],
        radii=[0, WRIST_RADIUS],
        lengths=[0, wrist_length],
        rgbaColors=[HAND_COLOR, LINK_COLOR],
        visualFramePositions=[[0, 0, 0], [0, 0, HAND_HALF_SIZE + wrist_length / 2]],
    )
    return mast_visual, arm_visual, hand_collision, hand_visual
