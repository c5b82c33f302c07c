"""FetchCarryPush-v0's Gymnasium contract: registration, checkers, spaces, masks, rewards, bad input, rendering."""

from __future__ import annotations

import itertools
import json
import math
import warnings
from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest
from sim_worlds import FAR, PUSH_PICK_PLACE_PLAN, action, make, push_pick_place, room

from fetchcarry_env import Capacity, ScenarioError
from fetchcarry_env.actions import Mode
from fetchcarry_env.env import FetchCarryPushEnv
from fetchcarry_env.errors import InputError
from fetchcarry_env.kinematics import INVALID_ACTION_PENALTY, WAIT_COST, travel_cost
from fetchcarry_env.observation import decode
from fetchcarry_env.registration import MAX_EPISODE_STEPS

ENV_ID = "FetchCarryPush-v0"


def unwrapped(env: gym.Env) -> FetchCarryPushEnv:
    return env.unwrapped  # type: ignore[return-value]


# ---------------------------------------------------------------------- registration and checkers
def test_importing_the_package_registers_the_env_with_a_time_limit():
    spec = gym.spec(ENV_ID)
    assert spec.max_episode_steps == MAX_EPISODE_STEPS
    env = gym.make(ENV_ID)
    env.reset(seed=0)
    for _ in range(MAX_EPISODE_STEPS - 1):
        assert not env.step(np.zeros(5, dtype=np.int64))[3]  # refused actions: no progress, no end
    assert env.step(np.zeros(5, dtype=np.int64))[3]  # truncated by the registration's TimeLimit
    env.close()


@pytest.mark.parametrize(
    "kwargs", [{}, {"family": "corridor"}, {"scenario": "spec"}], ids=["default", "family", "fixed"]
)
def test_gymnasium_check_env_passes_without_warnings(kwargs, spec_example):
    if kwargs.get("scenario") == "spec":
        kwargs = {"scenario": spec_example}
    from gymnasium.utils.env_checker import check_env

    env = gym.make(ENV_ID, render_mode="rgb_array", width=64, height=48, **kwargs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    assert [str(w.message) for w in caught] == []
    env.close()


def test_stable_baselines3_check_env_passes_without_warnings():
    from stable_baselines3.common.env_checker import check_env

    env = gym.make(ENV_ID)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped, warn=True)
    assert [str(w.message) for w in caught] == []
    env.close()


class MaskAudit(gym.Wrapper):
    """Counts actions that use a component value the env's mask forbade at that moment."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.masked_actions = 0
        self.steps = 0
        self.bounds = np.concatenate([[0], np.cumsum(env.action_space.nvec)])

    def action_masks(self) -> np.ndarray:
        return self.env.unwrapped.action_masks()

    def step(self, action):
        mask = self.action_masks()
        allowed = [mask[self.bounds[k] + int(a)] for k, a in enumerate(action)]
        self.masked_actions += not all(allowed)
        self.steps += 1
        return self.env.step(action)


def test_maskable_ppo_learns_512_steps_and_respects_the_masks():
    import torch
    from sb3_contrib import MaskablePPO

    torch.set_num_threads(1)
    env = MaskAudit(gym.make(ENV_ID))
    model = MaskablePPO("MultiInputPolicy", env, n_steps=128, batch_size=64, n_epochs=2, seed=0, verbose=0)
    model.learn(total_timesteps=512)
    assert model.num_timesteps >= 512
    assert env.steps >= 512
    assert env.masked_actions == 0  # the flat mask has the layout MaskablePPO reads
    env.close()


# ---------------------------------------------------------------------- arguments
def test_a_scenario_may_be_given_as_a_scenario_a_mapping_or_a_path(tmp_path, spec_example, spec_example_dict):
    path = tmp_path / "scenario.json"
    path.write_text(json.dumps(spec_example_dict))
    observations = []
    for given in (spec_example, spec_example_dict, path, str(path)):
        env = gym.make(ENV_ID, scenario=given)
        observations.append(env.reset(seed=0)[0]["observation"])
        assert unwrapped(env).scenario == spec_example
        env.close()
    assert all(np.array_equal(o, observations[0]) for o in observations)


def test_the_lattice_resolution_is_a_constructor_argument(spec_example):
    coarse = gym.make(ENV_ID, scenario=spec_example, resolution=0.1)
    fine = gym.make(ENV_ID, scenario=spec_example)
    # spec area is 7 m wide: 71 points at 10 cm, 141 at the default 5 cm
    assert list(coarse.action_space.nvec) == [71, 71, 4, 4, 4]
    assert list(fine.action_space.nvec) == [141, 141, 4, 4, 4]
    assert unwrapped(coarse).lattice.resolution == 0.1


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"scenario": "spec", "family": "basic"}, ValueError, "scenario or a family"),
        ({"family": "nope"}, ValueError, "unknown scenario family 'nope'"),
        ({"render_mode": "video"}, ValueError, "render_mode"),
        ({"camera": "fisheye"}, ValueError, "camera"),
        ({"resolution": 0.0}, ValueError, "resolution must be positive"),
        ({"scenario": 42}, TypeError, "Scenario, a mapping or a path"),
    ],
)
def test_bad_arguments_raise_clear_errors(kwargs, error, match, spec_example):
    if kwargs.get("scenario") == "spec":
        kwargs = {**kwargs, "scenario": spec_example}
    with pytest.raises(error, match=match), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # gym.make warns about an unknown render mode before the env refuses it
        gym.make(ENV_ID, **kwargs)


def test_a_scenario_that_breaks_a_rule_raises_scenario_error_naming_rule_and_ids(
    spec_example, spec_example_dict, tmp_path
):
    spec_example_dict["objects"][0]["goal"] = [0.5, 0.5]  # on the floor
    with pytest.raises(ScenarioError, match=r"rule 4 .*'bottle' goal"):
        gym.make(ENV_ID, scenario=spec_example_dict)
    path = tmp_path / "broken.json"
    path.write_text(json.dumps(spec_example_dict))
    with pytest.raises(ScenarioError, match="rule 4"):
        gym.make(ENV_ID, scenario=path)
    # A Scenario built by its constructor is trusted nowhere else: the env checks it too.
    duplicate = replace(spec_example.obstacles[0], id="table_src")
    overlapping = replace(spec_example, obstacles=(*spec_example.obstacles, duplicate))
    with pytest.raises(ScenarioError, match=r"rule 1 .*'table_src'"):
        gym.make(ENV_ID, scenario=overlapping)


def test_a_scenario_that_does_not_fit_the_env_raises_scenario_error(spec_example):
    with pytest.raises(ScenarioError, match="does not fit the observation"):
        gym.make(ENV_ID, scenario=spec_example, capacity=Capacity(clutter=0))
    env = gym.make(ENV_ID, family="basic")  # lattice over the families' extent, -1..6 m
    wide = replace(spec_example, area=replace(spec_example.area, max_x=9.0))
    with pytest.raises(ScenarioError, match="lattice's extent"):
        env.reset(seed=0, options={"scenario": wide})
    with pytest.raises(ValueError, match="unknown reset option"):
        env.reset(seed=0, options={"seed": 3})
    env.close()


def test_human_rendering_needs_a_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(InputError, match="needs a display"):
        gym.make(ENV_ID, render_mode="human")
    headless = gym.make(ENV_ID)
    assert headless.unwrapped.metadata["render_modes"] == ["rgb_array"]  # what check_env will try
    monkeypatch.setenv("DISPLAY", ":99")
    windowed = gym.make(ENV_ID)  # nothing connects before reset: no window is opened here
    assert windowed.unwrapped.metadata["render_modes"] == ["rgb_array", "human"]


# ---------------------------------------------------------------------- actions
@pytest.mark.parametrize(
    ("bad", "match"),
    [
        ([0, 0, 0, 0], r"shape \(5,\)"),
        ([0, 0, 0, 0, 4], r"mode = 4 is not in \[0, 4\)"),
        ([-1, 0, 0, 0, 0], r"x cell = -1"),
        ([0, 500, 0, 0, 0], r"y cell = 500"),
        ([0.5, 0, 0, 0, 0], "integers"),
    ],
)
def test_an_action_outside_the_space_raises_naming_the_component(bad, match, spec_example):
    env = make(spec_example)
    with pytest.raises(ValueError, match=match):
        env.step(np.array(bad))
    env.close()


def test_the_expert_s_phases_are_exactly_expressible():
    """Every phase kind (move, pick, place, push) is one action: a scripted plan runs without a refusal."""
    env = make(push_pick_place())
    infos = [env.step(action(env, *step))[4] for step in PUSH_PICK_PLACE_PLAN]
    assert [i["invalid_action"] for i in infos] == [None, None, None]
    assert infos[-1]["is_success"]
    env.close()


def test_masks_follow_the_maskable_ppo_convention():
    env = make(push_pick_place())
    u = unwrapped(env)
    mask = u.action_masks()
    nx, ny, headings, postures, modes = env.action_space.nvec
    assert mask.dtype == bool and mask.shape == (nx + ny + headings + postures + modes,)
    xs, ys = u.lattice.axis_points(0), u.lattice.axis_points(1)
    radius = u.scenario.robot.radius
    assert np.array_equal(mask[:nx], (xs >= radius - 1e-9) & (xs <= 3.0 - radius + 1e-9))  # the disc fits
    assert np.array_equal(mask[nx : nx + ny], (ys >= radius - 1e-9) & (ys <= 3.0 - radius + 1e-9))
    assert mask[nx + ny : nx + ny + 4].all()
    assert list(mask[nx + ny + 4 : nx + ny + 4 + postures]) == [True, True, False, False]  # two postures
    assert list(mask[-4:]) == [True, True, False, True]  # empty hand: move, pick, push
    env.step(action(env, *PUSH_PICK_PLACE_PLAN[0]))
    env.step(action(env, *PUSH_PICK_PLACE_PLAN[1]))
    assert list(u.action_masks()[-4:]) == [True, False, True, True]  # full hand: move, place, push
    no_clutter = make(room(start=(0.5, 1.5)))
    assert list(unwrapped(no_clutter).action_masks()[-4:]) == [True, True, False, False]  # nothing to push
    env.close()
    no_clutter.close()


def test_every_masked_action_is_refused_with_a_reason_and_moves_nothing():
    env = make(push_pick_place())
    u = unwrapped(env)
    rng = np.random.default_rng(0)
    nvec = env.action_space.nvec
    bounds = np.concatenate([[0], np.cumsum(nvec)])
    refused = 0
    for _ in range(200):
        mask = u.action_masks()
        vector = np.array([rng.integers(n) for n in nvec])
        if all(mask[bounds[k] + vector[k]] for k in range(5)):
            continue
        before = u.state
        _, reward, terminated, _, info = env.step(vector)
        assert info["invalid_action"], vector
        assert u.state == before
        waiting = WAIT_COST * (len(u.scenario.objects) - info["delivered"])  # the objects not at their goals
        assert reward == -(INVALID_ACTION_PENALTY + waiting) and info["travel"] == 0.0 and not terminated
        refused += 1
    assert refused > 100


@pytest.mark.parametrize(
    ("steps", "reason"),
    [
        ([((0.75, 1.5), "+x", FAR, Mode.PLACE)], "place with an empty hand"),
        ([((0.7, 1.2), "+x", FAR, Mode.PICK), ((0.7, 1.2), "+x", FAR, Mode.PICK)], "pick with a full hand"),
        ([((0.1, 1.5), "+x", FAR, Mode.MOVE)], "cell outside the area"),
        ([((0.7, 1.5), "+x", 3, Mode.MOVE)], "no posture 3"),
        ([((0.5, 0.5), "+x", FAR, Mode.PICK)], "nothing to pick within reach"),
        ([((0.75, 1.55), "+x", FAR, Mode.PUSH)], "push stroke not axis-aligned"),
        ([((0.45, 1.5), "+x", FAR, Mode.PUSH)], "heading +x cannot push along -x"),
        ([((0.7, 1.2), "+x", FAR, Mode.PICK), ((0.75, 1.5), "+x", FAR, Mode.PLACE)], "goal of 'bottle' occupied"),
    ],
)
def test_an_impossible_action_does_nothing_and_says_why(steps, reason):
    env = make(push_pick_place())
    u = unwrapped(env)
    for step in steps[:-1]:
        env.step(action(env, *step))
    before = u.state
    _, reward, _, _, info = env.step(action(env, *steps[-1]))
    assert info["invalid_action"].startswith(reason), info["invalid_action"]
    assert u.state == before
    assert reward == -(INVALID_ACTION_PENALTY + WAIT_COST * (len(u.scenario.objects) - info["delivered"]))
    assert info["penalty"] == INVALID_ACTION_PENALTY and info["travel"] == 0.0
    env.close()


def test_a_step_before_reset_raises_reset_needed():
    env = FetchCarryPushEnv()
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(5, dtype=np.int64))
    with pytest.raises(gym.error.ResetNeeded):
        env.action_masks()


# ---------------------------------------------------------------------- observations, rewards, episode end
def test_the_observation_holds_the_whole_geometry_in_the_goal_env_convention():
    env = make(push_pick_place())
    observation, *_ = env.step(action(env, *PUSH_PICK_PLACE_PLAN[0]))
    u = unwrapped(env)
    assert env.observation_space.contains(observation)
    assert set(observation) == {"observation", "achieved_goal", "desired_goal"}
    scenario, state = decode(observation, u.capacity)
    assert scenario.tables[0].rect == u.scenario.tables[0].rect
    assert np.allclose(state.base, u.state.base, atol=1e-6)
    assert np.allclose(state.clutter["clutter_0"], u.state.clutter["block"], atol=1e-6)  # where the push left it
    assert np.allclose(observation["desired_goal"][:3], (1.35, 1.5, 0.8), atol=1e-6)
    env.close()


def test_the_return_is_minus_the_task_cost_and_the_episode_ends_on_delivery():
    """Each step costs its travel and W1 per object not at its goal after it: the return is minus the task cost."""
    env = make(push_pick_place())
    u = unwrapped(env)
    bases = [u.state.base]
    results = []
    for step in PUSH_PICK_PLACE_PLAN:
        results.append(env.step(action(env, *step)))
        bases.append(u.state.base)
    travels = [travel_cost(a, b) for a, b in itertools.pairwise(bases)]
    rewards = [r[1] for r in results]
    assert rewards[:2] == pytest.approx([-(t + WAIT_COST) for t in travels[:2]])  # one object, not yet delivered
    assert rewards[2] == pytest.approx(-travels[2])  # delivered by this step
    assert [r[2] for r in results] == [False, False, True]  # terminated when delivered with an empty hand
    info = results[-1][4]
    assert info["is_success"] and info["delivered"] == 1 and info["collisions"] == 0
    assert info["travel_cost"] == pytest.approx(sum(travels))
    assert info["task_cost"] == pytest.approx(-sum(rewards)) == pytest.approx(sum(travels) + 2 * WAIT_COST)
    assert info["path_length"] == pytest.approx(sum(math.dist(a, b) for a, b in itertools.pairwise(bases)))
    assert info["invalid_action"] is None
    env.close()


def test_compute_reward_works_on_a_batch_and_agrees_with_step():
    env = make(push_pick_place())
    achieved, desired, infos, rewards = [], [], [], []
    for step in [*PUSH_PICK_PLACE_PLAN[:1], ((0.5, 0.5), "+y", FAR, Mode.PLACE), *PUSH_PICK_PLACE_PLAN[1:]]:
        observation, reward, _, _, info = env.step(action(env, *step))
        achieved.append(observation["achieved_goal"])
        desired.append(observation["desired_goal"])
        infos.append(info)
        rewards.append(reward)
    u = unwrapped(env)
    batch = u.compute_reward(np.stack(achieved), np.stack(desired), np.array(infos, dtype=object))
    assert batch.shape == (4,)
    assert np.allclose(batch, rewards)
    assert u.compute_reward(achieved[-1], desired[-1], infos[-1]) == pytest.approx(rewards[-1])
    # HER relabels the desired goal: an object away from the relabelled goal costs W1 more.
    relabelled = u.compute_reward(achieved[-1], infos[-1]["previous_achieved_goal"], infos[-1])
    assert relabelled == pytest.approx(rewards[-1] - WAIT_COST)
    env.close()


# ---------------------------------------------------------------------- rendering
def test_rgb_array_frames_show_the_world_from_both_cameras(spec_example):
    frames = {}
    for camera in ("perspective", "top_down"):
        env = gym.make(ENV_ID, scenario=spec_example, render_mode="rgb_array", camera=camera, width=80, height=60)
        with pytest.raises(gym.error.ResetNeeded):
            env.render()
        env.reset(seed=0)
        frame = env.render()
        assert frame.shape == (60, 80, 3) and frame.dtype == np.uint8
        assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 4  # floor, tables, objects: not a blank image
        frames[camera] = frame
        env.close()
    assert not np.array_equal(frames["perspective"], frames["top_down"])


def test_render_without_a_render_mode_warns_and_returns_none(spec_example):
    env = make(spec_example)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.unwrapped.render() is None
    env.close()


def test_the_env_docstring_is_its_specification():
    doc = FetchCarryPushEnv.__doc__
    headings = [
        "Description",
        "Action Space",
        "Observation Space",
        "Rewards",
        "Starting State",
        "Episode End",
        "Arguments",
        "Version History",
    ]
    positions = [doc.index(f"## {h}") for h in headings]
    assert positions == sorted(positions)
