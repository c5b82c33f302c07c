"""The ``rgbd`` observation: a camera on the robot's head and one over the floor, RGB and depth.

Each camera gives one ``(4, size, size)`` uint8 image, channels first: red, green, blue
and depth. Depth is the distance along the camera's axis, linear over the camera's range:
``depth_m = near + (far - near) * value / 255`` (:data:`HEAD_RANGE`, and for the
overhead camera ``OVERHEAD_RANGE`` below its height, so 255 is the floor or farther).

``head``: at the front of the base, :data:`HEAD_HEIGHT` above the floor, looking along
the heading and :data:`HEAD_PITCH` degrees down, :data:`HEAD_FOV` degrees of view.
``overhead``: straight down over the centre of the env's extent (north up, as the
``topdown`` map), high enough that :data:`OVERHEAD_FOV` degrees show the whole extent.

Drawn by PyBullet's CPU tiny renderer (``renderer="tiny"``, the default: the same
pixels on every machine), or by its EGL plugin (``renderer="egl"``: hardware OpenGL, or
Mesa without a GPU; falls back to the tiny renderer with a warning when the plugin does
not load). The pictures come from the PyBullet world the env steps, so they show what
physics did (a pushed box turned a little, say) as well as the geometry.
"""

from __future__ import annotations

import contextlib
import importlib.util
import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from fetchcarry_env.geometry import Rect, heading_vector
from fetchcarry_env.observation import WorldState
from fetchcarry_env.sim import Simulation
from fetchcarry_env.sim.client import QuietClient, pybullet, silenced_file_descriptors

CAMERA_NAMES: tuple[str, ...] = ("head", "overhead")
RENDERERS: tuple[str, ...] = ("tiny", "egl")
DEFAULT_SIZE = 128  # pixels a side
HEAD_HEIGHT = 1.2  # metres above the floor
HEAD_FORWARD = 0.1  # metres ahead of the base's centre (in front of the lift column)
HEAD_PITCH = 35.0  # degrees below the horizon
HEAD_FOV = 75.0  # degrees, vertical (the images are square)
HEAD_RANGE = (0.05, 8.0)  # metres: near and far plane, and the depth channel's range
OVERHEAD_FOV = 60.0  # degrees
OVERHEAD_MARGIN = 1.02  # the overhead camera shows 2% more than the extent
OVERHEAD_RANGE = 2.0  # metres above the floor the overhead depth channel resolves (255: the floor)


@dataclass
class Cameras:
    """Draws the ``head`` and ``overhead`` RGB-D images of the world a :class:`Simulation` holds."""

    extent: Rect
    size: int = DEFAULT_SIZE
    renderer: str = "tiny"
    _egl: dict = field(default_factory=dict, repr=False)  # {"client": id of the client the plugin loaded in}

    def __post_init__(self) -> None:
        if not isinstance(self.size, int) or isinstance(self.size, bool) or not 8 <= self.size <= 1024:
            raise ValueError(f"camera size must be an integer from 8 to 1024 pixels, got {self.size!r}")
        if self.renderer not in RENDERERS:
            raise ValueError(f"renderer must be one of {', '.join(RENDERERS)}, got {self.renderer!r}")
        side = max(self.extent.size) * OVERHEAD_MARGIN
        self.overhead_height = side / 2 / math.tan(math.radians(OVERHEAD_FOV) / 2)  # metres

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(4, size, size)``: RGB and depth, channels first."""
        return (4, self.size, self.size)

    def draw(self, sim: Simulation, state: WorldState) -> dict[str, np.ndarray]:
        """``{"head": image, "overhead": image}`` of the world at ``state`` (uint8, :attr:`shape`)."""
        client = sim.client
        renderer = self._renderer(sim, state)
        return {
            "head": self._image(client, renderer, *self._head(client, state)),
            "overhead": self._image(client, renderer, *self._overhead(client)),
        }

    def __getstate__(self) -> dict:
        return {**self.__dict__, "_egl": {}}  # a copy has its own PyBullet world: load the plugin again there

    # ------------------------------------------------------------------ internals
    def _head(
        self, client: QuietClient, state: WorldState
    ) -> tuple[list, list, tuple[float, float], tuple[float, float]]:
        hx, hy = heading_vector(state.heading)
        eye = [state.base[0] + HEAD_FORWARD * hx, state.base[1] + HEAD_FORWARD * hy, HEAD_HEIGHT]
        drop = math.tan(math.radians(HEAD_PITCH))
        target = [eye[0] + hx, eye[1] + hy, HEAD_HEIGHT - drop]
        view = client.computeViewMatrix(eye, target, [0.0, 0.0, 1.0])
        near, far = HEAD_RANGE
        projection = client.computeProjectionMatrixFOV(HEAD_FOV, 1.0, near, far)
        return view, projection, HEAD_RANGE, HEAD_RANGE

    def _overhead(self, client: QuietClient) -> tuple[list, list, tuple[float, float], tuple[float, float]]:
        cx, cy = self.extent.center
        height = self.overhead_height
        view = client.computeViewMatrix([cx, cy, height], [cx, cy, 0.0], [0.0, 1.0, 0.0])
        planes = (height - OVERHEAD_RANGE, height + 0.05)
        projection = client.computeProjectionMatrixFOV(OVERHEAD_FOV, 1.0, *planes)
        return view, projection, planes, (height - OVERHEAD_RANGE, height)

    def _image(
        self,
        client: QuietClient,
        renderer: int,
        view: list,
        projection: list,
        planes: tuple[float, float],
        depth_range: tuple[float, float],
    ) -> np.ndarray:
        """One RGB-D image: RGB as drawn; the depth buffer turned to metres (``planes``: the projection's
        near and far) and quantised over ``depth_range`` (metres)."""
        quiet = silenced_file_descriptors(1) if renderer != pybullet.ER_TINY_RENDERER else contextlib.nullcontext()
        with quiet:  # EGL prints its vendor on stdout
            _, _, rgba, depth, _ = client.getCameraImage(
                self.size,
                self.size,
                viewMatrix=view,
                projectionMatrix=projection,
                renderer=renderer,
                flags=pybullet.ER_NO_SEGMENTATION_MASK,
            )
        rgba = np.asarray(rgba, dtype=np.uint8).reshape(self.size, self.size, 4)
        buffer = np.asarray(depth, dtype=np.float64).reshape(self.size, self.size)
        near, far = planes
        metres = far * near / (far - (far - near) * buffer)
        low, high = depth_range
        scaled = np.clip((metres - low) / (high - low), 0.0, 1.0)
        image = np.empty(self.shape, dtype=np.uint8)
        image[:3] = rgba[:, :, :3].transpose(2, 0, 1)
        image[3] = np.rint(scaled * 255.0).astype(np.uint8)
        return image

    def _renderer(self, sim: Simulation, state: WorldState) -> int:
        """The renderer constant; loads the EGL plugin into the simulation's client once when asked for.

        The plugin draws only bodies made after it loaded: the simulation rebuilds its bodies
        where they are (exactly, as a copied env does).
        """
        if self.renderer == "tiny":
            return pybullet.ER_TINY_RENDERER
        client = sim.client
        if self._egl.get("client") == id(client):
            return pybullet.ER_BULLET_HARDWARE_OPENGL if self._egl["loaded"] else pybullet.ER_TINY_RENDERER
        with silenced_file_descriptors(1, 2):  # the plugin prints its OpenGL version on stdout
            loaded = _load_egl(client)
        if loaded:
            with silenced_file_descriptors(1, 2):
                sim.rebuild(state)
        else:
            warnings.warn("PyBullet's EGL plugin did not load: drawing with the tiny renderer", stacklevel=3)
        self._egl.update(client=id(sim.client), loaded=loaded)
        return pybullet.ER_BULLET_HARDWARE_OPENGL if loaded else pybullet.ER_TINY_RENDERER


def _load_egl(client: QuietClient) -> bool:
    """Load PyBullet's ``eglRenderer`` plugin into ``client``; False when it is not there or fails."""
    spec = importlib.util.find_spec("eglRenderer")
    if spec is None or spec.origin is None:
        return False
    return client.loadPlugin(spec.origin, "_eglRendererPlugin") >= 0
