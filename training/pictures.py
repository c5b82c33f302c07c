"""Pictures of an episode: an animated GIF of its frames, or one PNG strip of its key states.

The frames are the env's ``rgb_array`` renders, one per state (``run_episode(...,
render=True)`` keeps them). A GIF shows every state; a still picture (PNG, JPEG, SVG,
PDF) lays out up to :data:`MAX_PANELS` states in a grid, each titled with the step and
the action that led to it, under a caption with the episode's figures. Headless
(matplotlib's Agg canvas, Pillow for GIFs).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from fetchcarry_env.actions import Action
from training.rollout import EpisodeFigures, EpisodeRecord

MAX_PANELS = 12  # states shown in a still picture
PANEL_WIDTH_IN = 3.2  # inches per panel
COLUMNS = 4  # panels per row
GIF_FRAME_MS = 700  # milliseconds each state is shown in a GIF
STILL_SUFFIXES = (".png", ".jpg", ".jpeg", ".svg", ".pdf")


def check_picture_path(path: str | Path) -> Path:
    """``path`` as a Path, or ``ValueError`` when its suffix is not a picture format this module writes."""
    path = Path(path)
    if path.suffix.lower() not in (".gif", *STILL_SUFFIXES):
        raise ValueError(f"cannot write a picture to {path}: use a .gif, {', '.join(STILL_SUFFIXES)} file")
    return path


def save_episode_picture(record: EpisodeRecord, path: str | Path) -> Path:
    """Write ``record``'s frames to ``path``: a GIF of every state, or a still grid of key states."""
    path = check_picture_path(path)
    if not record.frames:
        raise ValueError("the episode has no frames: run it with render=True")
    if path.suffix.lower() == ".gif":
        save_gif(record.frames, path)
    else:
        save_strip(record.frames, step_titles(record.actions), caption(record.figures), path)
    return path


def save_gif(frames: Sequence[np.ndarray], path: Path, frame_ms: int = GIF_FRAME_MS) -> None:
    """An animated GIF of ``frames`` (uint8 rgb arrays), the last frame held twice as long."""
    from PIL import Image

    images = [Image.fromarray(np.asarray(frame, dtype=np.uint8)) for frame in frames]
    durations = [frame_ms] * (len(images) - 1) + [2 * frame_ms]
    images[0].save(path, save_all=True, append_images=images[1:], duration=durations, loop=0)


def save_strip(frames: Sequence[np.ndarray], titles: Sequence[str], text: str, path: Path) -> None:
    """Up to :data:`MAX_PANELS` frames (first and last always) in a grid, with ``text`` above."""
    chosen = key_states(len(frames))
    columns = min(COLUMNS, len(chosen))
    rows = math.ceil(len(chosen) / columns)
    height, width = np.asarray(frames[0]).shape[:2]
    panel_height_in = PANEL_WIDTH_IN * height / width + 0.35
    figure = Figure(figsize=(columns * PANEL_WIDTH_IN, rows * panel_height_in + 0.9), layout="constrained")
    FigureCanvasAgg(figure)
    figure.suptitle(text, fontsize=9, ha="left", x=0.01, family="monospace")
    for slot, state in enumerate(chosen):
        axes = figure.add_subplot(rows, columns, slot + 1)
        axes.imshow(np.asarray(frames[state]))
        axes.set_title(titles[state], fontsize=8)
        axes.set_axis_off()
    figure.savefig(path, dpi=110)


def key_states(count: int, most: int = MAX_PANELS) -> list[int]:
    """Indices of at most ``most`` states out of ``count``, evenly spread, first and last included."""
    if count <= most:
        return list(range(count))
    return sorted({round(k * (count - 1) / (most - 1)) for k in range(most)})


def step_titles(actions: np.ndarray) -> list[str]:
    """A title per state: ``start``, then ``step k: <mode> to (i, j) facing <heading>``."""
    titles = ["start"]
    for k, vector in enumerate(actions, start=1):
        action = Action.from_array(vector)
        titles.append(f"step {k}: {action.mode.name.lower()} to {action.cell} facing {action.heading}")
    return titles


def caption(figures: EpisodeFigures) -> str:
    """Two lines of the episode's figures."""
    return (
        f"{figures.scenario}  seed {figures.seed}  {figures.outcome}: delivered {figures.delivered}/{figures.objects} "
        f"in {figures.steps} steps, return {figures.episode_return:.2f}\n"
        f"path {figures.path_length_m:.2f} m, contacts {figures.collisions}, invalid actions "
        f"{figures.invalid_actions}, planning {figures.planning_s:.2f} s in {figures.plans} plan(s) "
        f"({figures.replans} replans)"
    )
