"""FetchCarryPushPhases-v0: Discrete(K) candidate phases whose masks the env's own rules decide."""

from __future__ import annotations

import copy
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest

import fetchcarry_env.phases as phases
from fetchcarry_env.actions import Action, Mode
from fetchcarry_env.kinematics import INVALID_ACTION_PENALTY, WAIT_COST
from fetchcarry_env.phase_env import PhaseActions
from fetchcarry_env.phases import KINDS, PhaseLayout, enumerate_phases
from fetchcarry_env.registration import MAX_EPISODE_STEPS
from fetchcarry_env.rules import check_action, move_stop
from fetchcarry_env.scenario import DEFAULT_POSTURES, Posture

ENV_ID = "FetchCarryPushPhases-v0"
FAMILIES = ("basic", "push", "corridor", "multi-2")


def random_walk(env: gym.Env, seed: int, steps: int):
    """Yield ``(env, mask)`` at each state of a random masked walk (resets at episode ends)."""
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    for _ in range(steps):
        mask = env.get_wrapper_attr("action_masks")()
        yield env, mask
        _obs, _r, terminated, truncated, _info = env.step(int(rng.choice(np.flatnonzero(mask))))
        if terminated or truncated:
            env.reset()


# ---------------------------------------------------------------------- registration, spaces, checkers
def test_registered_with_the_env_time_limit_and_a_discrete_space():
    env = gym.make(ENV_ID, family="basic")
    assert gym.spec(ENV_ID).max_episode_steps == MAX_EPISODE_STEPS
    layout = env.get_wrapper_attr("layout")
    assert env.action_space == gym.spaces.Discrete(layout.size)
    assert layout.size == sum(int(np.prod(layout.shape(kind))) for kind in KINDS) == 4080  # the documented K
    assert env.observation_space == gym.make("FetchCarryPush-v0").observation_space
    env.reset(seed=0)
    for _ in range(MAX_EPISODE_STEPS - 1):
        assert not env.step(0)[3]  # candidate 0 is a pick around an empty object slot here: refused
    assert env.step(0)[3]


def test_gymnasium_and_sb3_check_env_pass():
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = PhaseActions(gym.make("FetchCarryPush-v0", family="basic").unwrapped)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, skip_render_check=True)
        sb3_check_env(env, warn=True, skip_render_check=True)
    messages = [str(w.message) for w in caught if "wrapped" not in str(w.message)]
    assert messages == []


def test_layout_numbers_every_candidate_once():
    layout = PhaseLayout()
    seen = set()
    for kind in KINDS:
        for coords in np.ndindex(*layout.shape(kind)):
            index = layout.index(kind, *coords)
            assert layout.describe(index).kind == kind
            seen.add(index)
    assert seen == set(range(layout.size))
    with pytest.raises(ValueError):
        layout.describe(layout.size)


def test_default_window_holds_every_pose_within_reach_of_the_default_postures():
    layout = PhaseLayout.for_postures(DEFAULT_POSTURES, 0.05)
    assert (layout.forward, layout.lateral) == ((7, 14), 1)
    wide = PhaseLayout.for_postures((Posture("long", (0.30, 1.0), (-0.2, 0.1)),), 0.05)
    assert (wide.forward, wide.lateral) == ((6, 20), 4)


# ---------------------------------------------------------------------- exact masks
@pytest.mark.parametrize("family", FAMILIES)
def test_every_allowed_candidate_is_accepted_by_the_rules_on_its_item_without_contact(family):
    env = gym.make(ENV_ID, family=family)
    layout = env.get_wrapper_attr("layout")
    for walker, mask in random_walk(env, seed=3, steps=25):
        base = walker.unwrapped
        table = walker.get_wrapper_attr("table")
        assert mask.any()
        actions = [tuple(table.actions[k]) for k in np.flatnonzero(mask)]
        assert len(set(actions)) == len(actions)  # one to one
        for k in np.flatnonzero(mask):
            action = Action.from_array(table.actions[k])
            phase = check_action(base.scenario, base.state, base.lattice, action)
            assert not isinstance(phase, str), (k, phase)
            assert move_stop(base.scenario, base.state.base, phase.base)[1] is None
            candidate = layout.describe(int(k))
            if candidate.kind in ("pick", "place"):
                assert phase.target == base.scenario.objects[candidate.slot].id
                assert phase.mode == (Mode.PICK if candidate.kind == "pick" else Mode.PLACE)
            elif candidate.kind == "push":
                assert phase.target == base.scenario.clutter[candidate.slot].id
            else:
                assert action.mode == Mode.MOVE and action.heading == base.state.heading
            assert walker.get_wrapper_attr("index_of")(table.actions[k]) == k


@pytest.mark.parametrize("family", ["push", "multi-2"])
def test_an_allowed_candidate_is_never_refused_and_never_stops_at_a_contact(family):
    env = gym.make(ENV_ID, family=family)
    rng = np.random.default_rng(1)
    env.reset(seed=1)
    for _ in range(60):
        mask = env.get_wrapper_attr("action_masks")()
        _obs, _r, terminated, truncated, info = env.step(int(rng.choice(np.flatnonzero(mask))))
        assert info["invalid_action"] is None and info["contact"] is None and not info["masked"]
        if terminated or truncated:
            env.reset()


def test_a_masked_candidate_is_refused_and_changes_nothing():
    env = gym.make(ENV_ID, family="basic")
    observation, _ = env.reset(seed=2)
    mask = env.get_wrapper_attr("action_masks")()
    masked = int(np.flatnonzero(~mask)[0])
    after, reward, _terminated, _truncated, info = env.step(masked)
    assert reward == -(INVALID_ACTION_PENALTY + WAIT_COST * (len(env.unwrapped.scenario.objects) - info["delivered"]))
    assert info["masked"] and f"candidate {masked}" in info["invalid_action"]
    for key in observation:
        np.testing.assert_array_equal(after[key], observation[key])
    with pytest.raises(ValueError):
        env.step(env.action_space.n)
    with pytest.raises(ValueError):
        env.step(np.array([1, 2]))


def test_the_mask_follows_the_rules_not_a_copy_of_them(monkeypatch):
    """The env's rules decide the mask: pushes made while holding (the paper's push-aside) are offered, and a
    change of the rules (here: every push refused) changes the mask by itself."""
    env = gym.make(ENV_ID, family="push")
    env.reset(seed=3)
    base = env.unwrapped
    layout = env.get_wrapper_attr("layout")
    goal_table = base.scenario.table_under_rect(base.scenario.clutter[0].rect)  # beside it, pushes are one move away
    corner = phases.waypoint_cell(base.lattice, goal_table.rect, base.scenario.robot.radius, 0, 0, 0)
    beside = base.lattice.point(*corner)
    holding = type(base.state)(beside, base.state.heading, "bottle", base.state.objects, base.state.clutter)
    pushes = np.r_[layout.kind_slice("push"), layout.kind_slice("approach")]
    assert enumerate_phases(layout, base.scenario, holding, base.lattice).mask[pushes].any()

    original = check_action

    def refusing_pushes(scenario, state, lattice, action):
        return "pushes refused" if action.mode == Mode.PUSH else original(scenario, state, lattice, action)

    monkeypatch.setattr(phases, "check_action", refusing_pushes)
    assert not enumerate_phases(layout, base.scenario, holding, base.lattice).mask[pushes].any()


# ---------------------------------------------------------------------- the expert through the interface
def test_the_expert_acts_through_the_interface():
    from expert import ExpertPolicy

    env = gym.make(ENV_ID, family="basic")
    expert = ExpertPolicy(env, interface="env")  # the plan's env actions, mapped here
    observation, _ = env.reset(seed=4)
    for step in range(10):
        action, _ = expert.predict(observation, episode_start=step == 0)
        index = env.get_wrapper_attr("index_of")(action)
        if index is None:
            observation, _r, terminated, _t, info = env.get_wrapper_attr("step_env_action")(action)
        else:
            np.testing.assert_array_equal(env.get_wrapper_attr("env_action")(index), action)
            observation, _r, terminated, _t, info = env.step(index)
        if terminated:
            break
    assert info["is_success"]


# ---------------------------------------------------------------------- determinism and copies
def test_same_seed_same_masks_and_episode_bit_for_bit():
    def run():
        env = gym.make(ENV_ID, family="push")
        out = []
        for walker, mask in random_walk(env, seed=7, steps=12):
            out.append((mask.copy(), walker.unwrapped.state))
        return out

    first, second = run(), run()
    for (m1, s1), (m2, s2) in zip(first, second, strict=True):
        np.testing.assert_array_equal(m1, m2)
        assert s1 == s2


@pytest.mark.parametrize("clone", [copy.deepcopy, lambda e: pickle.loads(pickle.dumps(e))], ids=["deepcopy", "pickle"])
def test_copies_continue_exactly(clone):
    env = gym.make(ENV_ID, family="basic")
    env.reset(seed=5)
    twin = clone(env)
    rng = np.random.default_rng(0)
    for _ in range(5):
        mask = env.get_wrapper_attr("action_masks")()
        np.testing.assert_array_equal(mask, twin.get_wrapper_attr("action_masks")())
        k = int(rng.choice(np.flatnonzero(mask)))
        a, b = env.step(k), twin.step(k)
        np.testing.assert_array_equal(a[0]["observation"], b[0]["observation"])
        assert a[1] == b[1]
        if a[2]:
            break


def test_phase_actions_refuses_other_envs():
    with pytest.raises(TypeError):
        PhaseActions(gym.make("CartPole-v1"))
