"""The world state and its fixed-size observation.

The observation holds the whole geometry (area, robot, postures, objects and their
goals, clutter, tables, obstacles) in fixed-size arrays with presence flags, so that
a planner can rebuild the scenario from an observation alone: :func:`decode` is the
exact inverse of :func:`encode` up to ids, which come back as canonical names
(``object_0``, ``clutter_0``, ...) in the same order.

It follows the goal-env convention (Gymnasium-Robotics): a ``Dict`` with
``observation``, ``achieved_goal`` (every object's centre ``(x, y, z)``) and
``desired_goal`` (every goal's centre ``(x, y, z)``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace

import numpy as np
from gymnasium import spaces

from fetchcarry_env.errors import InputError
from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect
from fetchcarry_env.scenario import MAX_COUNTS, Clutter, DeliveryObject, Obstacle, Posture, Robot, Scenario, Table

Point3 = tuple[float, float, float]

LIFT_HEIGHT = 0.05  # metres a picked object is lifted above where it stood
DELIVERY_TOLERANCE = 0.01  # metres: an object within this of its goal (x, y and z) is delivered
COORD_LIMIT = 100.0  # metres: every coordinate of a valid scenario lies within this of the origin (rule 6)
OBSERVATION_LIMIT = 2 * COORD_LIMIT  # metres: bound of every entry of the observation space (see observation_space)


@dataclass(frozen=True)
class WorldState:
    """Where the movable things are: the base, what the hand holds, objects and clutter.

    ``objects`` maps each object id to its centre ``(x, y, z)`` in metres (z of the
    cylinder's centre); ``clutter`` maps each clutter id to its centre ``(x, y)``.
    """

    base: Point
    heading: Heading
    holding: str | None
    objects: dict[str, Point3] = field(default_factory=dict)
    clutter: dict[str, Point] = field(default_factory=dict)

    @classmethod
    def initial(cls, scenario: Scenario) -> WorldState:
        """The state a scenario starts in (objects standing at their starts)."""
        return cls(
            base=scenario.robot.start,
            heading=scenario.robot.heading,
            holding=None,
            objects={o.id: standing_center(scenario, o, o.start) for o in scenario.objects},
            clutter={c.id: c.rect.center for c in scenario.clutter},
        )

    def delivered(self, scenario: Scenario) -> list[str]:
        """Ids of the objects standing at their goals (not held), within 1 cm."""
        return [
            o.id
            for o in scenario.objects
            if o.id != self.holding
            and np.linalg.norm(np.subtract(self.objects[o.id], standing_center(scenario, o, o.goal)))
            <= DELIVERY_TOLERANCE
        ]


def standing_center(scenario: Scenario, obj: DeliveryObject, xy: Point) -> Point3:
    """Centre ``(x, y, z)`` of ``obj`` standing upright at ``xy`` on the table there."""
    table = scenario.table_under(xy, obj.radius)
    top = table.height if table is not None else 0.0
    return (xy[0], xy[1], top + obj.height / 2)


CAPACITY_LIMITS = {**MAX_COUNTS, "postures": 64}  # slots of a capacity at most: what a scenario may hold


class CapacityError(InputError):
    """A capacity that is not whole numbers of slots, or beyond what a scenario may hold."""


@dataclass(frozen=True)
class Capacity:
    """How many of each thing an observation has room for (absent slots are zero)."""

    objects: int = 4
    clutter: int = 8
    tables: int = 6
    obstacles: int = 12
    postures: int = 4

    def __post_init__(self) -> None:
        bad = {k: v for k, v in asdict(self).items() if not (isinstance(v, int) and not isinstance(v, bool) and v >= 0)}
        if bad or self.postures < 1:
            raise CapacityError(f"a capacity counts slots: whole numbers >= 0 (postures >= 1), got {asdict(self)}")

    @staticmethod
    def counts(scenario: Scenario) -> dict[str, int]:
        """How many of each thing ``scenario`` holds, by capacity field."""
        return {
            "objects": len(scenario.objects),
            "clutter": len(scenario.clutter),
            "tables": len(scenario.tables),
            "obstacles": len(scenario.obstacles),
            "postures": len(scenario.robot.postures),
        }

    def fits(self, scenario: Scenario) -> bool:
        """True when ``scenario`` has no more of anything than this capacity has room for."""
        return all(n <= getattr(self, k) for k, n in self.counts(scenario).items())

    def holding(self, scenario: Scenario) -> Capacity:
        """This capacity, grown where ``scenario`` needs more room."""
        return Capacity(**{k: max(getattr(self, k), n) for k, n in self.counts(scenario).items()})

    def covers(self, other: Capacity) -> bool:
        """True when every count of this capacity is at least ``other``'s."""
        return all(getattr(self, k) >= v for k, v in asdict(other).items())

    def check(self, scenario: Scenario) -> None:
        """Raise ``ValueError`` naming what does not fit."""
        counts = self.counts(scenario)
        too_many = [f"{n} {k} (room for {getattr(self, k)})" for k, n in counts.items() if n > getattr(self, k)]
        if too_many:
            raise ValueError(
                f"scenario {scenario.name!r} does not fit the observation: "
                + ", ".join(too_many)
                + " (make the env with a larger capacity=..., or --capacity on the command line)"
            )

    @classmethod
    def parse(cls, text: str, base: Capacity | None = None) -> Capacity:
        """A capacity from ``"objects=8,clutter=12"`` (the other counts from ``base``, by default :class:`Capacity`)."""
        values = asdict(base if base is not None else cls())
        given: set[str] = set()
        for part in (p.strip() for p in text.split(",")):
            key, sep, value = part.partition("=")
            key, digits = key.strip(), value.strip()
            if not sep or key not in values or not (digits.isascii() and digits.isdigit() and len(digits) <= 6):
                raise CapacityError(
                    f"capacity {text[:80]!r}: give comma-separated KEY=N with KEY one of {', '.join(values)}, "
                    "e.g. objects=8,clutter=12"
                )
            if key in given:
                raise CapacityError(f"capacity {text[:80]!r}: {key} is given twice")
            given.add(key)
            values[key] = int(digits)
        if any(v > CAPACITY_LIMITS[k] for k, v in values.items()):
            raise CapacityError(f"capacity {text[:80]!r}: at most {CAPACITY_LIMITS} (what a scenario may hold)")
        return cls(**values)


# Per-slot feature widths of the flat observation vector.
_AREA, _ROBOT, _POSTURE, _OBJECT, _CLUTTER, _TABLE, _OBSTACLE = 4, 7, 5, 11, 6, 6, 5


def observation_size(capacity: Capacity) -> int:
    return (
        _AREA
        + _ROBOT
        + _POSTURE * capacity.postures
        + _OBJECT * capacity.objects
        + _CLUTTER * capacity.clutter
        + _TABLE * capacity.tables
        + _OBSTACLE * capacity.obstacles
    )


FIELDS: dict[str, tuple[str, ...]] = {
    "area": ("min_x", "min_y", "max_x", "max_y"),
    "robot": ("x", "y", "radius", "heading_+x", "heading_+y", "heading_-x", "heading_-y"),
    "posture": ("present", "forward_low", "forward_high", "lateral_low", "lateral_high"),
    "object": ("present", "x", "y", "z", "goal_x", "goal_y", "goal_z", "radius", "height", "held", "delivered"),
    "clutter": ("present", "min_x", "min_y", "max_x", "max_y", "height"),
    "table": ("present", "min_x", "min_y", "max_x", "max_y", "height"),
    "obstacle": ("present", "min_x", "min_y", "max_x", "max_y"),
}
"""The features of each part of the ``observation`` vector, in order (metres; flags are 0 or 1)."""

SLOT_GROUPS: dict[str, str] = {
    "postures": "posture",
    "objects": "object",
    "clutter": "clutter",
    "tables": "table",
    "obstacles": "obstacle",
}
"""Capacity field -> the name of one of its slots."""


def observation_layout(capacity: Capacity) -> dict[str, slice]:
    """Named slices of the flat ``observation`` vector for ``capacity``.

    ``"area"`` and ``"robot"``; one slice per slot (``"posture_0"`` ...,
    ``"object_0"`` ..., ``"clutter_0"`` ..., ``"table_0"`` ..., ``"obstacle_0"`` ...),
    each holding :data:`FIELDS` of its kind in order; and one slice per group of slots
    (``"postures"``, ``"objects"``, ``"clutter"``, ``"tables"``, ``"obstacles"``), whose
    ``reshape(count, width)`` gives one row per slot. The slices cover the vector in
    order, without gaps (:func:`observation_size`).
    """
    layout: dict[str, slice] = {}
    cursor = 0

    def take(name: str, width: int) -> None:
        nonlocal cursor
        layout[name] = slice(cursor, cursor + width)
        cursor += width

    take("area", _AREA)
    take("robot", _ROBOT)
    for group, slot in SLOT_GROUPS.items():
        start = cursor
        for k in range(getattr(capacity, group)):
            take(f"{slot}_{k}", len(FIELDS[slot]))
        layout[group] = slice(start, cursor)
    return layout


def observation_space(capacity: Capacity) -> spaces.Dict:
    """The ``Dict`` observation space for a capacity: every entry within :data:`OBSERVATION_LIMIT` (200 m).

    The bound holds every observation of a valid scenario (rule 6: coordinates and sizes
    within ``COORD_LIMIT``, 100 m). A standing object's centre is at most 100 m up; a held
    one rides at the hand, :data:`LIFT_HEIGHT` above its table (100.05 m up at most) and
    as far from the base as a posture reaches (at most 100 m), so its ``x`` and ``y`` may
    lie up to 200 m from the origin.
    """

    def box(n: int) -> spaces.Box:
        return spaces.Box(-OBSERVATION_LIMIT, OBSERVATION_LIMIT, shape=(n,), dtype=np.float32)

    return spaces.Dict(
        {
            "observation": box(observation_size(capacity)),
            "achieved_goal": box(3 * capacity.objects),
            "desired_goal": box(3 * capacity.objects),
        }
    )


def encode(scenario: Scenario, state: WorldState, capacity: Capacity) -> dict[str, np.ndarray]:
    """The observation of ``state`` in ``scenario`` (float32 arrays)."""
    delivered = set(state.delivered(scenario))
    parts: list[list[float]] = [[scenario.area.min_x, scenario.area.min_y, scenario.area.max_x, scenario.area.max_y]]
    onehot = [0.0] * len(HEADINGS)
    onehot[HEADINGS.index(state.heading)] = 1.0
    parts.append([state.base[0], state.base[1], scenario.robot.radius, *onehot])
    parts += _slots(([1.0, *p.forward, *p.lateral] for p in scenario.robot.postures), capacity.postures, _POSTURE)
    achieved = np.zeros((capacity.objects, 3), dtype=np.float32)
    desired = np.zeros((capacity.objects, 3), dtype=np.float32)
    object_rows = []
    for k, obj in enumerate(scenario.objects):
        position = state.objects[obj.id]
        goal = standing_center(scenario, obj, obj.goal)
        achieved[k], desired[k] = position, goal
        held, done = float(obj.id == state.holding), float(obj.id in delivered)
        object_rows.append([1.0, *position, *goal, obj.radius, obj.height, held, done])
    parts += _slots(object_rows, capacity.objects, _OBJECT)
    clutter_rows = []
    for item in scenario.clutter:
        half_x, half_y = (s / 2 for s in item.rect.size)
        r = Rect.around(state.clutter[item.id], half_x, half_y)
        clutter_rows.append([1.0, r.min_x, r.min_y, r.max_x, r.max_y, item.height])
    parts += _slots(clutter_rows, capacity.clutter, _CLUTTER)
    parts += _slots(
        ([1.0, t.rect.min_x, t.rect.min_y, t.rect.max_x, t.rect.max_y, t.height] for t in scenario.tables),
        capacity.tables,
        _TABLE,
    )
    parts += _slots(
        ([1.0, o.rect.min_x, o.rect.min_y, o.rect.max_x, o.rect.max_y] for o in scenario.obstacles),
        capacity.obstacles,
        _OBSTACLE,
    )
    flat = np.fromiter((v for part in parts for v in part), dtype=np.float32)
    return {"observation": flat, "achieved_goal": achieved.reshape(-1), "desired_goal": desired.reshape(-1)}


def _slots(rows, capacity: int, width: int) -> list[list[float]]:
    rows = list(rows)
    return rows + [[0.0] * width] * (capacity - len(rows))


def decode(observation: dict[str, np.ndarray] | np.ndarray, capacity: Capacity) -> tuple[Scenario, WorldState]:
    """Rebuild the scenario and the state from an observation (the inverse of :func:`encode`).

    The scenario's ``robot.start`` is the current base, each object's ``start`` is where
    it stands now (a held object's is its goal, which the planner ignores), and clutter
    stands where it is now. The result is not validated: it is a state, not a file.
    """
    flat = np.asarray(observation["observation"] if isinstance(observation, dict) else observation, dtype=np.float64)
    reader = _Reader(flat.tolist())  # plain Python floats from here on
    take, rows = reader.take, reader.rows
    area = Rect(*take(_AREA))
    robot_row = take(_ROBOT)
    base, radius, heading = (robot_row[0], robot_row[1]), robot_row[2], HEADINGS[int(np.argmax(robot_row[3:]))]
    postures = tuple(
        Posture(f"posture_{k}", (r[1], r[2]), (r[3], r[4])) for k, r in enumerate(rows(capacity.postures, _POSTURE))
    )
    objects, positions, holding = _decode_objects(rows(capacity.objects, _OBJECT))
    clutter_rows = rows(capacity.clutter, _CLUTTER)
    tables = tuple(Table(f"table_{k}", Rect(*r[1:5]), r[5]) for k, r in enumerate(rows(capacity.tables, _TABLE)))
    obstacles = tuple(
        Obstacle(f"obstacle_{k}", Rect(*r[1:5])) for k, r in enumerate(rows(capacity.obstacles, _OBSTACLE))
    )
    clutter = tuple(Clutter(f"clutter_{k}", Rect(*r[1:5]), r[5]) for k, r in enumerate(clutter_rows))
    scenario = Scenario(
        name="observed",
        area=area,
        robot=Robot(start=base, heading=heading, radius=radius, postures=postures),
        tables=tables,
        obstacles=obstacles,
        objects=objects,
        clutter=clutter,
    )
    state = WorldState(
        base=base,
        heading=heading,
        holding=holding,
        objects=positions,
        clutter={c.id: c.rect.center for c in clutter},
    )
    return scenario, state


class _Reader:
    """An observation vector read front to back, part by part."""

    def __init__(self, flat: list[float]) -> None:
        self.flat = flat
        self.cursor = 0

    def take(self, n: int) -> list[float]:
        chunk = self.flat[self.cursor : self.cursor + n]
        self.cursor += n
        return chunk

    def rows(self, count: int, width: int) -> list[list[float]]:
        """The present rows (first feature above 0.5) of ``count`` slots of ``width`` features."""
        chunk = self.take(count * width)
        return [row for row in (chunk[k * width : (k + 1) * width] for k in range(count)) if row[0] > 0.5]


def _decode_objects(object_rows: list[list[float]]) -> tuple[tuple[DeliveryObject, ...], dict[str, Point3], str | None]:
    """The objects of the rows (a held object starts at its goal), where each is now, and the one held."""
    objects, positions, holding = [], {}, None
    for k, r in enumerate(object_rows):
        object_id = f"object_{k}"
        position, goal = (r[1], r[2], r[3]), (r[4], r[5])
        held = r[9] > 0.5
        if held:
            holding = object_id
        start = goal if held else (r[1], r[2])
        objects.append(DeliveryObject(object_id, start, goal, r[7], r[8]))
        positions[object_id] = position
    return tuple(objects), positions, holding


def with_state(scenario: Scenario, state: WorldState) -> Scenario:
    """``scenario`` re-posed at ``state``: the robot starts at the base, objects and clutter where they are."""
    objects = tuple(
        replace(o, start=o.goal if o.id == state.holding else state.objects[o.id][:2]) for o in scenario.objects
    )
    clutter = tuple(
        replace(c, rect=Rect.around(state.clutter[c.id], c.rect.size[0] / 2, c.rect.size[1] / 2))
        for c in scenario.clutter
    )
    robot = replace(scenario.robot, start=state.base, heading=state.heading)
    return replace(scenario, robot=robot, objects=objects, clutter=clutter)
