"""Physical parameters of the simulated world, with units; set explicitly on every body that moves."""

from __future__ import annotations

TIME_STEP = 1.0 / 240.0  # seconds simulated per stepSimulation call
GRAVITY = 9.81  # m/s^2
SOLVER_ITERATIONS = 50  # constraint-solver iterations per step (PyBullet's default, stated)

FRICTION = 0.5  # lateral (Coulomb) friction of table tops, clutter, objects and the hand
# (PyBullet multiplies the coefficients of the two bodies in contact: clutter on a table slides at 0.25.)
SPINNING_FRICTION = 0.001  # N*m per N: resists cylinders spinning on their base
ROLLING_FRICTION = 0.0001  # N*m per N: resists cylinders rolling once toppled
RESTITUTION = 0.0  # nothing bounces
LINEAR_DAMPING = 0.1  # 1/s: velocity decay of objects and clutter (PyBullet's default is 0.04)
ANGULAR_DAMPING = 0.1  # 1/s
# The dynamics above as changeDynamics keywords: what an object or a piece of clutter is set to.
ITEM_DYNAMICS = {
    "lateralFriction": FRICTION,
    "spinningFriction": SPINNING_FRICTION,
    "rollingFriction": ROLLING_FRICTION,
    "restitution": RESTITUTION,
    "linearDamping": LINEAR_DAMPING,
    "angularDamping": ANGULAR_DAMPING,
}

OBJECT_MASS = 0.3  # kg: a bottle
CLUTTER_MASS = 1.0  # kg: a box standing in the way

FLOOR_THICKNESS = 0.02  # metres: the floor slab below z = 0
OBSTACLE_HEIGHT = 1.2  # metres: walls and shelves are "full height", taller than any table
BASE_HEIGHT = 0.35  # metres: the round mobile base
ARM_CLEARANCE = 0.10  # metres between the arm and the highest top of anything standing on a table

PUSHER_MASS = 0.2  # kg: the hand's contact block during a push stroke
PUSH_FORCE = 30.0  # N: the arm's strength: slides several kilograms of clutter (1 kg needs 2.5 N), cannot crush a jam
CONSTRAINT_ERP = 0.9  # share of a constraint's error corrected per step (PyBullet's erp: the pusher's grip)
PUSH_SPEED = 0.5  # m/s: cruise speed of the hand along a push stroke
PUSH_ACCELERATION = 2.0  # m/s^2: below FRICTION**2 * GRAVITY (2.45), so the clutter stops with the hand
PUSH_MIN_SPEED = 0.02  # m/s: the hand never creeps slower than this near the end of a stroke
MAX_HAND_STEP = 0.01  # metres: the most the hand moves in one simulation step (the limit)
PUSH_SETTLE_STEPS = 24  # steps (0.1 s) the world runs after a stroke with the hand in place
PLACE_SETTLE_STEPS = 12  # steps (0.05 s) the world runs after a placed object is released
STALL_DEPTH = 0.005  # metres: a pusher this far behind the hand's path means the push is jammed: the stroke stops

# Collision groups (PyBullet's AND filter mode: two shapes touch when each one's group is in the other's mask).
GROUP_STATIC = 1  # floor, tables, obstacles
GROUP_ITEM = 2  # objects and clutter
GROUP_ROBOT = 4  # the robot's multibody: visual only for the physics (the base is kept off tables geometrically)
GROUP_HAND = 8  # the pusher: touches objects and clutter (it is parked far away between strokes)
MASK_ITEM = GROUP_STATIC | GROUP_ITEM | GROUP_HAND
MASK_NONE = 0
