"""Observation modes: the goal-env ``Dict`` of the state, with images beside it.

``obs_mode="state"`` is the env's own observation (:mod:`fetchcarry_env.observation`),
untouched. ``"topdown"`` adds ``topdown``, a semantic map drawn from the geometry
(:mod:`fetchcarry_env.observations.topdown`); ``"rgbd"`` adds ``head_rgbd`` and
``overhead_rgbd``, camera images drawn by PyBullet
(:mod:`fetchcarry_env.observations.cameras`). Every image is uint8, channels first, so
SB3's ``MultiInputPolicy`` gives each a NatureCNN. Each mode is one record of
:mod:`fetchcarry_env.observations.modes`; ``docs/observations.md`` has the details.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gymnasium import spaces

from fetchcarry_env.geometry import Rect
from fetchcarry_env.observation import Capacity, WorldState
from fetchcarry_env.observations.modes import (
    ImageSource,
    ModeOption,
    ObservationMode,
    get_mode,
    image_option_names,
    mode_names,
    modes,
    register_mode,
    unregister_mode,
)
from fetchcarry_env.observations.topdown import CHANNELS, FRAMES
from fetchcarry_env.scenario import Scenario
from fetchcarry_env.sim import Simulation

__all__ = [
    "CHANNELS", "FRAMES", "ImageObservations", "ImageSource", "ModeOption", "ObservationMode", "get_mode",
    "image_option_names", "image_options", "image_space", "mode_names", "modes", "register_mode", "unregister_mode",
]  # fmt: skip


def image_options(obs_mode: str, values: int) -> dict[str, Any]:
    """The env options whose images of ``obs_mode``, flattened and concatenated, hold ``values`` numbers.

    ``{}`` for ``state``; ``{"obs_mode": "topdown", "topdown_size": S}`` for ``7 * S * S``
    values; ``{"obs_mode": "rgbd", "camera_size": C}`` for ``2 * 4 * C * C``. How a learned
    network's input size tells the env to make (the other options keep their defaults).
    ``ValueError`` when the count fits no square image.
    """
    mode = get_mode(obs_mode)
    if not mode.keys:
        return {}
    return {"obs_mode": obs_mode, mode.side_option: mode.side(values)}


def image_space(shape: tuple[int, ...]) -> spaces.Box:
    """A uint8 image space ``[0, 255]`` of ``shape`` (channels first)."""
    return spaces.Box(0, 255, shape=shape, dtype=np.uint8)


@dataclass
class ImageObservations:
    """Adds a mode's images to an observation; one per env (its drawer may keep what does not change).

    ``mode``: a mode with images (``"topdown"``, ``"rgbd"`` or a registered one);
    ``extent``: the env's floor (metres); ``options``: the mode's options
    (:class:`~fetchcarry_env.observations.modes.ModeOption`; ``ValueError`` names one it
    does not take or a value out of range).
    """

    mode: str
    extent: Rect
    capacity: Capacity
    options: dict[str, Any]
    _source: ImageSource = field(init=False, repr=False)
    _record: ObservationMode = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._record = get_mode(self.mode)
        if self._record.make is None:
            raise ValueError(f"obs_mode {self.mode!r} adds no images")
        self._source = self._record.make(self.extent, self.capacity, self._record.resolved(self.options))

    def space(self, state_space: spaces.Dict) -> spaces.Dict:
        """``state_space`` with this mode's image spaces beside its keys."""
        images = {key: image_space(self._source.shape) for key in self._record.keys}
        return spaces.Dict({**state_space.spaces, **images})

    def add(self, observation: dict[str, np.ndarray], scenario: Scenario, state: WorldState, sim: Simulation) -> None:
        """Put the images of ``scenario`` at ``state`` into ``observation`` (``sim`` shows that state)."""
        observation.update(self._source.draw(scenario, state, sim))
