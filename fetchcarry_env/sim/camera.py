"""Headless pictures of the world: a perspective view and a top-down view, drawn by the tiny renderer."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from fetchcarry_env.scenario import Scenario
from fetchcarry_env.sim.client import QuietClient, pybullet

Camera = Literal["perspective", "top_down"]
CAMERAS: tuple[str, ...] = ("perspective", "top_down")

TOP_DOWN_HEIGHT = 40.0  # metres: a far, narrow camera looks nearly orthographic
TOP_DOWN_MARGIN = 1.05  # the top-down view shows 5% more than the area
PERSPECTIVE_FOV = 50.0  # degrees, vertical
PERSPECTIVE_YAW = -30.0  # degrees: seen from the -y side, turned towards +x
PERSPECTIVE_PITCH = -45.0  # degrees below the horizon
PERSPECTIVE_TARGET_HEIGHT = 0.4  # metres: the camera looks at this height over the area's centre


def view_and_projection(
    client: QuietClient, scenario: Scenario, camera: Camera, width: int, height: int
) -> tuple[list, list]:
    """PyBullet view and projection matrices framing the scenario's area."""
    area = scenario.area
    cx, cy = area.center
    size_x, size_y = area.size
    aspect = width / height
    if camera == "top_down":
        extent = max(size_y, size_x / aspect) * TOP_DOWN_MARGIN
        fov = math.degrees(2 * math.atan(extent / 2 / TOP_DOWN_HEIGHT))
        view = client.computeViewMatrix([cx, cy, TOP_DOWN_HEIGHT], [cx, cy, 0.0], [0.0, 1.0, 0.0])
        projection = client.computeProjectionMatrixFOV(fov, aspect, TOP_DOWN_HEIGHT - 5.0, TOP_DOWN_HEIGHT + 1.0)
        return view, projection
    if camera == "perspective":
        distance = 0.9 * math.hypot(size_x, size_y)
        view = client.computeViewMatrixFromYawPitchRoll(
            [cx, cy, PERSPECTIVE_TARGET_HEIGHT], distance, PERSPECTIVE_YAW, PERSPECTIVE_PITCH, 0.0, 2
        )
        projection = client.computeProjectionMatrixFOV(PERSPECTIVE_FOV, aspect, 0.05, 4 * distance)
        return view, projection
    raise ValueError(f"unknown camera {camera!r}: choose one of {', '.join(CAMERAS)}")


def render_image(client: QuietClient, scenario: Scenario, camera: Camera, width: int, height: int) -> np.ndarray:
    """An RGB image (``height x width x 3``, uint8) drawn headless by PyBullet's tiny renderer."""
    view, projection = view_and_projection(client, scenario, camera, width, height)
    _, _, rgba, _, _ = client.getCameraImage(
        width,
        height,
        viewMatrix=view,
        projectionMatrix=projection,
        renderer=pybullet.ER_TINY_RENDERER,
        flags=pybullet.ER_NO_SEGMENTATION_MASK,
    )
    return np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3].copy()
