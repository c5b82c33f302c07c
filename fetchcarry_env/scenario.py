"""The scenario model: the whole planning problem, in the ``fetchcarry-scenario/1`` format.

A :class:`Scenario` is what the environment simulates, what the MILP expert plans on
and what the benchmark reports about. It is a tree of frozen dataclasses that reads
and writes exactly the JSON of ``docs/scenario-format.md``; :meth:`Scenario.from_dict`
checks every rule of that spec and reports all violations at once in a
:class:`ScenarioError` that names the rule and the ids.

Units are metres throughout.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fetchcarry_env.errors import InputError
from fetchcarry_env.geometry import HEADINGS, Heading, Point, Rect, discs_overlap, rect_under
from fetchcarry_env.jsontext import describe, read_json_or

FORMAT = "fetchcarry-scenario/1"

COORD_LIMIT = 100.0  # metres: every coordinate lies within this of the origin (the observation's bound)
MIN_SIZE = 1e-3  # metres: the smallest radius, height and rectangle width
MAX_COUNTS = {"objects": 64, "clutter": 256, "tables": 64, "obstacles": 1024}  # items a scenario may hold
MAX_FILE_BYTES = 64 * 2**20  # bytes: a file is refused unread beyond this (the largest valid one is under 1 MB)
MAX_ID_LENGTH = 200  # characters of a name or an id
MAX_SHOWN = 50  # violations spelled out in the message of a ScenarioError (all are in .violations)


class ScenarioError(InputError):
    """A scenario breaks one or more rules of ``docs/scenario-format.md``.

    ``violations`` lists one message per broken rule and id; ``str(error)`` shows them all.
    """

    def __init__(self, violations: list[str], source: str | None = None) -> None:
        self.violations = list(violations)
        where = f"{source}: " if source else ""
        lines = "\n".join(f"  - {v}" for v in self.violations[:MAX_SHOWN])
        if len(self.violations) > MAX_SHOWN:
            lines += f"\n  ... and {len(self.violations) - MAX_SHOWN} more"
        super().__init__(f"{where}invalid scenario ({len(self.violations)} problem(s)):\n{lines}")


@dataclass(frozen=True)
class Posture:
    """An arm posture: where, relative to the base, the hand can be put over a table.

    ``forward`` and ``lateral`` are ``(low, high)`` ranges in metres in the robot frame
    (forward = heading, lateral = 90 degrees to its left). A range of zero width is the
    paper's fixed posture.
    """

    name: str
    forward: tuple[float, float]
    lateral: tuple[float, float]

    def reaches(self, forward: float, lateral: float, tol: float = 1e-3) -> bool:
        """True when a robot-frame offset (metres) lies within this posture's ranges."""
        return (
            self.forward[0] - tol <= forward <= self.forward[1] + tol
            and self.lateral[0] - tol <= lateral <= self.lateral[1] + tol
        )

    @property
    def center(self) -> tuple[float, float]:
        """The middle of the ranges, ``(forward, lateral)`` in metres."""
        return ((self.forward[0] + self.forward[1]) / 2, (self.lateral[0] + self.lateral[1]) / 2)


DEFAULT_POSTURES: tuple[Posture, ...] = (
    Posture("reach_far", (0.55, 0.70), (-0.05, 0.05)),
    Posture("reach_near", (0.35, 0.50), (-0.05, 0.05)),
)
DEFAULT_RADIUS = 0.22  # metres: a Toyota HSR base is about 0.43 m across
DEFAULT_TABLE_HEIGHT = 0.70  # metres
DEFAULT_CLUTTER_HEIGHT = 0.10  # metres


@dataclass(frozen=True)
class Robot:
    """The mobile manipulator: a round base and its arm postures."""

    start: Point
    heading: Heading = "+x"
    radius: float = DEFAULT_RADIUS  # metres
    postures: tuple[Posture, ...] = DEFAULT_POSTURES

    def posture(self, name: str) -> Posture:
        for posture in self.postures:
            if posture.name == name:
                return posture
        raise KeyError(f"no posture named {name!r}")


@dataclass(frozen=True)
class Table:
    """A surface objects and clutter stand on; impassable for the base, the arm reaches over it."""

    id: str
    rect: Rect
    height: float = DEFAULT_TABLE_HEIGHT  # metres, top surface above the floor


@dataclass(frozen=True)
class Obstacle:
    """A floor-standing, full-height obstacle (wall, shelf, the non-corridor part of a room)."""

    id: str
    rect: Rect


@dataclass(frozen=True)
class DeliveryObject:
    """An upright cylinder that must be carried from ``start`` to ``goal``."""

    id: str
    start: Point
    goal: Point
    radius: float = 0.035  # metres
    height: float = 0.20  # metres


@dataclass(frozen=True)
class Clutter:
    """A box standing on a table that is not delivered; it may be pushed aside."""

    id: str
    rect: Rect
    height: float = DEFAULT_CLUTTER_HEIGHT  # metres


@dataclass(frozen=True)
class Scenario:
    """A fetch-and-carry problem (``fetchcarry-scenario/1``).

    Build one with :meth:`load`, :meth:`from_dict` (both validate) or the constructor
    (which trusts its input, as the planner does for states rebuilt from observations).
    """

    name: str
    area: Rect
    robot: Robot
    objects: tuple[DeliveryObject, ...]
    tables: tuple[Table, ...] = ()
    obstacles: tuple[Obstacle, ...] = ()
    clutter: tuple[Clutter, ...] = ()
    format: str = field(default=FORMAT, repr=False)

    # ------------------------------------------------------------------ queries
    def table_under(self, center: Point, radius: float = 0.0) -> Table | None:
        """The table whose top holds the whole disc ``(center, radius)``, or None."""
        index = rect_under(center, radius, (t.rect for t in self.tables))
        return None if index is None else self.tables[index]

    def table_under_rect(self, rect: Rect) -> Table | None:
        """The table whose top holds the whole rectangle, or None."""
        for table in self.tables:
            if table.rect.contains_rect(rect, tol=1e-6):
                return table
        return None

    def object(self, object_id: str) -> DeliveryObject:
        return _by_id(self.objects, object_id)

    def clutter_item(self, clutter_id: str) -> Clutter:
        return _by_id(self.clutter, clutter_id)

    @property
    def layout_key(self) -> tuple:
        """What the simulator must rebuild bodies for: everything but the movable poses."""
        return (
            self.area,
            self.robot.radius,
            self.robot.postures,
            self.tables,
            self.obstacles,
            tuple((o.id, o.radius, o.height) for o in self.objects),
            tuple((c.id, c.rect.size, c.height) for c in self.clutter),
        )

    # ------------------------------------------------------------------ I/O
    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | None = None) -> Scenario:
        """Parse and validate a ``fetchcarry-scenario/1`` mapping; raise :class:`ScenarioError`.

        Too many items (``MAX_COUNTS``) are refused with their count before anything else is looked at.
        """
        too_many = _rule_counts(data)
        if too_many:
            raise ScenarioError(too_many, source)
        parser = _Parser()
        scenario = parser.parse(data)
        if scenario is not None:
            parser.violations.extend(check_rules(scenario))
        if parser.violations:
            raise ScenarioError(parser.violations, source)
        assert scenario is not None
        return scenario

    @classmethod
    def load(cls, path: str | Path) -> Scenario:
        """Read and validate a scenario file; raise :class:`ScenarioError` for anything but a valid scenario.

        A file larger than ``MAX_FILE_BYTES``, not UTF-8 text, or not JSON is a
        :class:`ScenarioError` too; ``OSError`` (a missing or unreadable file) passes through.
        """
        path = Path(path)
        data = read_json_or(path, MAX_FILE_BYTES, lambda error: ScenarioError([f"format: {error}"], str(path)))
        return cls.from_dict(data, source=str(path))

    def to_dict(self) -> dict[str, Any]:
        """The ``fetchcarry-scenario/1`` mapping of this scenario (round-trips through :meth:`from_dict`)."""
        return {
            "format": FORMAT,
            "name": self.name,
            "area": _rect_dict(self.area),
            "robot": {
                "start": list(self.robot.start),
                "heading": self.robot.heading,
                "radius": self.robot.radius,
                "postures": [
                    {"name": p.name, "forward": list(p.forward), "lateral": list(p.lateral)}
                    for p in self.robot.postures
                ],
            },
            "tables": [{"id": t.id, **_rect_dict(t.rect), "height": t.height} for t in self.tables],
            "obstacles": [{"id": o.id, **_rect_dict(o.rect)} for o in self.obstacles],
            "objects": [
                {"id": o.id, "start": list(o.start), "goal": list(o.goal), "radius": o.radius, "height": o.height}
                for o in self.objects
            ],
            "clutter": [{"id": c.id, **_rect_dict(c.rect), "height": c.height} for c in self.clutter],
        }

    def save(self, path: str | Path) -> None:
        """Write this scenario as indented JSON."""
        Path(path).write_text(json.dumps(self.to_dict(), indent=2) + "\n")


def _by_id(items: tuple, item_id: str):
    for item in items:
        if item.id == item_id:
            return item
    raise KeyError(f"no item with id {item_id!r}")


def _rect_dict(rect: Rect) -> dict[str, list[float]]:
    return {"min": [rect.min_x, rect.min_y], "max": [rect.max_x, rect.max_y]}


# ---------------------------------------------------------------------- rules
def check_rules(scenario: Scenario) -> list[str]:
    """Every violation of the six rules of ``docs/scenario-format.md``, one message each."""
    return [
        *_rule_unique_ids(scenario),
        *_rule_rectangles(scenario),
        *_rule_robot_start(scenario),
        *_rule_on_tables(scenario),
        *_rule_no_overlap(scenario),
        *_rule_numbers(scenario),
        *_rule_counts({key: getattr(scenario, key) for key in MAX_COUNTS}),
    ]


def _all_ids(scenario: Scenario) -> Iterator[str]:
    for group in (scenario.tables, scenario.obstacles, scenario.objects, scenario.clutter):
        yield from (item.id for item in group)


def _rule_unique_ids(scenario: Scenario) -> list[str]:
    seen: set[str] = set()
    duplicates: list[str] = []
    for item_id in _all_ids(scenario):
        if item_id in seen and item_id not in duplicates:
            duplicates.append(item_id)
        seen.add(item_id)
    return [f"rule 1 (unique ids): id {i!r} is used more than once" for i in duplicates]


def _rule_rectangles(scenario: Scenario) -> list[str]:
    out = []
    if not scenario.area.is_proper:
        out.append("rule 2 (rectangles): area must have min < max on both axes")
    for group in (scenario.tables, scenario.obstacles, scenario.clutter):
        for item in group:
            if not item.rect.is_proper:
                out.append(f"rule 2 (rectangles): {item.id!r} must have min < max on both axes")
            elif not scenario.area.contains_rect(item.rect):
                out.append(f"rule 2 (rectangles): {item.id!r} does not lie inside the area")
    return out


def _rule_robot_start(scenario: Scenario) -> list[str]:
    robot = scenario.robot
    out = []
    if not scenario.area.contains_disc(robot.start, robot.radius):
        out.append("rule 3 (robot start): the base disc at robot.start does not lie inside the area")
    for item in (*scenario.tables, *scenario.obstacles):
        if item.rect.overlaps_disc(robot.start, robot.radius):
            out.append(f"rule 3 (robot start): the base disc at robot.start overlaps {item.id!r}")
    return out


def _rule_on_tables(scenario: Scenario) -> list[str]:
    out = []
    for obj in scenario.objects:
        for which, point in (("start", obj.start), ("goal", obj.goal)):
            if scenario.table_under(point, obj.radius) is None:
                out.append(f"rule 4 (on a table): object {obj.id!r} {which} {list(point)} is not fully on a table")
    for item in scenario.clutter:
        if item.rect.is_proper and scenario.table_under_rect(item.rect) is None:
            out.append(f"rule 4 (on a table): clutter {item.id!r} is not fully on one table")
    return out


def _rule_no_overlap(scenario: Scenario) -> list[str]:
    out = []
    objects, clutter = scenario.objects, scenario.clutter
    for i, a in enumerate(objects):
        for b in objects[i + 1 :]:
            if discs_overlap(a.start, a.radius, b.start, b.radius):
                out.append(f"rule 5 (no overlap): objects {a.id!r} and {b.id!r} overlap at the start")
        for c in clutter:
            if c.rect.overlaps_disc(a.start, a.radius):
                out.append(f"rule 5 (no overlap): object {a.id!r} overlaps clutter {c.id!r} at the start")
    for i, a in enumerate(clutter):
        for b in clutter[i + 1 :]:
            if a.rect.overlaps_rect(b.rect):
                out.append(f"rule 5 (no overlap): clutter {a.id!r} and {b.id!r} overlap")
    return out


def _rule_numbers(scenario: Scenario) -> list[str]:
    """Rule 6: finite numbers of sane size (coordinates, radii, heights, range and rectangle widths)."""
    check = _Numbers()
    check.rect("area", scenario.area)
    check.size("robot", "radius", scenario.robot.radius)
    for name, value in zip(("start x", "start y"), scenario.robot.start, strict=True):
        check.coordinate("robot", name, value)
    for posture in scenario.robot.postures:
        check.posture(posture)
    for table in scenario.tables:
        check.rect(repr(table.id), table.rect)
        check.size(repr(table.id), "height", table.height)
    for obstacle in scenario.obstacles:
        check.rect(repr(obstacle.id), obstacle.rect)
    for obj in scenario.objects:
        for which, point in (("start", obj.start), ("goal", obj.goal)):
            check.coordinate(repr(obj.id), f"{which} x", point[0])
            check.coordinate(repr(obj.id), f"{which} y", point[1])
        check.size(repr(obj.id), "radius", obj.radius)
        check.size(repr(obj.id), "height", obj.height, _headroom(scenario, obj.start, obj.goal))
    for item in scenario.clutter:
        check.rect(repr(item.id), item.rect)
        check.size(repr(item.id), "height", item.height, _headroom(scenario, item.rect.center))
    return check.out


class _Numbers:
    """Rule 6's checks of single numbers; the violations gather in ``out``."""

    def __init__(self) -> None:
        self.out: list[str] = []

    def finite(self, owner: str, name: str, value: float) -> bool:
        if math.isfinite(value):
            return True
        self.out.append(f"rule 6 (numbers): {owner} {name} is not a finite number")
        return False

    def coordinate(self, owner: str, name: str, value: float) -> None:
        if self.finite(owner, name, value) and abs(value) > COORD_LIMIT:
            self.out.append(
                f"rule 6 (numbers): {owner} {name} {_number(value)} is more than {COORD_LIMIT:g} m from the origin"
            )

    def size(self, owner: str, name: str, value: float, high: float = COORD_LIMIT) -> None:
        if not self.finite(owner, name, value):
            return
        if value < 0:
            self.out.append(f"rule 6 (numbers): {owner} {name} is negative")
        elif value < MIN_SIZE:
            self.out.append(f"rule 6 (numbers): {owner} {name} {_number(value)} is less than {MIN_SIZE * 1000:g} mm")
        elif value > high:
            self.out.append(f"rule 6 (numbers): {owner} {name} {_number(value)} is more than {_number(high)} m")

    def rect(self, owner: str, r: Rect) -> None:
        for name, value in zip(("min x", "min y", "max x", "max y"), (r.min_x, r.min_y, r.max_x, r.max_y), strict=True):
            self.coordinate(owner, name, value)
        width, depth = r.size
        if r.is_proper and min(width, depth) < MIN_SIZE:
            self.out.append(
                f"rule 6 (numbers): {owner} is {width:g} x {depth:g} m, less than {MIN_SIZE * 1000:g} mm wide"
            )

    def posture(self, posture: Posture) -> None:
        for axis in ("forward", "lateral"):
            low, high = getattr(posture, axis)
            self.coordinate(f"posture {posture.name!r}", f"{axis} range", low)
            self.coordinate(f"posture {posture.name!r}", f"{axis} range", high)
            if math.isfinite(low) and math.isfinite(high) and high < low:
                self.out.append(f"rule 6 (numbers): posture {posture.name!r} {axis} range has a negative width")


def _number(value: float) -> str:
    """``value`` short (``0.05``, ``120``) where that is exact, else in full: two numbers compared never print alike."""
    short = f"{value:g}"
    return short if float(short) == value else repr(float(value))


def _headroom(scenario: Scenario, *points: Point) -> float:
    """How tall (metres) a thing standing at ``points`` may be: its top stays within ``COORD_LIMIT`` of the floor."""
    tops = [
        t.height for t in scenario.tables if math.isfinite(t.height) and any(t.rect.contains_point(p) for p in points)
    ]
    return COORD_LIMIT - max([0.0, *tops])


def _rule_counts(data: Any) -> list[str]:
    """Rule 6's counts, read from the raw mapping so that a huge file is refused before it is parsed."""
    if not isinstance(data, Mapping):
        return []
    out = []
    for key, limit in MAX_COUNTS.items():
        items = data.get(key)
        if isinstance(items, list | tuple) and len(items) > limit:
            out.append(f"rule 6 (numbers): {len(items):,} {key}, more than the {limit:,} a scenario may hold")
    return out


# ---------------------------------------------------------------------- parser
_TOP_KEYS = {"format", "name", "area", "robot", "tables", "obstacles", "objects", "clutter"}
_ROBOT_KEYS = {"start", "heading", "radius", "postures"}
_POSTURE_KEYS = {"name", "forward", "lateral"}
_KEYS = {
    "tables": {"id", "min", "max", "height"},
    "obstacles": {"id", "min", "max"},
    "objects": {"id", "start", "goal", "radius", "height"},
    "clutter": {"id", "min", "max", "height"},
}


class _Parser:
    """Turns a JSON mapping into a :class:`Scenario`, collecting every structural problem."""

    def __init__(self) -> None:
        self.violations: list[str] = []

    def fail(self, message: str) -> None:
        self.violations.append(message)

    def parse(self, data: Any) -> Scenario | None:
        if not isinstance(data, Mapping):
            self.fail("format: a scenario must be a JSON object")
            return None
        self._unknown(data, _TOP_KEYS, "scenario")
        if data.get("format") != FORMAT:
            self.fail(f"format: 'format' must be {FORMAT!r}, got {describe(data.get('format'))}")
        name = self._text(data.get("name"), "'name'")
        area = self._rect(data.get("area"), "area", required=True)
        robot = self._robot(data.get("robot"))
        if "objects" not in data:
            self.fail("format: 'objects' is required (at least one object)")
        groups = {key: self._items(data.get(key, []), key) for key in _KEYS}
        if "objects" in data and not groups["objects"]:
            self.fail("format: 'objects' must hold at least one object")
        if area is None or robot is None:
            return None
        return Scenario(
            name=name if isinstance(name, str) else "",
            area=area,
            robot=robot,
            tables=tuple(groups["tables"]),
            obstacles=tuple(groups["obstacles"]),
            objects=tuple(groups["objects"]),
            clutter=tuple(groups["clutter"]),
        )

    def _unknown(self, data: Mapping, allowed: set[str], where: str, shown: int = 10) -> None:
        unknown = [key for key in data if key not in allowed]
        for key in unknown[:shown]:
            self.fail(f"format: unknown key {describe(key)} in {where}")
        if len(unknown) > shown:
            self.fail(f"format: {len(unknown) - shown:,} more unknown keys in {where}")

    def _text(self, value: Any, where: str) -> str | None:
        """A name or an id: a non-empty string of valid Unicode, at most ``MAX_ID_LENGTH`` characters.

        Control characters are allowed (the format does not forbid them); whatever prints a name
        escapes them, so a name cannot drive the terminal."""
        if not isinstance(value, str) or not value:
            self.fail(f"format: {where} is required and must be a non-empty string, got {describe(value)}")
            return None
        if len(value) > MAX_ID_LENGTH:
            self.fail(f"format: {where} {describe(value)} is longer than {MAX_ID_LENGTH} characters")
            return None
        if any(_lone_surrogate(c) for c in value):
            self.fail(f"format: {where} {describe(value)} holds a lone surrogate (it must be valid Unicode text)")
            return None
        return value

    def _number(self, value: Any, where: str) -> float | None:
        if isinstance(value, bool) or not isinstance(value, int | float):
            self.fail(f"format: {where} must be a number, got {describe(value)}")
            return None
        try:
            return float(value)
        except OverflowError:
            return math.inf  # an integer beyond float range: rule 6 reports it as not finite

    def _point(self, value: Any, where: str) -> Point | None:
        if not isinstance(value, list | tuple) or len(value) != 2:
            self.fail(f"format: {where} must be a pair [x, y], got {describe(value)}")
            return None
        x, y = (self._number(v, where) for v in value)
        return None if x is None or y is None else (x, y)

    def _range(self, value: Any, where: str) -> tuple[float, float] | None:
        return self._point(value, where)

    def _rect(self, value: Any, where: str, required: bool = False) -> Rect | None:
        if not isinstance(value, Mapping):
            self.fail(f"format: {where} must be an object with 'min' and 'max'")
            return None
        if required:
            self._unknown(value, {"min", "max"}, where)
        lo = self._point(value.get("min"), f"{where}.min")
        hi = self._point(value.get("max"), f"{where}.max")
        return None if lo is None or hi is None else Rect.from_corners(lo, hi)

    def _robot(self, value: Any) -> Robot | None:
        if not isinstance(value, Mapping):
            self.fail("format: 'robot' is required and must be an object")
            return None
        self._unknown(value, _ROBOT_KEYS, "robot")
        start = self._point(value.get("start"), "robot.start")
        heading = value.get("heading", "+x")
        if not isinstance(heading, str) or heading not in HEADINGS:
            self.fail(f"format: robot.heading must be one of {', '.join(HEADINGS)}, got {describe(heading)}")
        radius = self._number(value.get("radius", DEFAULT_RADIUS), "robot.radius")
        postures = DEFAULT_POSTURES
        if "postures" in value:
            listed = value["postures"]
            if not isinstance(listed, list | tuple):
                self.fail(f"format: robot.postures must be a list of postures, got {describe(listed)}")
                listed = []
            postures = tuple(p for p in (self._posture(p, i) for i, p in enumerate(listed)) if p)
            if not postures:
                self.fail("format: robot.postures must hold at least one posture")
            counts = Counter(p.name for p in postures)
            for name in sorted(n for n, count in counts.items() if count > 1):
                self.fail(f"rule 1 (unique ids): posture name {name!r} is used more than once")
        if start is None or radius is None or not isinstance(heading, str) or heading not in HEADINGS:
            return None
        return Robot(start=start, heading=heading, radius=radius, postures=postures)

    def _posture(self, value: Any, index: int) -> Posture | None:
        where = f"robot.postures[{index}]"
        if not isinstance(value, Mapping):
            self.fail(f"format: {where} must be an object")
            return None
        self._unknown(value, _POSTURE_KEYS, where)
        name = self._text(value.get("name"), f"{where}.name")
        forward = self._range(value.get("forward"), f"{where}.forward")
        lateral = self._range(value.get("lateral"), f"{where}.lateral")
        if name is None or forward is None or lateral is None:
            return None
        return Posture(name, forward, lateral)

    def _items(self, value: Any, key: str) -> list:
        if not isinstance(value, list | tuple):
            self.fail(f"format: {key!r} must be a list, got {describe(value)}")
            return []
        return [item for item in (self._item(v, key, i) for i, v in enumerate(value)) if item is not None]

    def _item(self, value: Any, key: str, index: int):
        if not isinstance(value, Mapping):
            self.fail(f"format: {key}[{index}] must be an object")
            return None
        item_id = self._text(value.get("id"), f"{key}[{index}].id")
        where = f"{key}[{index}]" if item_id is None else f"{item_id!r}"
        self._unknown(value, _KEYS[key], where)
        if item_id is None:
            return None
        if key == "objects":
            start = self._point(value.get("start"), f"{where}.start")
            goal = self._point(value.get("goal"), f"{where}.goal")
            radius = self._number(value.get("radius", 0.035), f"{where}.radius")
            height = self._number(value.get("height", 0.20), f"{where}.height")
            if None in (start, goal, radius, height):
                return None
            return DeliveryObject(item_id, start, goal, radius, height)
        rect = self._rect(value, where)
        if key == "obstacles":
            return None if rect is None else Obstacle(item_id, rect)
        default_height = DEFAULT_CLUTTER_HEIGHT if key == "clutter" else DEFAULT_TABLE_HEIGHT
        height = self._number(value.get("height", default_height), f"{where}.height")
        if rect is None or height is None:
            return None
        return Table(item_id, rect, height) if key == "tables" else Clutter(item_id, rect, height)


def _lone_surrogate(char: str) -> bool:
    """True for a lone surrogate: not valid Unicode, it cannot be written as UTF-8 (nor given to SCIP)."""
    return "\ud800" <= char <= "\udfff"
