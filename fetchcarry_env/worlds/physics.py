"""Physics variation: each piece of clutter's mass and friction drawn per episode.

The scenario format has no mass or friction (every piece of clutter weighs
``sim.physics.CLUTTER_MASS``, 1 kg, with friction ``sim.physics.FRICTION``, 0.5), so a
variation is an option of the environment, not of the file: a family may name one
(``perturbed`` does), and ``gym.make(..., physics=...)`` sets or clears it for any
scenario. At every reset the env draws the values from its own generator
(``env.np_random``, seeded by ``reset(seed=...)``), after the scenario is drawn: the
same seed gives the same scenario and the same masses and frictions, bit for bit.

Lower friction makes a piece slide on after the hand stops (the hand decelerates at
2 m/s^2; a combined friction below 0.2 cannot hold a piece at that), so a push lands
farther than planned; a heavier piece needs more of the arm's 30 N to start. The
expert sees only the observation (no masses), so it replans from where the piece landed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from fetchcarry_env.errors import InputError
from fetchcarry_env.scenario import Scenario


class ItemPhysics(NamedTuple):
    """One piece of clutter's mass (kg) and lateral friction coefficient."""

    mass: float
    friction: float


@dataclass(frozen=True)
class PhysicsVariation:
    """Ranges each piece of clutter's mass (kg) and friction are drawn from, uniformly."""

    name: str
    mass: tuple[float, float]  # kg
    friction: tuple[float, float]  # lateral friction coefficient (PyBullet multiplies the two bodies')

    def __post_init__(self) -> None:
        if not 0 < self.mass[0] <= self.mass[1] or not 0 <= self.friction[0] <= self.friction[1]:
            raise ValueError(f"physics variation {self.name!r}: ranges must be (low, high), masses positive")

    def draw(self, rng: np.random.Generator, scenario: Scenario) -> dict[str, ItemPhysics]:
        """Mass then friction of each piece of clutter, in the scenario's order, from ``rng``."""
        values = {}
        for item in scenario.clutter:
            mass = float(rng.uniform(*self.mass))
            values[item.id] = ItemPhysics(mass, float(rng.uniform(*self.friction)))
        return values


HOME = PhysicsVariation("home", mass=(0.4, 2.5), friction=(0.25, 0.8))
"""What a home changes: boxes from 0.4 to 2.5 kg, from slippery (0.25) to grippy (0.8)."""
PHYSICS_VARIATIONS: dict[str, PhysicsVariation] = {HOME.name: HOME}
NO_VARIATION = "none"  # the env's physics= value that turns a family's variation off


class PhysicsError(InputError):
    """An unknown physics variation name."""


def physics_variation(spec: str | PhysicsVariation | None) -> PhysicsVariation | None:
    """A variation from a name (``"home"``), an instance or ``None`` / ``"none"`` (no variation)."""
    if spec is None or isinstance(spec, PhysicsVariation):
        return spec
    if spec == NO_VARIATION:
        return None
    if spec not in PHYSICS_VARIATIONS:
        known = ", ".join([NO_VARIATION, *PHYSICS_VARIATIONS])
        raise PhysicsError(f"unknown physics variation {spec!r}; known: {known}")
    return PHYSICS_VARIATIONS[spec]
