"""A run folder at another capacity: the set encoder acts at the env's, a flat network refuses it."""

from __future__ import annotations

import pytest
import torch

from fetchcarry_env.observation import Capacity
from training.envs import make_env
from training.learners.bc import BCConfig, record_demonstrations, train_bc
from training.learners.imitation import CapacityMismatch
from training.learners.runs import load_policy, read_config
from training.rollout import run_episode


@pytest.fixture(scope="module")
def small_demos():
    torch.set_num_threads(1)
    return record_demonstrations("objects-2", range(6))


def test_set_encoder_trained_at_four_objects_acts_on_six(small_demos, tmp_path):
    train_bc(small_demos, BCConfig(encoder="set", epochs=3, hidden=16), Capacity(), out=tmp_path / "set")
    assert read_config(tmp_path / "set")["capacity"] == {"objects": 4, "clutter": 8, "tables": 6, "obstacles": 12,
                                                         "postures": 4}  # fmt: skip
    env = make_env("phases", family="objects-6")
    policy = load_policy(tmp_path / "set", env)
    assert policy.capacity == env.unwrapped.capacity == Capacity(objects=6)
    observation, _ = env.reset(seed=3)
    masks = env.get_wrapper_attr("action_masks")()
    action, _ = policy.predict(observation, action_masks=masks)
    assert masks[int(action)]  # an allowed candidate of the six-object numbering
    record = run_episode(env, policy, 3)
    assert record.figures.steps > 1 and record.figures.invalid_actions == 0
    at_four = load_policy(tmp_path / "set")  # without an env: the capacity it was trained at
    assert at_four.capacity == Capacity()


def test_flat_network_refuses_another_capacity_with_a_clear_message(small_demos, tmp_path):
    train_bc(small_demos, BCConfig(encoder="mlp", epochs=2, hidden=16), Capacity(), out=tmp_path / "mlp")
    with pytest.raises(CapacityMismatch, match=r"flat network \(mlp\) trained at capacity .*'objects': 4.*set encoder"):
        load_policy(tmp_path / "mlp", make_env("phases", family="objects-6"))
    same = load_policy(tmp_path / "mlp", make_env("phases", family="objects-2"))
    assert same.capacity == Capacity() and bool(torch.isfinite(same.network.mean).all())
