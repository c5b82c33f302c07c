"""Observation modes: the goal-env ``Dict`` of the state, with images beside it.

``obs_mode="state"`` is the env's own observation (:mod:`fetchcarry_env.observation`),
untouched. ``"topdown"`` adds ``topdown``, a semantic map drawn from the geometry
(:mod:`fetchcarry_env.observations.topdown`); ``"rgbd"`` adds ``head_rgbd`` and
``overhead_rgbd``, camera images drawn by PyBullet
(:mod:`fetchcarry_env.observations.cameras`). Every image is uint8, channels first, so
SB3's ``MultiInputPolicy`` gives each a NatureCNN. ``docs/observations.md`` has the details.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium import spaces

from fetchcarry_env.geometry import Rect
from fetchcarry_env.observation import Capacity, WorldState
from fetchcarry_env.observations.cameras import Cameras
from fetchcarry_env.observations.topdown import CHANNELS, FRAMES, TopdownMap
from fetchcarry_env.scenario import Scenario
from fetchcarry_env.sim import Simulation

OBS_MODES: tuple[str, ...] = ("state", "topdown", "rgbd")
IMAGE_KEYS: dict[str, tuple[str, ...]] = {"state": (), "topdown": ("topdown",), "rgbd": ("head_rgbd", "overhead_rgbd")}
"""The image keys each mode adds to the goal-env keys (``observation``, ``achieved_goal``, ``desired_goal``)."""

__all__ = ["CHANNELS", "FRAMES", "IMAGE_KEYS", "OBS_MODES", "ImageObservations", "image_options", "image_space"]


def image_options(obs_mode: str, values: int) -> dict[str, Any]:
    """The env options whose images of ``obs_mode``, flattened and concatenated, hold ``values`` numbers.

    ``{}`` for ``state``; ``{"obs_mode": "topdown", "topdown_size": S}`` for ``7 * S * S``
    values; ``{"obs_mode": "rgbd", "camera_size": C}`` for ``2 * 4 * C * C``. How a learned
    network's input size tells the env to make (the map's frame is the default, ``world``).
    ``ValueError`` when the count fits no square image.
    """
    if obs_mode == "state":
        return {}
    channels = {"topdown": len(CHANNELS), "rgbd": 8}.get(obs_mode)
    side = math.isqrt(values // channels) if channels else 0
    if not channels or channels * side * side != values:
        raise ValueError(f"{values} values are no square images of obs_mode {obs_mode!r}")
    return {"obs_mode": obs_mode, ("topdown_size" if obs_mode == "topdown" else "camera_size"): side}


def image_space(shape: tuple[int, ...]) -> spaces.Box:
    """A uint8 image space ``[0, 255]`` of ``shape`` (channels first)."""
    return spaces.Box(0, 255, shape=shape, dtype=np.uint8)


@dataclass
class ImageObservations:
    """Adds a mode's images to an observation; one per env (it keeps the static layers of the map).

    ``mode``: ``"topdown"`` or ``"rgbd"``; ``extent``: the env's floor (metres);
    ``options``: ``topdown_size``, ``topdown_frame``, ``topdown_span`` (metres),
    ``camera_size`` and ``renderer`` (see the env's docstring).
    """

    mode: str
    extent: Rect
    capacity: Capacity
    options: dict[str, Any]

    def __post_init__(self) -> None:
        if self.mode not in OBS_MODES[1:]:
            raise ValueError(f"obs_mode must be one of {', '.join(OBS_MODES)}, got {self.mode!r}")
        known = {"topdown_size", "topdown_frame", "topdown_span", "camera_size", "renderer"}
        unknown = set(self.options) - known
        if unknown:
            raise ValueError(f"unknown observation option(s) {sorted(unknown)}: known are {sorted(known)}")
        o = {k: v for k, v in self.options.items() if v is not None}
        self._map: TopdownMap | None = None
        self._cameras: Cameras | None = None
        if self.mode == "topdown":
            cap = self.capacity
            self._map = TopdownMap(
                self.extent,
                cap.tables,
                cap.obstacles,
                cap.objects,
                cap.clutter,
                size=o.get("topdown_size", 64),
                frame=o.get("topdown_frame", "world"),
                span=o.get("topdown_span"),
            )
        else:
            self._cameras = Cameras(self.extent, size=o.get("camera_size", 128), renderer=o.get("renderer", "tiny"))

    def space(self, state_space: spaces.Dict) -> spaces.Dict:
        """``state_space`` with this mode's image spaces beside its keys."""
        shape = self._map.shape if self._map is not None else self._cameras.shape
        images = {key: image_space(shape) for key in IMAGE_KEYS[self.mode]}
        return spaces.Dict({**state_space.spaces, **images})

    def add(self, observation: dict[str, np.ndarray], scenario: Scenario, state: WorldState, sim: Simulation) -> None:
        """Put the images of ``scenario`` at ``state`` into ``observation`` (``sim`` shows that state)."""
        if self._map is not None:
            observation["topdown"] = self._map.draw(scenario, state)
            return
        drawn = self._cameras.draw(sim, state)
        observation["head_rgbd"] = drawn["head"]
        observation["overhead_rgbd"] = drawn["overhead"]
