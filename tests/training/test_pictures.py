"""Episode pictures: what each step did, which states are shown, where the camera puts things."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pybullet
import pytest

import fetchcarry_env  # noqa: F401  (registers FetchCarryPush-v0)
from expert import ExpertPolicy
from fetchcarry_env.scenario import Scenario
from fetchcarry_env.sim.camera import PERSPECTIVE_TARGET_HEIGHT, view_and_projection
from training.pictures import MAX_RENDERS, crop, episode_steps, key_states, project, save_episode_picture
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
    assert acted[0].endswith("push block 15 cm")
    assert acted[1].endswith("pick bottle") and acted[2].endswith("place bottle")
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
    from dataclasses import replace

    with pytest.raises(ValueError, match="render=True"):
        save_episode_picture(replace(record, frames=[]), tmp_path / "x.png")
    with pytest.raises(ValueError, match="cannot write a picture"):
        save_episode_picture(record, tmp_path / "x.bmp")
