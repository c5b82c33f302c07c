"""Top-down pictures of a scenario and a world state, in plain matplotlib.

Used by the plan plot (``expert/plot.py``) and by the environment's episode pictures.
Headless: figures are made with the Agg canvas directly (no ``pyplot``, no global
figure state, no display), and nothing here imports PyBullet.

A *state* is anything with ``base``, ``heading``, ``holding``, ``objects`` (id ->
centre, ``(x, y)`` or ``(x, y, z)``) and ``clutter`` (id -> centre ``(x, y)``): a
:class:`~fetchcarry_env.observation.WorldState` or a plan's phase. Without a state the
scenario is drawn as it starts.

Units are metres; one axis unit is one metre.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from matplotlib import patheffects
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.legend_handler import HandlerTuple
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, FancyArrowPatch, Patch, Rectangle
from matplotlib.text import Text
from matplotlib.transforms import Bbox

from fetchcarry_env.geometry import Heading, Point, Rect, heading_vector
from fetchcarry_env.scenario import Clutter, DeliveryObject, Scenario


class StateLike(Protocol):
    """What :func:`draw_scenario` needs of a state (WorldState and plan phases have it)."""

    base: Point
    heading: Heading
    holding: str | None
    objects: Mapping[str, Sequence[float]]
    clutter: Mapping[str, Sequence[float]]


@dataclass(frozen=True)
class Palette:
    """Colours of the top-down pictures (matplotlib colour strings).

    Objects, their goals and clutter have the colours the simulator gives their bodies
    (``fetchcarry_env/sim/bodies.py``; a test keeps the two equal), so that a map and a
    3-D render of the same state read alike: the (first) object red, goals green, clutter
    blue. Further objects get colours of matplotlib's ``tab10`` that no other mark of the
    maps has (not its blue, green, grey or red), in scenario order, then three more
    (purple, brown, navy) for up to eight, the most objects a family draws.
    """

    outside: str = "#d0d0d0"  # beyond the area
    floor: str = "#fbfbf8"
    wall: str = "#404040"
    table: str = "#e3c59a"
    table_edge: str = "#9c7a4b"
    obstacle: str = "#6b6b7a"  # the renders' obstacle grey
    clutter: str = "#3373d9"  # the renders' clutter blue
    clutter_edge: str = "#1d4380"
    goal: str = "#26bf40"  # the renders' goal-marker green
    # the renders' red, then tab10's orange, cyan, pink, olive, purple, brown, and a navy: one per object
    objects: tuple[str, ...] = ("#d92e2e", "#ff7f0e", "#17becf", "#e377c2", "#bcbd22", "#9467bd", "#8c564b", "#1b2a6b")

    @property
    def object(self) -> str:
        """The colour of the first (or only) object: the renders' object red."""
        return self.objects[0]

    robot: str = "#d9d9d9"  # the renders' light grey base
    robot_edge: str = "#333333"


PALETTE = Palette()

# z-orders: floor < furniture < clutter < goals < objects < robot < annotations
Z_FLOOR, Z_FURNITURE, Z_CLUTTER, Z_GOAL, Z_OBJECT, Z_ROBOT, Z_TEXT = 0, 1, 2, 3, 4, 5, 8

MARGIN = 0.3  # metres of the outside shown around the area
GOAL_MARKER_SCALE = 1.2  # the goal marker's radius in object radii (as the simulator draws it)
LABEL_GAP_PX = 2.0  # pixels kept between two labels by separate_labels
LABEL_TRIES = 12  # positions separate_labels tries for one label
LABEL_HALO = [patheffects.withStroke(linewidth=2.0, foreground="white")]  # keeps labels legible on any fill


def object_colour(scenario: Scenario, object_id: str) -> str:
    """The colour of an object, its goal and its carrying moves: one per object, in scenario order."""
    ids = [obj.id for obj in scenario.objects]
    index = ids.index(object_id) if object_id in ids else 0
    return PALETTE.objects[index % len(PALETTE.objects)]


def new_figure(scenario: Scenario, width_in: float = 7.0) -> tuple[Figure, Axes]:
    """A headless figure with one equal-aspect axes framing the scenario's area (``width_in`` inches wide)."""
    figure = Figure(figsize=(width_in, map_height_in(scenario, width_in) + 0.6), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    frame_map(axes, scenario.area.inflate(MARGIN))
    return figure, axes


def map_height_in(scenario: Scenario, width_in: float) -> float:
    """Height (inches) of a map of the area with its margin that is ``width_in`` wide."""
    width_m, height_m = scenario.area.inflate(MARGIN).size
    return max(2.5, width_in * height_m / width_m)


def frame_map(axes: Axes, view: Rect) -> None:
    """Make ``axes`` an equal-aspect map (metres) of the rectangle ``view``."""
    axes.set_xlim(view.min_x, view.max_x)
    axes.set_ylim(view.min_y, view.max_y)
    axes.set_aspect("equal")
    axes.set_xlabel("x [m]")
    axes.set_ylabel("y [m]")
    axes.set_facecolor(PALETTE.outside)


def draw_scenario(
    axes: Axes,
    scenario: Scenario,
    state: StateLike | None = None,
    *,
    show_robot: bool = True,
    show_goals: bool = True,
    show_clutter: bool = True,
    show_labels: bool = True,
) -> None:
    """Draw the area, tables, obstacles, clutter, objects, goals and the robot, from above.

    Positions of objects, clutter and the robot come from ``state``, else from the
    scenario's start. A held object is drawn with a thick outline.
    """
    draw_area(axes, scenario.area)
    for table in scenario.tables:
        draw_rect(axes, table.rect, face=PALETTE.table, edge=PALETTE.table_edge, zorder=Z_FURNITURE)
        if show_labels:
            box_label(axes, table.rect, table.id, color=PALETTE.table_edge, side="below")
    for obstacle in scenario.obstacles:
        draw_rect(axes, obstacle.rect, face=PALETTE.obstacle, edge=PALETTE.wall, zorder=Z_FURNITURE, hatch="//")
    if show_goals:
        for obj in scenario.objects:
            draw_goal(axes, obj, colour=object_colour(scenario, obj.id))
    if show_clutter:
        for item in scenario.clutter:
            center = state.clutter.get(item.id, item.rect.center) if state else item.rect.center
            draw_clutter(axes, item, center, label=show_labels)
    for obj in scenario.objects:
        center = state.objects.get(obj.id, obj.start) if state else obj.start
        held = state is not None and state.holding == obj.id
        draw_object(axes, obj, center, colour=object_colour(scenario, obj.id), held=held, label=show_labels)
    if show_robot:
        base, heading = (state.base, state.heading) if state else (scenario.robot.start, scenario.robot.heading)
        draw_robot(axes, base, heading, scenario.robot.radius)


def draw_area(axes: Axes, area: Rect) -> None:
    """The floor of the room: a light rectangle with a dark border."""
    draw_rect(axes, area, face=PALETTE.floor, edge=PALETTE.wall, zorder=Z_FLOOR, linewidth=1.5)


def draw_rect(
    axes: Axes,
    rect: Rect,
    *,
    face: str,
    edge: str,
    zorder: float,
    linewidth: float = 1.0,
    linestyle: str = "-",
    alpha: float = 1.0,
    hatch: str | None = None,
    label: str | None = None,
) -> Rectangle:
    """An axis-aligned rectangle patch."""
    width, height = rect.size
    patch = Rectangle(
        rect.min,
        width,
        height,
        facecolor=face,
        edgecolor=edge,
        linewidth=linewidth,
        linestyle=linestyle,
        alpha=alpha,
        hatch=hatch,
        zorder=zorder,
        label=label,
    )
    axes.add_patch(patch)
    return patch


def draw_clutter(
    axes: Axes, item: Clutter, center: Sequence[float], *, ghost: bool = False, label: bool = True
) -> None:
    """A piece of clutter centred at ``center``; ``ghost`` draws a dashed outline (where it was)."""
    width, depth = item.rect.size
    rect = Rect.around((float(center[0]), float(center[1])), width / 2, depth / 2)
    if ghost:
        draw_rect(axes, rect, face="none", edge=PALETTE.clutter_edge, zorder=Z_CLUTTER, linestyle="--")
        return
    draw_rect(axes, rect, face=PALETTE.clutter, edge=PALETTE.clutter_edge, zorder=Z_CLUTTER, alpha=0.9)
    if label:
        box_label(axes, rect, item.id, color=PALETTE.clutter_edge, weight="bold")


def draw_object(
    axes: Axes,
    obj: DeliveryObject,
    center: Sequence[float],
    *,
    colour: str = PALETTE.object,
    held: bool = False,
    label: bool = True,
) -> None:
    """A delivery object (a disc of its radius) centred at ``center``; held ones get a thick outline.

    Its label, in its colour, sits on top of the disc (or touching it elsewhere: :func:`separate_labels`).
    """
    x, y = float(center[0]), float(center[1])
    axes.add_patch(
        Circle(
            (x, y),
            obj.radius,
            facecolor=colour,
            edgecolor="black" if held else colour,
            linewidth=2.0 if held else 0.5,
            zorder=Z_OBJECT,
        )
    )
    if label:
        box_label(axes, Rect.around((x, y), obj.radius, obj.radius), obj.id, color=colour, side="above")


def draw_goal(axes: Axes, obj: DeliveryObject, *, colour: str = PALETTE.object) -> None:
    """An object's goal: a green disc (the renders' goal marker, 1.2 object radii) ringed in the object's colour."""
    x, y = obj.goal
    axes.add_patch(Circle((x, y), GOAL_MARKER_SCALE * obj.radius, facecolor=PALETTE.goal, alpha=0.6, zorder=Z_GOAL))
    axes.add_patch(
        Circle((x, y), obj.radius, facecolor="none", edgecolor=colour, linestyle="--", linewidth=1.2, zorder=Z_GOAL)
    )
    axes.plot([x], [y], marker="x", color=colour, markersize=5, zorder=Z_GOAL)


def draw_robot(
    axes: Axes,
    base: Point,
    heading: Heading,
    radius: float,
    *,
    alpha: float = 0.8,
    face: str | None = None,
    edge: str | None = None,
    zorder: float = Z_ROBOT,
) -> None:
    """The round base at ``base`` with an arrow from its centre to its rim along ``heading``."""
    face = PALETTE.robot if face is None else face
    edge = PALETTE.robot_edge if edge is None else edge
    axes.add_patch(Circle(base, radius, facecolor=face, edgecolor=edge, alpha=alpha, linewidth=1.2, zorder=zorder))
    draw_heading(axes, base, heading, radius, color=edge, zorder=zorder + 0.1)


def draw_heading(axes: Axes, base: Point, heading: Heading, length: float, *, color: str, zorder: float) -> None:
    """An arrow of ``length`` metres from ``base`` along ``heading``."""
    hx, hy = heading_vector(heading)
    axes.add_patch(
        FancyArrowPatch(
            base,
            (base[0] + hx * length, base[1] + hy * length),
            arrowstyle="-|>",
            mutation_scale=10,
            color=color,
            linewidth=1.5,
            zorder=zorder,
        )
    )


def render_rgb(
    scenario: Scenario, state: StateLike | None = None, *, width_px: int = 640, title: str = ""
) -> np.ndarray:
    """The top-down picture as an ``(height, width, 3)`` uint8 array (for ``render_mode="rgb_array"``)."""
    dpi = 100
    figure, axes = new_figure(scenario, width_in=width_px / dpi)
    figure.set_dpi(dpi)
    draw_scenario(axes, scenario, state)
    if title:
        axes.set_title(title, fontsize=9)
    canvas = figure.canvas
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def _label_style(color: str, weight: str) -> dict:
    """The look of a map's name label: small, coloured, over everything, with a white halo."""
    return {
        "fontsize": 7,
        "color": color,
        "weight": weight,
        "zorder": Z_TEXT,
        "clip_on": True,
        "path_effects": LABEL_HALO,
    }


class BoxLabel(Text):
    """A text that names a box (a table, a piece of clutter, an object's disc): it stays on or touching the box.

    ``box`` is the box in data coordinates (metres). :func:`separate_labels` places these
    labels first and moves one only to another side of its own box.
    """

    def __init__(self, box: Rect, text: str, side: str, **style) -> None:
        super().__init__(0.0, 0.0, text, **style)
        self.box = box
        self.side = side
        self.put(side)

    def put(self, side: str) -> None:
        """Place the label on ``side`` of its box: ``on`` (centred), ``above``, ``below``, ``left`` or ``right``."""
        box = self.box
        self.side = side
        (cx, cy), ha, va = box.center, "center", "center"
        if side == "above":
            cy, va = box.max_y, "bottom"
        elif side == "below":
            cy, va = box.min_y, "top"
        elif side == "left":
            cx, ha = box.min_x, "right"
        elif side == "right":
            cx, ha = box.max_x, "left"
        elif side != "on":
            raise ValueError(f"unknown side {side!r}")
        self.set_position((cx, cy))
        self.set_horizontalalignment(ha)
        self.set_verticalalignment(va)


BOX_LABEL_SIDES = ("above", "below", "right", "left", "on")  # where separate_labels tries a box's label, after its own


def box_label(
    axes: Axes, box: Rect, text: str, *, color: str = "black", weight: str = "normal", side: str = "on"
) -> BoxLabel:
    """A :class:`BoxLabel` naming ``box`` (metres), on ``side`` of it."""
    label = BoxLabel(box, text, side, **_label_style(color, weight))
    axes.add_artist(label)
    return label


def draw_faint_base(axes: Axes, base: Point, heading: Heading, radius: float) -> None:
    """A base disc of ``radius`` metres, faint, with its heading: one pose along a path."""
    edge = PALETTE.robot_edge
    axes.add_patch(Circle(base, radius, facecolor=PALETTE.robot, edgecolor=edge, alpha=0.15, zorder=Z_ROBOT))
    axes.add_patch(Circle(base, radius, facecolor="none", edgecolor=edge, linewidth=0.8, zorder=Z_ROBOT))
    draw_heading(axes, base, heading, radius, color=edge, zorder=Z_ROBOT + 0.1)


def number_points(axes: Axes, points: Sequence[Point], merge_m: float, offset_m: float, *, fontsize: float = 7) -> None:
    """The index of each point beside it, ``offset_m`` up-left.

    Points closer than ``merge_m`` metres share one label, runs of indices written as
    ranges (:func:`index_ranges`: "3,7", "20-23").
    """
    groups: list[tuple[Point, list[int]]] = []
    for k, point in enumerate(points):
        for at, members in groups:
            if math.dist(at, point) < merge_m:
                members.append(k)
                break
        else:
            groups.append((point, [k]))
    for at, members in groups:
        axes.text(
            at[0] - offset_m,
            at[1] + offset_m,
            index_ranges(members),
            ha="center",
            va="center",
            fontsize=fontsize,
            weight="bold",
            zorder=Z_TEXT + 1,
            clip_on=True,
            bbox={"boxstyle": "round,pad=0.15", "facecolor": "white", "edgecolor": PALETTE.robot_edge},
        )


def index_ranges(indices: Sequence[int]) -> str:
    """Indices as text, runs of three or more as a range: ``[4, 16, 23, 24, 25]`` -> ``"4,16,23-25"``."""
    runs: list[list[int]] = []
    for k in indices:
        if runs and k == runs[-1][-1] + 1:
            runs[-1].append(k)
        else:
            runs.append([k])
    return ",".join(f"{run[0]}-{run[-1]}" if len(run) >= 3 else ",".join(str(k) for k in run) for run in runs)


def separate_labels(axes: Axes) -> None:
    """Move the texts of ``axes`` apart so that none overlaps another (call once everything is drawn).

    The labels of boxes (:class:`BoxLabel`: tables, clutter, objects) are placed first, each on the
    first side of its own box (:data:`BOX_LABEL_SIDES`, its drawn side first) where it
    overlaps no placed label, else where it was drawn: a box's label always touches its
    box. The other texts follow in drawing order; one that overlaps a placed text moves up
    or down (alternately, one text height further at each try) to the first free place, at
    most :data:`LABEL_TRIES` tries; one moved farther than the next place gets a thin line
    back to where it was drawn. Needs the figure's canvas (the Agg canvas has a renderer).
    """
    renderer = axes.figure.canvas.get_renderer()
    texts = [t for t in axes.texts if t.get_visible() and t.get_text()]
    placed: list[Bbox] = []
    for label in (t for t in texts if isinstance(t, BoxLabel)):
        placed.append(_place_box_label(label, placed, renderer))
    for text in (t for t in texts if not isinstance(t, BoxLabel)):
        placed.append(_place_text(axes, text, placed, renderer))


def _extent(text: Text, renderer) -> Bbox:
    """The window extent (pixels) of ``text`` with the gap kept between labels."""
    return text.get_window_extent(renderer).expanded(1.0, 1.0).padded(LABEL_GAP_PX)


def _place_box_label(label: BoxLabel, placed: list[Bbox], renderer) -> Bbox:
    """Put ``label`` on the first side of its box where it overlaps none of ``placed``; its extent."""
    drawn = label.side
    for side in dict.fromkeys((drawn, *BOX_LABEL_SIDES)):
        label.put(side)
        box = _extent(label, renderer)
        if not any(box.overlaps(other) for other in placed):
            return box
    label.put(drawn)
    return _extent(label, renderer)


def _place_text(axes: Axes, text: Text, placed: list[Bbox], renderer) -> Bbox:
    """Move ``text`` up or down to the first place where it overlaps none of ``placed``; its extent."""
    to_data = axes.transData.inverted()
    box = _extent(text, renderer)
    if any(box.overlaps(other) for other in placed):
        drawn = text.get_position()
        anchor = axes.transData.transform(drawn)
        for k in range(1, LABEL_TRIES + 1):
            shift = box.height * ((k + 1) // 2) * (1 if k % 2 else -1)
            moved = box.translated(0, shift)
            if not any(moved.overlaps(other) for other in placed):
                text.set_position(to_data.transform((anchor[0], anchor[1] + shift)))
                if k > 2:  # moved farther than next to where it was drawn: a line back to that place
                    _leader(axes, drawn, text.get_position())
                return moved
    return box


def _leader(axes: Axes, drawn: Sequence[float], moved: Sequence[float]) -> None:
    """A thin line from a label moved to ``moved`` back to where it was drawn (``drawn``), under the labels."""
    axes.plot([drawn[0], moved[0]], [drawn[1], moved[1]], color=PALETTE.robot_edge, linewidth=0.6, zorder=Z_TEXT - 0.5)


CLOSE_UP_MOST = 0.6  # a close-up's side at most this share of the whole view's longer side, else none is drawn


def close_up(boxes: Sequence[Rect], whole: Rect, margin: float, most: float = CLOSE_UP_MOST) -> Rect | None:
    """A square view (metres) around ``boxes`` plus ``margin``: where the action is, to draw beside ``whole``.

    ``None`` when there are no boxes, or when the square's side is more than ``most`` of
    ``whole``'s longer side: such a "close-up" would show about what the whole view shows.
    """
    if not boxes:
        return None
    low = (min(b.min_x for b in boxes), min(b.min_y for b in boxes))
    box = Rect(*low, max(b.max_x for b in boxes), max(b.max_y for b in boxes)).inflate(margin)
    half = max(box.size) / 2
    if 2 * half > most * max(whole.size):
        return None
    return Rect.around(box.center, half, half)


def point_box(point: Sequence[float]) -> Rect:
    """The box of zero size at ``point`` (``(x, y)`` or ``(x, y, z)``, metres)."""
    return Rect.around((float(point[0]), float(point[1])), 0.0, 0.0)


LEGEND_HANDLERS = {tuple: HandlerTuple(ndivide=None, pad=0.2)}  # a tuple of handles: its samples side by side


def scene_legend(objects: int, *, obstacles: bool, clutter: bool) -> tuple[list, list[str]]:
    """Legend handles and labels of a scene drawn by :func:`draw_scenario` (pass ``handler_map=LEGEND_HANDLERS``).

    ``objects``: how many objects the scenes have at most (their colours are shown side by
    side); ``obstacles``, ``clutter``: whether any scene has them.
    """
    colours = PALETTE.objects[: max(1, min(objects, len(PALETTE.objects)))]
    discs = tuple(_disc_handle(c, c, 6) for c in colours)
    entries: list[tuple[object, str]] = [
        (_disc_handle(PALETTE.robot, PALETTE.robot_edge, 11), "robot start (arrow: its heading)"),
        (discs, "objects at their start, one colour each"),
        (_disc_handle(PALETTE.goal, colours[0], 9), "goal (ring, cross: its object's colour)"),
        (Patch(facecolor=PALETTE.table, edgecolor=PALETTE.table_edge), "table"),
    ]
    if obstacles:
        entries.append((Patch(facecolor=PALETTE.obstacle, edgecolor=PALETTE.wall, hatch="//"), "wall, obstacle"))
    if clutter:
        entries.append((Patch(facecolor=PALETTE.clutter, edgecolor=PALETTE.clutter_edge), "clutter"))
    return [handle for handle, _ in entries], [label for _, label in entries]


def _disc_handle(face: str, edge: str, size: float) -> Line2D:
    """A legend sample: a disc of ``size`` points filled ``face``, ringed ``edge``."""
    return Line2D([], [], marker="o", markersize=size, markerfacecolor=face, markeredgecolor=edge, linestyle="none")


def draw_arrow(axes: Axes, start: Point, end: Point, colour: str, *, width: float, style: str = "-|>") -> None:
    """A straight arrow from ``start`` to ``end`` (metres); nothing when they coincide (a turn in place)."""
    if math.dist(start, end) < 1e-9:
        return
    axes.add_patch(
        FancyArrowPatch(
            tuple(start),
            tuple(end),
            arrowstyle=style,
            mutation_scale=14,
            color=colour,
            linewidth=width,
            shrinkA=0,
            shrinkB=0,
            zorder=Z_ROBOT + 0.5,
        )
    )
