"""Episode pictures: what each step did, which states are shown, where the camera puts things."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import gymnasium as gym
import numpy as np
import pybullet
import pytest
from matplotlib import colors
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
from expert import ExpertPolicy
from fetchcarry_env import drawing
from fetchcarry_env.scenario import Scenario
from fetchcarry_env.sim.bodies import CLUTTER_COLOR, GOAL_COLOR, OBJECT_COLOR
from fetchcarry_env.sim.camera import PERSPECTIVE_TARGET_HEIGHT, view_and_projection
from training.pictures.episode import (
    CAPTION_PX,
    GIF_HEIGHT,
    MAX_RENDERS,
    crop,
    episode_steps,
    gif_captions,
    key_states,
    project,
    save_episode_picture,
)
from training.rollout import run_episode


@pytest.fixture(scope="module")
def record(request):
    scenario = Scenario.load(Path(__file__).resolve().parents[2] / "examples" / "push_basic.json")
    env = gym.make("FetchCarryPush-v0", scenario=scenario, render_mode="rgb_array", width=160, height=120)
    try:
        return run_episode(env, ExpertPolicy(env), seed=0, render=True)
    finally:
        env.close()


def test_each_step_says_what_the_arm_did(record) -> None:
    steps = episode_steps(record.states, record.actions)
    acted = [step.label() for step in steps if step.acted]
    assert len(acted) == 3
    assert acted[0].endswith("pick bottle")  # the paper's push-aside: carried to the goal, pushed, placed
    assert acted[1].endswith("push block 15 cm") and acted[2].endswith("place bottle")
    assert [step.number for step in steps] == list(range(1, len(record.actions) + 1))
    assert key_states(steps) == [0, *(step.number for step in steps if step.acted)]  # the last step is the place


def test_key_states_keep_the_start_and_the_end(record) -> None:
    steps = episode_steps(record.states, record.actions) * 4  # more arm actions than the strip has room for
    chosen = key_states(steps)
    assert len(chosen) <= MAX_RENDERS and chosen[0] == 0 and chosen[-1] == len(steps)


def test_projection_agrees_with_the_env_camera() -> None:
    """The camera looks at the area's centre: that point projects to the middle of the frame."""
    scenario = Scenario.load(Path(__file__).resolve().parents[2] / "examples" / "push_basic.json")
    width, height = 400, 300
    view, projection = view_and_projection(pybullet, scenario, "perspective", width, height)
    centre = (*scenario.area.center, PERSPECTIVE_TARGET_HEIGHT)
    assert project([centre], view, projection, width, height)[0] == pytest.approx((width / 2, height / 2), abs=1e-3)
    frame = np.zeros((height, width, 3), dtype=np.uint8)
    part = crop(frame, scenario, [centre])
    assert part.shape[0] < height and part.shape[1] < width  # zoomed in
    assert part.shape[1] / part.shape[0] == pytest.approx(width / height, rel=0.02)


def test_a_picture_needs_frames(record, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="render=True"):
        save_episode_picture(replace(record, frames=[]), tmp_path / "x.png")
    with pytest.raises(ValueError, match="cannot write a picture"):
        save_episode_picture(record, tmp_path / "x.bmp")


def test_maps_and_renders_share_the_colours_of_objects_goals_and_clutter() -> None:
    for map_colour, render_colour in (
        (drawing.PALETTE.object, OBJECT_COLOR),
        (drawing.PALETTE.goal, GOAL_COLOR),
        (drawing.PALETTE.clutter, CLUTTER_COLOR),
    ):
        assert colors.to_rgb(map_colour) == pytest.approx(render_colour[:3], abs=1 / 255)


def test_labels_are_moved_apart() -> None:
    figure = Figure(figsize=(3, 3))
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    axes.set_xlim(0, 10)
    axes.set_ylim(0, 10)
    for text in ("small_1", "bottle", "block", "2,3,5"):
        axes.text(5.0, 5.0, text, ha="center", va="center", fontsize=8)
    figure.canvas.draw()
    drawing.separate_labels(axes)
    renderer = figure.canvas.get_renderer()
    boxes = [t.get_window_extent(renderer) for t in axes.texts]
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :])


def test_the_gif_is_large_and_captions_every_state(record, tmp_path: Path) -> None:
    path = save_episode_picture(record, tmp_path / "episode.gif")
    captions = gif_captions(record)
    assert captions[0].startswith("start: ") and captions[-1].startswith(f"step {len(record.actions)}/")
    assert "push block 15 cm" in " ".join(captions)
    with Image.open(path) as image:
        assert image.width >= 1000 and image.height == GIF_HEIGHT + 2 * CAPTION_PX
        assert image.n_frames == len(record.frames) == len(captions)
        for k in range(image.n_frames):
            image.seek(k)
            band = np.asarray(image.convert("RGB"))[: 2 * CAPTION_PX]
            assert (band < 100).any() and (band > 200).mean() > 0.8  # dark text on a white band


def test_ppo_curves_with_one_point_per_run_show_the_points(tmp_path: Path) -> None:
    """A smoke run's metrics.csv has one row: drawn as a line without markers, the four panels were empty."""
    from training.pictures.benchmark import plot_ppo_curves

    runs = [[{"steps": 2048.0, "seconds": 12.0 + s, "success": 0.25 * s, "return": s - 3.0}] for s in (1, 2)]
    picture = np.asarray(Image.open(plot_ppo_curves([("ppo-phases", runs)], tmp_path / "ppo.png")).convert("RGB"))
    blue = np.array(colors.to_rgb("C0")) * 255  # the first baseline's colour (drawn at alpha 0.8)
    near = np.abs(picture.astype(float) - blue).max(axis=2) < 60
    height, width = near.shape
    panels = [near[: height // 2, width // 2 :], near[height // 2 :, : width // 2], near[height // 2 :, width // 2 :]]
    assert all(panel.sum() > 20 for panel in panels)  # the top-left panel holds the legend's sample line too


def test_success_against_objects_draws_every_policy_in_its_colour(tmp_path: Path) -> None:
    """The graded worlds' curve: one line per policy over k = 1..8, each policy's colour present in both panels."""
    from training.evaluation.metrics import by_objects
    from training.pictures.benchmark import plot_against_objects, policy_colours

    def record(policy: str, k: int, seed: int, success: bool) -> dict:
        return {"policy": policy, "split": "objects-v1:test", "source": f"objects-{k}", "seed": seed, "objects": k,
                "success": success, "delivered": k if success else 0, "cost": 10.0 + k, "expert_cost": 10.0,
                "return": 1.0, "phases": 4, "pushes": 0, "invalid_actions": 0, "contacts": 0, "decision_ms": 1.0,
                "mask_ms": 0.5, "digest": f"d{seed}"}  # fmt: skip

    records = [
        record(p, k, 100 * k + s, s < 10 - k) for p in ("expert", "bc-set") for k in range(1, 9) for s in range(8)
    ]
    picture = plot_against_objects(by_objects(records), tmp_path / "objects.png", title="objects-v1:test")
    pixels = np.asarray(Image.open(picture).convert("RGB")).astype(float)
    height, width, _ = pixels.shape
    orange = np.array(colors.to_rgb(policy_colours(["expert", "bc-set"])["bc-set"])) * 255
    near = np.abs(pixels - orange).max(axis=2) < 40
    plots = near[height // 5 : height * 9 // 10]  # below the legend, above the caption
    assert plots[:, : width // 2].sum() > 100 and plots[:, width // 2 :].sum() > 100
