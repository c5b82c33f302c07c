"""Pictures of an episode: a still that tells its story at a glance, or an animated GIF of every state.

The still (PNG, JPEG, SVG, PDF) has three parts under a title with the episode's figures:

- a large top-down map of the executed episode (:mod:`fetchcarry_env.drawing`): the room,
  the base's path step by step (travel with an empty hand, carrying in the object's
  colour, push strokes in red), the base at every step with its number, the arm line of
  every pick and place, clutter where it started (dashed) and where it ended;
- a close-up map of where objects were placed and clutter pushed, when that is a small
  part of the area; otherwise the legend takes its place;
- a strip of the env's renders (perspective camera) at the key states (the start and the
  state after each pick, place and push), each cropped around the robot and what its arm
  acted on, titled with the step's number and what it did.

The colours are those of the plan plot (:mod:`expert.plot`) and of the renders: the
object red (further objects a distinct colour each, the same for the object, its goal
ring, its label and the moves that carry it), goals green, clutter blue in the maps and
in the 3-D renders alike. Step numbers at one place share a label ("20-23"); labels
that would overlap are moved apart, the name of a piece of clutter or an object only
to another side of it. The GIF shows, for every state, the env's render
(cropped to where the episode happens) beside the top-down map of the path so far,
under a caption that says which step it is and what the step did. Headless (matplotlib's Agg canvas, Pillow for GIFs).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from PIL import Image, ImageDraw, ImageFont

from expert.plot import PICK, PLACE, PUSH, TRAVEL, draw_arm, path_legend_handles
from fetchcarry_env import drawing
from fetchcarry_env.actions import Action, Mode
from fetchcarry_env.geometry import Rect
from fetchcarry_env.observation import WorldState
from fetchcarry_env.scenario import Scenario
from fetchcarry_env.sim.camera import view_and_projection
from fetchcarry_env.sim.client import pybullet
from training.pictures.files import check_picture_path, is_gif
from training.rollout import EpisodeFigures, EpisodeRecord

GIF_FRAME_MS = 700  # milliseconds each state is shown in a GIF
MAX_RENDERS = 6  # env renders in the strip of a still picture
MAP_WIDTH_IN = 6.6  # inches of the whole-area map (the close-up has the same size)
LONE_MAP_SHARE = 0.68  # of the picture's width: the whole-area map's where no close-up is drawn (the legend beside)
CLOSE_UP_MARGIN = 0.35  # metres shown around the close-up's content
CROP_MARGIN = 0.06  # of the frame's width, kept around the robot and its target in a render crop
CROP_MIN_WIDTH = 0.28  # of the frame's width: the smallest crop (a zoom of about 3.5)
ROBOT_TOP = 1.0  # metres: the height of the robot's head, kept inside a crop
STILL_DPI = 100
GIF_HEIGHT = 540  # pixels: a GIF's render and map, side by side at this height (under the caption)
GIF_MAP_IN = 5.4  # inches (at 100 dpi) of the map beside a GIF's render
CAPTION_PX = 30  # pixels: the caption's font size; its band is twice as high


def save_episode_picture(record: EpisodeRecord, path: str | Path) -> Path:
    """Write ``record`` as a picture: a GIF of every frame, or the still described in the module docstring.

    The record must have its frames (``run_episode(..., render=True)``) and its states.
    """
    path = check_picture_path(path)
    if not record.frames:
        raise ValueError("the episode has no frames: run it with render=True")
    if is_gif(path):
        scenario = Scenario.from_dict(record.scenario)
        points = episode_points(scenario, record.states)
        steps = episode_steps(record.states, record.actions)
        frames = [
            side_by_side(crop(np.asarray(frame), scenario, points), map_so_far(scenario, record.states, steps, k))
            for k, frame in enumerate(record.frames)
        ]
        save_gif(frames, path, captions=gif_captions(record))
    else:
        save_story(record, path)
    return path


def save_gif(
    frames: Sequence[np.ndarray], path: Path, frame_ms: int = GIF_FRAME_MS, captions: Sequence[str] | None = None
) -> None:
    """An animated GIF of ``frames`` (uint8 rgb arrays), each under its caption; the last frame held twice as long."""
    images = [Image.fromarray(np.asarray(frame, dtype=np.uint8)) for frame in frames]
    if captions is not None:
        images = [captioned(image, text) for image, text in zip(images, captions, strict=True)]
    durations = [frame_ms] * (len(images) - 1) + [2 * frame_ms]
    images[0].save(path, save_all=True, append_images=images[1:], duration=durations, loop=0)


def map_so_far(
    scenario: Scenario, states: Sequence[WorldState], steps: Sequence[EpisodeStep], index: int
) -> np.ndarray:
    """The top-down map of state ``index`` with the base's path up to it, as a uint8 rgb array."""
    figure = Figure(figsize=(GIF_MAP_IN, GIF_MAP_IN), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    view = scenario.area.inflate(drawing.MARGIN)
    drawing.frame_map(axes, view)
    draw_episode(axes, scenario, states[: index + 1], steps[:index], label_size_m=0.2 * view.size[0] / GIF_MAP_IN)
    figure.canvas.draw()
    drawing.separate_labels(axes)
    figure.canvas.draw()
    return np.asarray(figure.canvas.buffer_rgba())[..., :3].copy()


def side_by_side(left: np.ndarray, right: np.ndarray, height: int = GIF_HEIGHT) -> np.ndarray:
    """Two rgb arrays scaled to ``height`` pixels and put next to each other."""
    parts = []
    for array in (left, right):
        image = Image.fromarray(np.asarray(array, dtype=np.uint8))
        parts.append(np.asarray(image.resize((round(image.width * height / image.height), height))))
    return np.concatenate(parts, axis=1)


def episode_points(scenario: Scenario, states: Sequence[WorldState]) -> list[tuple[float, float, float]]:
    """World points (metres) a GIF's crop must show: the robot at every state, every object and its goal, clutter."""
    points: list[tuple[float, float, float]] = []
    for state in states:
        points += [(state.base[0], state.base[1], 0.0), (state.base[0], state.base[1], ROBOT_TOP)]
        points += [(float(p[0]), float(p[1]), float(p[2]) if len(p) > 2 else 0.7) for p in state.objects.values()]
        points += [(float(x), float(y), 0.7) for x, y in state.clutter.values()]
    points += [(o.goal[0], o.goal[1], 0.7) for o in scenario.objects]
    return points


def gif_captions(record: EpisodeRecord) -> list[str]:
    """One caption per state: the start, then each step's number, what it did and the objects delivered."""
    steps = episode_steps(record.states, record.actions)
    scenario = Scenario.from_dict(record.scenario)
    total = len(steps)
    captions = [f"start: {scenario.name}, {len(scenario.objects)} object(s) to deliver"]
    for step in steps:
        delivered = len(step.after.delivered(scenario))
        captions.append(f"step {step.number}/{total}: {step.label().split(' ', 1)[1]}  ({delivered} delivered)")
    return captions


def captioned(image: Image.Image, text: str) -> Image.Image:
    """``image`` (a Pillow image) under a white band with ``text`` in black."""
    band = 2 * CAPTION_PX
    out = Image.new("RGB", (image.width, image.height + band), "white")
    out.paste(image.convert("RGB"), (0, band))
    font = ImageFont.load_default(size=CAPTION_PX)
    ImageDraw.Draw(out).text((CAPTION_PX // 2, band // 2), text, fill="black", font=font, anchor="lm")
    return out


# ---------------------------------------------------------------------------- what each step did
@dataclass(frozen=True)
class EpisodeStep:
    """What one step of the episode did, read from the states before and after it."""

    number: int  # 1-based: step k leads from state k-1 to state k
    mode: Mode
    before: WorldState
    after: WorldState
    target: str | None  # the object picked or placed, the clutter pushed (None for a move, or if refused)
    pushed_m: float  # metres the pushed clutter moved

    @property
    def acted(self) -> bool:
        """True when the arm picked, placed or pushed something."""
        return self.target is not None

    def label(self) -> str:
        """A few words: ``"3 push block 15 cm"``, ``"4 pick bottle"``, ``"1 move"``."""
        if self.mode == Mode.PUSH and self.target is not None:
            return f"{self.number} push {self.target} {self.pushed_m * 100:.0f} cm"
        if self.target is not None:
            return f"{self.number} {self.mode.name.lower()} {self.target}"
        if self.mode != Mode.MOVE:
            return f"{self.number} {self.mode.name.lower()} (invalid)"
        return f"{self.number} move"


def episode_steps(states: Sequence[WorldState], actions: np.ndarray) -> list[EpisodeStep]:
    """One :class:`EpisodeStep` per action, from the states around it (``len(states) == len(actions) + 1``).

    An action is an env action vector (``FetchCarryPush-v0``) or a candidate's index
    (``FetchCarryPushPhases-v0``, e.g. a learned policy's episode); an index does not say
    its mode without the state's candidates, so the step's mode is read from what
    changed: a pick, a place, a push, or a move.
    """
    if len(states) != len(actions) + 1:
        raise ValueError(f"{len(states)} states for {len(actions)} actions: the record has no states?")
    steps = []
    for k, action in enumerate(actions):
        before, after = states[k], states[k + 1]
        mode = Action.from_array(action).mode if np.ndim(action) else _mode_from_states(before, after)
        target, pushed = None, 0.0
        if mode == Mode.PICK and after.holding is not None and before.holding is None:
            target = after.holding
        elif mode == Mode.PLACE and before.holding is not None and after.holding is None:
            target = before.holding
        elif mode == Mode.PUSH:
            moved = {c: math.dist(before.clutter[c], after.clutter[c]) for c in before.clutter if c in after.clutter}
            if moved and max(moved.values()) > 1e-3:
                target = max(moved, key=moved.get)
                pushed = moved[target]
        steps.append(EpisodeStep(k + 1, mode, before, after, target, pushed))
    return steps


def _mode_from_states(before: WorldState, after: WorldState) -> Mode:
    """What a step did, from the states around it: the hand took or let go of an object, clutter moved, or neither."""
    if before.holding is None and after.holding is not None:
        return Mode.PICK
    if before.holding is not None and after.holding is None:
        return Mode.PLACE
    if any(math.dist(before.clutter[c], after.clutter[c]) > 1e-3 for c in before.clutter if c in after.clutter):
        return Mode.PUSH
    return Mode.MOVE


def key_states(steps: Sequence[EpisodeStep], most: int = MAX_RENDERS) -> list[int]:
    """State indices for the strip: the start, the state after each arm action, and the end (at most ``most``)."""
    acted = [s.number for s in steps if s.acted]
    chosen = sorted({0, *acted, len(steps)})
    if len(chosen) <= most:
        return chosen
    middle = chosen[1:-1]
    keep = [middle[round(k * (len(middle) - 1) / (most - 3))] for k in range(most - 2)] if most > 3 else []
    return sorted({0, *keep, len(steps)})


# ---------------------------------------------------------------------------- the still picture
def save_story(record: EpisodeRecord, path: Path) -> None:
    """The still picture of the module docstring."""
    story_figure(record).savefig(path, dpi=STILL_DPI)


def story_figure(record: EpisodeRecord) -> Figure:
    """The still picture of the module docstring, as a headless figure (labels already moved apart)."""
    scenario = Scenario.from_dict(record.scenario)
    steps = episode_steps(record.states, record.actions)
    shown = key_states(steps)
    view = close_up_view(scenario, steps)
    whole_width_in = MAP_WIDTH_IN if view is not None else LONE_MAP_SHARE * 2 * MAP_WIDTH_IN
    map_height_in = drawing.map_height_in(scenario, whole_width_in)
    render_width_in = 2 * MAP_WIDTH_IN / max(len(shown), 3)
    strip_height_in = render_width_in * 0.75 + 0.3
    legend_height_in = 0.4 if view is not None else 0.0
    figure = Figure(
        figsize=(2 * MAP_WIDTH_IN, map_height_in + strip_height_in + legend_height_in + 1.1), layout="constrained"
    )
    FigureCanvasAgg(figure)
    rows = figure.add_gridspec(3, 1, height_ratios=[map_height_in, strip_height_in, max(legend_height_in, 1e-3)])
    maps = rows[0].subgridspec(1, 2, width_ratios=[whole_width_in, 2 * MAP_WIDTH_IN - whole_width_in])
    whole = figure.add_subplot(maps[0])
    drawing.frame_map(whole, scenario.area.inflate(drawing.MARGIN))
    draw_episode(whole, scenario, record.states, steps, label_size_m=0.2 * scenario.area.size[0] / whole_width_in)
    whole.set_title("the episode from above (numbers: the state after each step)", fontsize=10)
    if view is not None:
        close = figure.add_subplot(maps[1])
        drawing.frame_map(close, view)
        draw_episode(close, scenario, record.states, steps, label_size_m=0.2 * view.size[0] / MAP_WIDTH_IN)
        close.set_title("close-up: pushes and places", fontsize=10)
        legend_axes = figure.add_subplot(rows[2])
    else:
        legend_axes = figure.add_subplot(maps[1])
    _draw_strip(figure, rows[1], record, scenario, steps, shown)
    _draw_legend(legend_axes, scenario, beside=view is None)
    figure.suptitle(title(record.figures), fontsize=11, family="monospace")
    figure.canvas.draw()  # lays the figure out, so that labels are separated where they will be
    for axes in figure.axes:
        drawing.separate_labels(axes)
    return figure


def _draw_strip(
    figure: Figure, cell, record: EpisodeRecord, scenario: Scenario, steps: Sequence[EpisodeStep], shown: list[int]
) -> None:
    """The env's renders of the ``shown`` states in a row of ``cell``, each cropped around what its step did."""
    strip = cell.subgridspec(1, max(len(shown), 3))
    for slot, state_index in enumerate(shown):
        axes = figure.add_subplot(strip[slot])
        frame = np.asarray(record.frames[state_index])
        if state_index > 0:
            frame = crop(frame, scenario, focus_points(steps[state_index - 1]))
        axes.imshow(frame)
        axes.set_axis_off()
        axes.set_title("0 start" if state_index == 0 else steps[state_index - 1].label(), fontsize=10)


def _draw_legend(axes: Axes, scenario: Scenario, *, beside: bool) -> None:
    """The legend on ``axes``: a row under the maps, or a column beside the map where no close-up is drawn."""
    axes.set_axis_off()
    if beside:
        note = "no close-up: the pushes and places\nspread over most of the area"
        axes.legend(handles=legend_handles(scenario), loc="center left", ncol=1, fontsize=9, frameon=False, title=note)
    else:
        axes.legend(handles=legend_handles(scenario), loc="center", ncol=5, fontsize=8, frameon=False)


def title(figures: EpisodeFigures) -> str:
    """Two lines: what happened, and the figures behind it."""
    objective = "" if figures.objective is None else f", objective {figures.objective:.2f}"
    first = (
        f"{figures.scenario} (seed {figures.seed}): {figures.outcome}, {figures.delivered}/{figures.objects} "
        f"object(s) at the goal after {figures.steps} steps, return {figures.episode_return:.2f}"
    )
    second = (
        f"path {figures.path_length_m:.2f} m, {figures.collisions} collisions, {figures.invalid_actions} invalid "
        f"actions; planning {figures.planning_s:.2f} s in {figures.plans} plan(s), {figures.replans} replans"
        f"{objective}; simulation {figures.simulation_s:.2f} s"
    )
    return f"{first}\n{second}"


def draw_episode(
    axes: Axes, scenario: Scenario, states: Sequence[WorldState], steps: Sequence[EpisodeStep], *, label_size_m: float
) -> None:
    """The scene at the end of the episode, the clutter's start (dashed), and every step of the base."""
    last = states[-1]
    drawing.draw_scenario(axes, scenario, last, show_robot=False, show_clutter=False)
    for item in scenario.clutter:
        start, end = states[0].clutter[item.id], last.clutter[item.id]
        if math.dist(start, end) > 1e-3:
            drawing.draw_clutter(axes, item, start, ghost=True)
        drawing.draw_clutter(axes, item, end)
    for state in states[:-1]:
        drawing.draw_faint_base(axes, state.base, state.heading, scenario.robot.radius)
    for step in steps:
        _draw_step(axes, scenario, step)
    drawing.draw_robot(axes, last.base, last.heading, scenario.robot.radius)
    drawing.number_points(axes, [s.base for s in states], label_size_m, 0.75 * scenario.robot.radius, fontsize=8)


def close_up_view(scenario: Scenario, steps: Sequence[EpisodeStep]) -> Rect | None:
    """A square around the bases and targets of every push and place, or None (:func:`fetchcarry_env.drawing.close_up`).

    The targets: where each object was placed, where each pushed piece of clutter was and
    went. None when nothing was pushed or placed, or when the square would show about as
    much as the whole area.
    """
    boxes = []
    for step in steps:
        if step.acted and step.mode == Mode.PUSH:
            pushed = (step.before.clutter[step.target], step.after.clutter[step.target])
            boxes += [drawing.point_box(point) for point in (step.before.base, step.after.base, *pushed)]
        elif step.acted and step.mode == Mode.PLACE:
            boxes += [drawing.point_box(step.after.base), drawing.point_box(step.after.objects[step.target])]
    return drawing.close_up(boxes, scenario.area.inflate(drawing.MARGIN), CLOSE_UP_MARGIN)


def _draw_step(axes: Axes, scenario: Scenario, step: EpisodeStep) -> None:
    before, after = step.before, step.after
    if step.mode == Mode.PUSH and step.target is not None:
        drawing.draw_arrow(axes, before.base, after.base, PUSH, width=3.0)
        drawing.draw_arrow(axes, before.clutter[step.target], after.clutter[step.target], PUSH, width=1.5, style="->")
        return
    colour = TRAVEL if before.holding is None else drawing.object_colour(scenario, before.holding)
    drawing.draw_arrow(axes, before.base, after.base, colour, width=1.6)
    if step.target is not None and step.mode in (Mode.PICK, Mode.PLACE):
        at = before.objects[step.target] if step.mode == Mode.PICK else after.objects[step.target]
        arm, action = (PICK, "pick") if step.mode == Mode.PICK else (PLACE, "place")
        draw_arm(axes, after.base, at, arm, action, drawing.object_colour(scenario, step.target))


def legend_handles(scenario: Scenario) -> list:
    palette = drawing.PALETTE
    handles = path_legend_handles(scenario, "base at state k", "at the end, goal ring")
    if scenario.clutter:
        handles.append(Patch(facecolor=palette.clutter, edgecolor=palette.clutter_edge, label="clutter (end)"))
        handles.append(Patch(facecolor="none", edgecolor=palette.clutter_edge, linestyle="--", label="clutter (start)"))
    handles.append(Patch(facecolor=palette.goal, alpha=0.6, label="goal marker (green in the renders too)"))
    return handles


# ---------------------------------------------------------------------------- render crops
def focus_points(step: EpisodeStep) -> list[tuple[float, float, float]]:
    """World points (metres) a render of the state after ``step`` must show: the robot and what it acted on."""
    after = step.after
    points = [(after.base[0], after.base[1], 0.0), (after.base[0], after.base[1], ROBOT_TOP)]
    if step.target in after.objects:
        x, y, z = after.objects[step.target]
        points.append((x, y, z))
    elif step.target in after.clutter:
        x, y = after.clutter[step.target]
        points.append((x, y, 0.7))
    return points


def crop(frame: np.ndarray, scenario: Scenario, points: Sequence[tuple[float, float, float]]) -> np.ndarray:
    """The part of a perspective render that shows ``points`` with a margin (aspect kept, at least 3x zoom).

    ``frame`` is the env's perspective render of ``scenario``; the points are projected with
    the env's camera (:func:`fetchcarry_env.sim.camera.view_and_projection`).
    """
    height, width = frame.shape[:2]
    # The camera's matrices are pure math: pybullet's module functions compute them without a connection.
    view, projection = view_and_projection(pybullet, scenario, "perspective", width, height)
    pixels = project(points, view, projection, width, height)
    aspect = height / width
    lo, hi = pixels.min(axis=0), pixels.max(axis=0)
    crop_w = max(hi[0] - lo[0] + 2 * CROP_MARGIN * width, (hi[1] - lo[1]) / aspect + 2 * CROP_MARGIN * width)
    crop_w = float(np.clip(crop_w, CROP_MIN_WIDTH * width, width))
    crop_h = crop_w * aspect
    cx, cy = (lo + hi) / 2
    x0 = round(float(np.clip(cx - crop_w / 2, 0, width - crop_w)))
    y0 = round(float(np.clip(cy - crop_h / 2, 0, height - crop_h)))
    return frame[y0 : y0 + int(crop_h), x0 : x0 + int(crop_w)]


def project(
    points: Sequence[tuple[float, float, float]],
    view: Sequence[float],
    projection: Sequence[float],
    width: int,
    height: int,
) -> np.ndarray:
    """Pixel coordinates ``(column, row)`` of world points under PyBullet's column-major view and projection."""
    v = np.asarray(view, dtype=np.float64).reshape(4, 4).T
    p = np.asarray(projection, dtype=np.float64).reshape(4, 4).T
    homogeneous = np.c_[np.asarray(points, dtype=np.float64), np.ones(len(points))]
    clip = homogeneous @ (p @ v).T
    ndc = clip[:, :3] / clip[:, 3:4]
    return np.c_[(ndc[:, 0] + 1) / 2 * width, (1 - ndc[:, 1]) / 2 * height]
