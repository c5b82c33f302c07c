"""The plan plot and the top-down drawing: real pictures with the plan's marks in them."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from matplotlib import colors
from matplotlib.image import imread

from expert import plot
from expert.plans import Plan
from expert.plot import plot_plan
from fetchcarry_env import drawing
from fetchcarry_env.observation import WorldState

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def pixels_of(image: np.ndarray, colour: str, tol: float = 0.02) -> int:
    """How many pixels of ``image`` (floats in [0, 1]) have ``colour``."""
    rgb = np.array(colors.to_rgb(colour))
    return int(np.all(np.abs(image[..., :3] - rgb) <= tol, axis=-1).sum())


MARKS = (plot.PUSH, plot.PICK, plot.PLACE, plot.TRAVEL, plot.CARRY)


def no_plan_picture(tmp_path, scenario) -> np.ndarray:
    """The picture of a plan without phases: the scenario, the legend, no marks."""
    plan = Plan(scenario.name, "infeasible", None, (), {"total_s": 0.2})
    return imread(plot_plan(scenario, plan, tmp_path / "none.png"))


def test_plot_plan_writes_a_picture_with_every_kind_of_mark(tmp_path, spec_example, hand_plan):
    path = plot_plan(spec_example, hand_plan, tmp_path / "plan.png")
    assert path == tmp_path / "plan.png"
    assert path.read_bytes()[:8] == PNG_SIGNATURE
    image = imread(path)
    height, width = image.shape[:2]
    assert width >= 1000 and height >= 600
    # Beyond the legend's samples, the plan's marks are drawn: the push stroke, the pick and place arm
    # lines, travel with an empty hand and carrying.
    baseline = no_plan_picture(tmp_path, spec_example)
    for colour in MARKS:
        assert pixels_of(image, colour) > pixels_of(baseline, colour) + 30, colour
    assert pixels_of(image, drawing.PALETTE.table) > 1000
    assert pixels_of(image, drawing.PALETTE.clutter, tol=0.05) > 30


def test_a_shorter_plan_draws_only_its_own_marks(tmp_path, spec_example, hand_plan):
    baseline = no_plan_picture(tmp_path, spec_example)
    shorter = replace(hand_plan, phases=hand_plan.phases[:4])  # up to the push: no pick, no place
    image = imread(plot_plan(spec_example, shorter, tmp_path / "short.png"))
    assert pixels_of(image, plot.PUSH) > pixels_of(baseline, plot.PUSH) + 30
    for colour in (plot.PICK, plot.PLACE):
        assert pixels_of(image, colour) <= pixels_of(baseline, colour) + 5, colour


def test_render_rgb_draws_the_state(spec_example):
    start = drawing.render_rgb(spec_example, width_px=400)
    assert start.dtype == np.uint8 and start.ndim == 3 and start.shape[1] == 400 and start.shape[2] == 3
    state = WorldState.initial(spec_example)
    moved = drawing.render_rgb(spec_example, replace(state, base=(3.0, 1.0), heading="+y"), width_px=400)
    assert start.shape == moved.shape and not np.array_equal(start, moved)
    assert pixels_of(start / 255.0, drawing.PALETTE.table) > 100
