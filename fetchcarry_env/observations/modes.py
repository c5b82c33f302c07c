"""Observation modes as records: one table that the env, the learners and the command line read.

An :class:`ObservationMode` says what a mode adds to the state observation (its image
keys and their channels), which keyword options of ``gym.make`` it takes (each with its
default and its range or choices: :class:`ModeOption`) and how to make what draws its
images (``make``). ``state`` adds nothing. A new mode is one module with its drawer and
one :func:`register_mode` call; ``docs/observations.md`` has the built-in ones.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from fetchcarry_env.geometry import Rect
from fetchcarry_env.observation import Capacity, WorldState
from fetchcarry_env.observations.cameras import RENDERERS, Cameras
from fetchcarry_env.observations.topdown import CHANNELS, FRAMES, TopdownMap
from fetchcarry_env.scenario import Scenario
from fetchcarry_env.sim import Simulation

IMAGE_SIDES = (8, 1024)  # pixels a side an image may have, low and high


class ImageSource(Protocol):
    """What draws a mode's images: one per env (it may keep what does not change, as the map's static layers)."""

    shape: tuple[int, int, int]  # (channels, side, side) of each of the mode's images

    def draw(self, scenario: Scenario, state: WorldState, sim: Simulation) -> dict[str, np.ndarray]:
        """The mode's images of ``scenario`` at ``state`` (``sim`` shows that state), by key."""


@dataclass(frozen=True)
class ModeOption:
    """One keyword option of ``gym.make`` a mode takes: its default and the values it may have.

    ``kind`` is ``int``, ``float`` or ``str``; a number lies in ``[low, high]`` (``low``
    exclusive when ``above`` is set), a string is one of ``choices``. ``default`` None means
    the mode decides (and no value is recorded).
    """

    name: str
    kind: type
    default: Any
    help: str
    low: float | None = None
    high: float | None = None
    above: bool = False
    choices: tuple[str, ...] = ()

    def problem(self, value: Any) -> str | None:
        """Why ``value`` is no value of this option, or None."""
        if self.kind is str:
            return None if value in self.choices else f"{self.name} must be one of {', '.join(self.choices)}"
        numeric = (int,) if self.kind is int else (int, float)
        if not isinstance(value, numeric) or isinstance(value, bool) or not math.isfinite(value):
            return f"{self.name} must be {'a whole number' if self.kind is int else 'a number'}"
        if self.low is not None and (value <= self.low if self.above else value < self.low):
            return f"{self.name} must be {'above' if self.above else 'at least'} {self.low:g}"
        if self.high is not None and value > self.high:
            return f"{self.name} must be at most {self.high:g}"
        return None


@dataclass(frozen=True)
class ObservationMode:
    """One observation mode: the images it adds beside the state, its options and its drawer.

    ``keys`` are the image keys, each ``(channels, side, side)`` uint8; ``side_option`` the
    option whose value is ``side``; ``make(extent, capacity, options)`` the drawer of an
    env's images (``options`` complete: every option's value or default). ``state`` has no
    keys, options or drawer.
    """

    name: str
    description: str
    keys: tuple[str, ...] = ()
    channels: int = 0
    options: tuple[ModeOption, ...] = ()
    side_option: str | None = None
    make: Callable[[Rect, Capacity, dict[str, Any]], ImageSource] | None = None

    @property
    def option_names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.options)

    @property
    def input_channels(self) -> int:
        """Channels of the images stacked (what a network of this mode reads per pixel)."""
        return len(self.keys) * self.channels

    def resolved(self, options: Mapping[str, Any]) -> dict[str, Any]:
        """Every option of this mode: ``options``' values, checked, and the defaults of the others.

        ``ValueError`` names an option this mode does not take or a value out of its range.
        """
        unknown = sorted(set(options) - set(self.option_names))
        if unknown:
            known = ", ".join(self.option_names) or "none"
            raise ValueError(f"obs_mode {self.name!r} takes no option(s) {', '.join(unknown)} (it takes: {known})")
        values = {}
        for option in self.options:
            value = options.get(option.name)
            value = option.default if value is None else value
            problem = None if value is None else option.problem(value)
            if problem is not None:
                raise ValueError(f"{problem}, got {shown(value)}")
            values[option.name] = value
        return values

    def side(self, values: int) -> int:
        """The side of the square images whose pixels, stacked and flattened, are ``values`` numbers.

        ``ValueError`` unless they make square images of :data:`IMAGE_SIDES` pixels a side.
        """
        channels = self.input_channels
        side = math.isqrt(values // channels) if channels else 0
        low, high = IMAGE_SIDES
        if not channels or channels * side * side != values or not low <= side <= high:
            raise ValueError(
                f"{values} values are not {channels} square images of {low} to {high} pixels a side (obs_mode "
                f"{self.name!r})"
            )
        return side


def image_side_option(name: str, default: int, what: str) -> ModeOption:
    """An option giving images' side in pixels, within :data:`IMAGE_SIDES`."""
    low, high = IMAGE_SIDES
    return ModeOption(name, int, default, f"{what} pixels a side, {low} to {high}", low=low, high=high)


@dataclass
class _Topdown:
    map: TopdownMap

    @property
    def shape(self) -> tuple[int, int, int]:
        return self.map.shape

    def draw(self, scenario: Scenario, state: WorldState, sim: Simulation) -> dict[str, np.ndarray]:
        return {"topdown": self.map.draw(scenario, state)}


def _topdown(extent: Rect, capacity: Capacity, options: dict[str, Any]) -> ImageSource:
    c = capacity
    size, frame, span = options["topdown_size"], options["topdown_frame"], options["topdown_span"]
    return _Topdown(TopdownMap(extent, c.tables, c.obstacles, c.objects, c.clutter, size=size, frame=frame, span=span))


@dataclass
class _Rgbd:
    cameras: Cameras

    @property
    def shape(self) -> tuple[int, int, int]:
        return self.cameras.shape

    def draw(self, scenario: Scenario, state: WorldState, sim: Simulation) -> dict[str, np.ndarray]:
        drawn = self.cameras.draw(sim, state)
        return {"head_rgbd": drawn["head"], "overhead_rgbd": drawn["overhead"]}


def _rgbd(extent: Rect, capacity: Capacity, options: dict[str, Any]) -> ImageSource:
    return _Rgbd(Cameras(extent, size=options["camera_size"], renderer=options["renderer"]))


STATE = ObservationMode("state", "the geometry vector alone (the goal-env Dict)")
TOPDOWN = ObservationMode(
    "topdown",
    "plus a semantic map drawn from the geometry",
    keys=("topdown",),
    channels=len(CHANNELS),
    options=(
        image_side_option("topdown_size", 64, "topdown map"),
        ModeOption("topdown_frame", str, "world", "topdown map centred on the world or on the robot", choices=FRAMES),
        ModeOption("topdown_span", float, None, "metres the map covers a side (default the extent's)", 0, above=True),
    ),
    side_option="topdown_size",
    make=_topdown,
)
RGBD = ObservationMode(
    "rgbd",
    "plus head and overhead RGB-D camera images",
    keys=("head_rgbd", "overhead_rgbd"),
    channels=4,
    options=(
        image_side_option("camera_size", 128, "rgbd camera"),
        ModeOption("renderer", str, "tiny", "PyBullet's renderer: tiny (CPU) or egl", choices=RENDERERS),
    ),
    side_option="camera_size",
    make=_rgbd,
)
_MODES: dict[str, ObservationMode] = {mode.name: mode for mode in (STATE, TOPDOWN, RGBD)}


def register_mode(mode: ObservationMode) -> ObservationMode:
    """Add ``mode`` (its name must be new, and its options' names no other mode's)."""
    if mode.name in _MODES:
        raise ValueError(f"an observation mode {mode.name!r} is registered already")
    taken = {name for other in _MODES.values() for name in other.option_names} & set(mode.option_names)
    if taken:
        raise ValueError(f"option(s) {', '.join(sorted(taken))} belong to another mode already")
    _MODES[mode.name] = mode
    return mode


def unregister_mode(name: str) -> None:
    """Remove the mode ``name`` (tests that register a throwaway one)."""
    if name in (STATE.name, TOPDOWN.name, RGBD.name):
        raise ValueError(f"{name!r} is a built-in mode")
    _MODES.pop(name, None)


def modes() -> tuple[ObservationMode, ...]:
    """Every registered mode, ``state`` first."""
    return tuple(_MODES.values())


def mode_names() -> tuple[str, ...]:
    """The registered modes' names, ``state`` first."""
    return tuple(_MODES)


def get_mode(name: str) -> ObservationMode:
    """The mode ``name``; ``ValueError`` lists the known ones otherwise."""
    mode = _MODES.get(name)
    if mode is None:
        raise ValueError(f"obs_mode must be one of {', '.join(_MODES)}, got {shown(name)}")
    return mode


def shown(value: Any) -> str:
    """``value`` as a message shows it: its repr, a long text cut to 40 characters."""
    return repr(value[:40] if isinstance(value, str) else value)[:60]


def image_option_names() -> tuple[str, ...]:
    """Every option of every registered mode (the env keywords that are image options)."""
    return tuple(name for mode in _MODES.values() for name in mode.option_names)
