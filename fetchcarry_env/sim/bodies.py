"""Building the bodies of a scenario's layout: floor, tables, obstacles, objects, clutter, goal markers.

Heights come from the scenario (tables, objects, clutter) or :mod:`fetchcarry_env.sim.physics`
(obstacles, the floor). Every movable body gets its friction and damping set explicitly.
Poses are set later (:meth:`Simulation.reset`); here every body is created at its start.
"""

from __future__ import annotations

from dataclasses import dataclass

import fetchcarry_env.sim.physics as physics
from fetchcarry_env.geometry import Rect
from fetchcarry_env.scenario import Scenario
from fetchcarry_env.sim.client import QuietClient, pybullet

RGBA = tuple[float, float, float, float]

FLOOR_COLOR: RGBA = (0.86, 0.86, 0.82, 1.0)
TABLE_COLOR: RGBA = (0.72, 0.53, 0.34, 1.0)
OBSTACLE_COLOR: RGBA = (0.42, 0.42, 0.48, 1.0)
OBJECT_COLOR: RGBA = (0.85, 0.18, 0.18, 1.0)
CLUTTER_COLOR: RGBA = (0.20, 0.45, 0.85, 1.0)
GOAL_COLOR: RGBA = (0.15, 0.75, 0.25, 1.0)
GOAL_MARKER_THICKNESS = 0.002  # metres: goal markers are flat discs drawn on the table top (no collision)

IDENTITY = (0.0, 0.0, 0.0, 1.0)  # quaternion (x, y, z, w)


@dataclass(frozen=True)
class LayoutBodies:
    """PyBullet body ids of a built layout, addressed by scenario id."""

    floor: int
    tables: dict[str, int]
    obstacles: dict[str, int]
    objects: dict[str, int]
    clutter: dict[str, int]
    goal_markers: dict[str, int]


def build_layout(client: QuietClient, scenario: Scenario) -> LayoutBodies:
    """Create every body of ``scenario``'s layout, movable ones at their start poses."""
    floor = _static_box(client, scenario.area, -physics.FLOOR_THICKNESS, 0.0, FLOOR_COLOR)
    tables = {t.id: _static_box(client, t.rect, 0.0, t.height, TABLE_COLOR) for t in scenario.tables}
    obstacles = {
        o.id: _static_box(client, o.rect, 0.0, physics.OBSTACLE_HEIGHT, OBSTACLE_COLOR) for o in scenario.obstacles
    }
    objects = {}
    markers = {}
    for obj in scenario.objects:
        collision = client.createCollisionShape(pybullet.GEOM_CYLINDER, radius=obj.radius, height=obj.height)
        visual = client.createVisualShape(
            pybullet.GEOM_CYLINDER, radius=obj.radius, length=obj.height, rgbaColor=OBJECT_COLOR
        )
        objects[obj.id] = client.createMultiBody(
            physics.OBJECT_MASS,
            collision,
            visual,
            _on_table(scenario, obj.start, obj.height),
        )
        marker = client.createVisualShape(
            pybullet.GEOM_CYLINDER, radius=obj.radius * 1.2, length=GOAL_MARKER_THICKNESS, rgbaColor=GOAL_COLOR
        )
        markers[obj.id] = client.createMultiBody(0.0, -1, marker, _on_table(scenario, obj.goal, GOAL_MARKER_THICKNESS))
    clutter = {}
    for item in scenario.clutter:
        half = [item.rect.size[0] / 2, item.rect.size[1] / 2, item.height / 2]
        collision = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half)
        visual = client.createVisualShape(pybullet.GEOM_BOX, halfExtents=half, rgbaColor=CLUTTER_COLOR)
        clutter[item.id] = client.createMultiBody(
            physics.CLUTTER_MASS,
            collision,
            visual,
            _on_table(scenario, item.rect.center, item.height),
        )
    for body in (floor, *tables.values(), *obstacles.values()):
        client.setCollisionFilterGroupMask(body, -1, physics.GROUP_STATIC, physics.GROUP_ITEM)
        client.changeDynamics(body, -1, lateralFriction=physics.FRICTION, restitution=physics.RESTITUTION)
    for body in (*objects.values(), *clutter.values()):
        set_item_dynamics(client, body)
        client.setCollisionFilterGroupMask(body, -1, physics.GROUP_ITEM, physics.MASK_ITEM)
    for body in markers.values():
        client.setCollisionFilterGroupMask(body, -1, 0, physics.MASK_NONE)
    return LayoutBodies(floor, tables, obstacles, objects, clutter, markers)


def set_item_dynamics(client: QuietClient, body: int) -> None:
    """Friction, damping and restitution of an object or a piece of clutter, stated rather than defaulted.

    Sleeping is disabled so that the outcome of a primitive depends only on the poses it
    starts from (a body asleep in one run and awake in another would break replays).
    """
    client.changeDynamics(body, -1, **physics.ITEM_DYNAMICS, activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING)


def table_top(scenario: Scenario, xy: tuple[float, float]) -> float:
    """Height (metres) of the table under point ``xy``, or 0 (the floor)."""
    table = scenario.table_under(xy)
    return table.height if table is not None else 0.0


def _on_table(scenario: Scenario, xy: tuple[float, float], height: float) -> list[float]:
    """Centre of a body of ``height`` standing at ``xy`` on whatever table is there."""
    return [xy[0], xy[1], table_top(scenario, xy) + height / 2]


def _static_box(client: QuietClient, rect: Rect, z_low: float, z_high: float, color: RGBA) -> int:
    half = [rect.size[0] / 2, rect.size[1] / 2, (z_high - z_low) / 2]
    collision = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half)
    visual = client.createVisualShape(pybullet.GEOM_BOX, halfExtents=half, rgbaColor=color)
    center = [*rect.center, (z_low + z_high) / 2]
    return client.createMultiBody(0.0, collision, visual, center)
