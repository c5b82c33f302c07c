"""The PyBullet simulation: the only code in fetchcarry that imports ``pybullet``.

:class:`Simulation` builds a scenario's bodies (tables, walls, objects, clutter and an
HSR-like robot) in its own physics server and runs the phase primitives (move, pick,
place, push). Nothing here runs at import time: a server starts on first use.
"""

from fetchcarry_env.sim.camera import CAMERAS, Camera
from fetchcarry_env.sim.robot import HandPose
from fetchcarry_env.sim.world import PushOutcome, Simulation, Snapshot, stroke_profile

__all__ = ["CAMERAS", "Camera", "HandPose", "PushOutcome", "Simulation", "Snapshot", "stroke_profile"]
