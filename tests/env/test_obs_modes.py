"""obs_mode: the state observation unchanged, the topdown map's pixels, camera images, checkers, copies."""

from __future__ import annotations

import copy
import warnings

import gymnasium as gym
import numpy as np
import pytest
from sim_worlds import make, room

from fetchcarry_env.observations.topdown import CHANNELS, ROBOT_BACK, ROBOT_FRONT, WALL, slot_level
from fetchcarry_env.phase_env import make_phase_env

PHASES = "FetchCarryPushPhases-v0"
STATE_KEYS = ("observation", "achieved_goal", "desired_goal")
TOPDOWN = {name: k for k, name in enumerate(CHANNELS)}


def random_episode(env: gym.Env, seed: int, steps: int = 6) -> list[dict[str, np.ndarray]]:
    """Observations of an episode of allowed candidates drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    observation, _ = env.reset(seed=seed)
    seen = [observation]
    for _ in range(steps):
        allowed = np.flatnonzero(env.get_wrapper_attr("action_masks")())
        observation, _, terminated, truncated, _ = env.step(int(rng.choice(allowed)))
        seen.append(observation)
        if terminated or truncated:
            break
    return seen


def test_state_mode_is_the_default_observation_bit_for_bit():
    default = gym.make(PHASES, family="push")
    state = gym.make(PHASES, family="push", obs_mode="state")
    topdown = gym.make(PHASES, family="push", obs_mode="topdown")
    assert state.observation_space == default.observation_space
    assert list(default.observation_space.spaces) == list(STATE_KEYS[1:2] + STATE_KEYS[2:] + STATE_KEYS[:1])
    for seed in (0, 1):
        a, b, c = (random_episode(env, seed) for env in (default, state, topdown))
        assert len(a) == len(b) == len(c)
        for x, y, z in zip(a, b, c, strict=True):
            assert set(x) == set(y) == set(STATE_KEYS)
            for key in STATE_KEYS:
                assert x[key].tobytes() == y[key].tobytes() == z[key].tobytes()


def test_topdown_pixels_show_the_geometry_at_their_slot_levels():
    scenario = room(start=(0.5, 0.5), heading="+y", clutter={"box": ((1.3, 1.45), (1.4, 1.55))})
    env = make(scenario, obs_mode="topdown", topdown_size=30, topdown_span=3.0)  # 0.1 m a pixel, area = map
    image = env.reset(seed=0)[0]["topdown"]
    assert image.shape == (len(CHANNELS), 30, 30) and image.dtype == np.uint8

    def pixel(x: float, y: float) -> tuple[int, int]:  # (row, col): north up, origin at the area's corner
        return int((3.0 - y) / 0.1), int(x / 0.1)

    tables = image[TOPDOWN["tables"]]
    assert tables[pixel(1.5, 1.5)] == slot_level(0, 6) == 255 and tables[pixel(0.5, 2.5)] == 0
    assert (tables > 0).sum() == 100  # the 1 m table, 10 x 10 pixels
    assert (image[TOPDOWN["obstacles"]] == 0).all()  # the map is the area: no wall, no obstacle
    assert image[TOPDOWN["clutter"]][pixel(1.35, 1.5)] == 255 and (image[TOPDOWN["clutter"]] > 0).sum() == 2
    assert image[TOPDOWN["objects"]][pixel(1.8, 1.2)] == 255 and image[TOPDOWN["goals"]][pixel(1.8, 1.8)] == 255
    assert image[TOPDOWN["objects"]][pixel(1.8, 1.8)] == 0 and not image[TOPDOWN["held"]].any()
    robot = image[TOPDOWN["robot"]]
    assert robot[pixel(0.5, 0.62)] == ROBOT_FRONT and robot[pixel(0.5, 0.38)] == ROBOT_BACK  # heading +y
    assert robot[pixel(0.5, 0.8)] == 0 and robot[pixel(0.1, 0.5)] == 0


def test_topdown_walls_robot_frame_and_slot_levels():
    objects = [
        {"id": "a", "start": [1.25, 1.25], "goal": [1.25, 1.85]},
        {"id": "b", "start": [1.85, 1.25], "goal": [1.85, 1.85]},
    ]
    scenario = room(start=(0.5, 0.5), objects=objects, obstacles={"pillar": ((2.5, 0.2), (2.8, 0.5))})
    env = make(scenario, obs_mode="topdown", topdown_size=60, topdown_span=6.0, topdown_frame="robot")
    image = env.reset(seed=0)[0]["topdown"]
    robot = image[TOPDOWN["robot"]]
    rows, cols = np.nonzero(robot)
    assert abs(rows.mean() - 29.5) < 0.6 and abs(cols.mean() - 29.5) < 0.6  # the base at the centre
    obstacles = image[TOPDOWN["obstacles"]]
    assert obstacles[0, 0] == WALL  # (-2.45, 3.45): outside the area
    assert obstacles[31, 51] == slot_level(1, 13)  # the pillar (2.65, 0.35) is the first obstacle
    assert obstacles[31, 30] == 0  # (0.55, 0.35): free floor
    levels = [image[TOPDOWN["objects"]][22, k] for k in (37, 43)]  # (1.25, 1.25) and (1.85, 1.25)
    assert levels == [slot_level(0, 4), slot_level(1, 4)] == [255, 199]


@pytest.mark.parametrize("env_id", ["FetchCarryPush-v0", PHASES])
@pytest.mark.parametrize("mode", ["state", "topdown", "rgbd"])
def test_both_checkers_pass_in_every_mode(env_id, mode):
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    options = {"camera_size": 48} if mode == "rgbd" else {}
    if env_id == PHASES:
        env = make_phase_env(family="basic", obs_mode=mode, **options)  # PhaseActions, without gym.make's wrappers
    else:
        env = gym.make(env_id, family="basic", obs_mode=mode, **options).unwrapped
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, skip_render_check=True)
        sb3_check_env(env, warn=True, skip_render_check=True)
    assert [str(w.message) for w in caught if "wrapped" not in str(w.message)] == []
    observation, _ = env.reset(seed=3)
    assert env.observation_space.contains(observation)


def test_rgbd_images_come_from_the_world_and_copies_continue_exactly():
    env = gym.make(PHASES, family="push", obs_mode="rgbd", camera_size=40)
    first = random_episode(env, seed=2, steps=2)[-1]
    for key in ("head_rgbd", "overhead_rgbd"):
        assert first[key].shape == (4, 40, 40) and first[key].dtype == np.uint8
        assert first[key][:3].std() > 5  # a picture, not a blank
    overhead_depth = first["overhead_rgbd"][3]
    assert (overhead_depth == 255).mean() > 0.5  # most of the view is floor (255: 2 m below the camera's range)
    assert (overhead_depth < 200).any()  # tables stand 0.7 m above it
    clone = copy.deepcopy(env)
    allowed = np.flatnonzero(env.get_wrapper_attr("action_masks")())
    a = env.step(int(allowed[0]))[0]
    b = clone.step(int(allowed[0]))[0]
    for key in a:
        assert a[key].tobytes() == b[key].tobytes()
    again = gym.make(PHASES, family="push", obs_mode="rgbd", camera_size=40)
    assert random_episode(again, seed=2, steps=2)[-1]["head_rgbd"].tobytes() == first["head_rgbd"].tobytes()


@pytest.mark.parametrize(
    ("options", "error"),
    [
        ({"obs_mode": "pixels"}, ValueError),
        ({"obs_mode": "topdown", "topdown_size": 4}, ValueError),
        ({"obs_mode": "topdown", "topdown_frame": "hand"}, ValueError),
        ({"obs_mode": "topdown", "topdown_span": -1.0}, ValueError),
        ({"obs_mode": "rgbd", "renderer": "vulkan"}, ValueError),
        ({"obs_mode": "topdown", "colour": True}, ValueError),
        ({"obs_mode": "state", "topdown_size": 64}, TypeError),
    ],
)
def test_bad_observation_options_are_refused(options, error):
    with pytest.raises(error):
        gym.make(PHASES, family="basic", **options)


def test_the_egl_renderer_draws_the_world_and_prints_nothing(capfd):
    import importlib.util

    if importlib.util.find_spec("eglRenderer") is None:
        pytest.skip("PyBullet's EGL plugin is not installed here")
    env = gym.make(PHASES, family="push", obs_mode="rgbd", camera_size=32, renderer="egl")
    observation = random_episode(env, seed=2, steps=1)[-1]
    env.close()
    assert observation["overhead_rgbd"][:3].std() > 5 and (observation["overhead_rgbd"][3] < 200).any()  # tables
    assert capfd.readouterr().out == ""
