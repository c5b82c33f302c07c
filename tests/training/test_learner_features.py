"""The BC learner's options: relative features for the flat MLP, and not repeating a choice in a state met again."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from fetchcarry_env.observation import FIELDS, Capacity, observation_layout, observation_size
from fetchcarry_env.phases import PhaseLayout
from training.envs import make_env
from training.learners.bc import BCConfig, BCPolicy, Demonstrations, fit
from training.learners.encoders import (
    RELATIVE_COLUMNS,
    FlatMLP,
    PushScores,
    RelativeFeatures,
    SetScorer,
    build_network,
)


@pytest.fixture(scope="module")
def push_state() -> tuple[np.ndarray, np.ndarray]:
    env = make_env("phases", family="push")
    observation, _ = env.reset(seed=3)
    mask = env.get_wrapper_attr("action_masks")()
    env.close()
    return np.asarray(observation["observation"], np.float32), mask


def test_relative_features_are_differences_to_the_base_and_the_goals(push_state):
    flat, _ = push_state
    capacity = Capacity()
    features = RelativeFeatures(capacity)
    out = features(torch.as_tensor(flat[None]))[0].numpy()
    assert out.shape == (len(flat) + RelativeFeatures.extra_width(capacity),)
    np.testing.assert_array_equal(out[: len(flat)], flat)  # the vector itself comes first
    layout = observation_layout(capacity)
    base = flat[layout["robot"]][:2]
    first = flat[layout["object_0"]]  # present, x, y, z, goal x, goal y, ...
    extra = out[len(flat) :]
    np.testing.assert_allclose(extra[:6], [*(first[1:3] - base), *(first[4:6] - base), *(first[4:6] - first[1:3])])
    assert not extra[6:12].any()  # the second object slot is empty: its features are zero
    clutter = flat[layout["clutter_0"]]
    start = 6 * capacity.objects
    np.testing.assert_allclose(extra[start : start + 4], clutter[1:5] - np.tile(base, 2), atol=1e-6)
    between = extra[-2 * capacity.clutter * capacity.objects :].reshape(capacity.clutter, capacity.objects, 2)
    centre = (clutter[1:3] + clutter[3:5]) / 2
    np.testing.assert_allclose(between[0, 0], centre - first[4:6], atol=1e-6)
    assert not between[:, 1:].any()


def test_flat_mlp_with_relative_features_trains_and_loads(push_state):
    flat, mask = push_state
    allowed = np.flatnonzero(mask)
    moved = flat.copy()
    moved[observation_layout(Capacity())["robot"].start] += 0.5  # the base half a metre further along x
    observations = np.stack([flat, moved] * 4)
    labels = np.array([allowed[0], allowed[-1]] * 4)
    demos = Demonstrations(observations, np.repeat(mask[None], 8, 0), labels)
    config = BCConfig(epochs=100, hidden=32, relative=True)
    network, _ = fit(demos, config, Capacity())
    assert isinstance(network, FlatMLP) and isinstance(network.features, RelativeFeatures)
    again = build_network(config, Capacity(), mask.size, torch.zeros(1, flat.size))
    again.load_state_dict(network.state_dict())
    policy = BCPolicy(again, config, Capacity())
    np.testing.assert_array_equal(policy.predict(observations[:2], action_masks=demos.masks[:2])[0], labels[:2])


def test_set_encoder_with_relative_columns_sees_the_base_move(push_state):
    flat, _ = push_state
    capacity = Capacity()
    network = build_network(
        BCConfig(encoder="set", hidden=32, relative=True), capacity, 4080, torch.zeros(1, flat.size)
    )
    assert network.embed["object"].in_features == len(FIELDS["object"]) + len(RELATIVE_COLUMNS["object"])
    moved = flat.copy()
    moved[observation_layout(capacity)["robot"].start] += 0.5
    with torch.no_grad():
        scores = network(torch.as_tensor(np.stack([flat, moved])))
    assert scores.shape == (2, 4080) and not torch.equal(scores[0], scores[1])
    bigger = Capacity(objects=6, clutter=10)
    SetScorer(bigger, PhaseLayout.for_postures(capacity=bigger), width=32, relative=True).load_state_dict(
        network.state_dict()
    )  # still independent of the slot counts


class _Fixed(torch.nn.Module):
    """Scores that prefer lower candidate numbers: the choice is the first allowed one."""

    def forward(self, flat: torch.Tensor) -> torch.Tensor:
        return -torch.arange(4, dtype=torch.float32).expand(len(flat), 4)


def test_avoid_repeats_tries_another_candidate_in_a_state_met_again():
    state, other = np.zeros(3, np.float32), np.ones(3, np.float32)
    mask = np.array([True, True, False, True])
    plain = BCPolicy(_Fixed(), BCConfig(avoid_repeats=False), Capacity())
    assert [int(plain.predict(state, action_masks=mask)[0]) for _ in range(3)] == [0, 0, 0]
    policy = BCPolicy(_Fixed(), BCConfig(avoid_repeats=True), Capacity())
    choices = [int(policy.predict(state, action_masks=mask)[0]) for _ in range(4)]
    assert choices == [0, 1, 3, 0]  # the best not yet chosen here; once all were, the best again
    assert int(policy.predict(other, action_masks=mask)[0]) == 0  # another state has its own memory
    policy.predict(state, action_masks=mask, episode_start=np.array([True]))
    assert int(policy.predict(state, action_masks=mask)[0]) == 1  # a new episode forgot the old one
    policy.reset()
    assert int(policy.predict(state, action_masks=mask)[0]) == 0
    batch = policy.predict(np.stack([state, state]), action_masks=np.stack([mask, mask]))[0]
    assert batch.tolist() == [0, 0]  # batched calls have no memory


class _Ranked(torch.nn.Module):
    """Scores that rank three candidates first: ``ranked[0]`` above ``ranked[1]`` above ``ranked[2]``."""

    def __init__(self, size: int, ranked: list[int]) -> None:
        super().__init__()
        self.scores = torch.full((size,), -10.0)
        self.scores[ranked] = torch.tensor([3.0, 2.0, 1.0])

    def forward(self, flat: torch.Tensor) -> torch.Tensor:
        return self.scores.expand(len(flat), -1)


def _at(x: float, y: float) -> np.ndarray:
    flat = np.zeros(observation_size(Capacity()), np.float32)
    flat[observation_layout(Capacity())["robot"]] = [x, y, 0.3, 1, 0, 0, 0]
    return flat


@pytest.mark.parametrize("returns", [False, True])
def test_avoid_returns_cuts_a_round_of_moves_one_step_early(returns: bool):
    layout = PhaseLayout.for_postures(capacity=Capacity())
    a, b = layout.index("approach", 0, 0, 0, 0, 0), layout.index("waypoint", 0, 0, 0, 0)
    c = layout.index("pick", 0, 0, 0, 0)
    config = BCConfig(avoid_repeats=True, avoid_returns=returns)
    policy = BCPolicy(_Ranked(layout.size, [a, b, c]), config, Capacity())

    def allowed(*candidates: int) -> np.ndarray:
        mask = np.zeros(layout.size, bool)
        mask[list(candidates)] = True
        return mask

    start, at_a, at_b = _at(0, 0), _at(1, 0), _at(2, 0)  # the same world, the base elsewhere
    assert int(policy.predict(start, action_masks=allowed(a, b, c))[0]) == a  # the move to A
    assert int(policy.predict(at_a, action_masks=allowed(b, c))[0]) == b  # (a move to A from A goes nowhere)
    # At B, a leads back to A: with the memory of where a went, it is left out before the round closes.
    assert int(policy.predict(at_b, action_masks=allowed(a, c))[0]) == (c if returns else a)
    policy.reset()
    assert int(policy.predict(at_b, action_masks=allowed(a, c))[0]) == a  # a new episode knows no ends


def test_avoid_returns_knows_ends_per_world_and_needs_the_phase_layout():
    layout = PhaseLayout.for_postures(capacity=Capacity())
    a, b = layout.index("approach", 0, 0, 0, 0, 0), layout.index("waypoint", 0, 0, 0, 0)
    push = layout.index("push", 0, 0, 0, 0)
    policy = BCPolicy(_Ranked(layout.size, [a, b, push]), BCConfig(avoid_returns=True), Capacity())
    both = np.zeros(layout.size, bool)
    both[[a, b, push]] = True
    start, at_a = _at(0, 0), _at(1, 0)
    assert int(policy.predict(start, action_masks=both)[0]) == a
    moved = at_a.copy()
    moved[observation_layout(Capacity())["clutter_0"]] = [1, 3, 3, 3.2, 3.2, 0.1]  # another world: a piece appeared
    assert int(policy.predict(moved, action_masks=both)[0]) == a  # a's end in this world is unknown
    with pytest.raises(ValueError, match="phase layout"):
        BCPolicy(_Ranked(10, [0, 1, 2]), BCConfig(avoid_returns=True), Capacity()).predict(
            start, action_masks=np.ones(10, bool)
        )


@pytest.mark.parametrize("rule", [False, True])
def test_push_after_approach_leaves_out_a_second_approach_in_a_row(rule: bool):
    layout = PhaseLayout.for_postures(capacity=Capacity())
    first, second = layout.index("approach", 0, 0, 0, 0, 0), layout.index("approach", 1, 2, 1, 3, 1)
    push = layout.index("push", 0, 0, 0, 0)
    config = BCConfig(avoid_repeats=False, push_after_approach=rule)
    policy = BCPolicy(_Ranked(layout.size, [first, second, push]), config, Capacity())
    mask = np.zeros(layout.size, bool)
    mask[[first, second, push]] = True
    assert int(policy.predict(_at(0, 0), action_masks=mask)[0]) == first
    after = mask.copy()
    after[first] = False  # where the base now stands
    assert int(policy.predict(_at(1, 0), action_masks=after)[0]) == (push if rule else second)
    only_approaches = after.copy()
    only_approaches[push] = False
    policy.reset()
    policy.predict(_at(0, 0), action_masks=mask)
    assert int(policy.predict(_at(1, 0), action_masks=only_approaches)[0]) == second  # nothing else is allowed


def _one_goal_one_clutter() -> np.ndarray:
    """An observation vector with one object (goal at 1, 1, radius 0.035) and one 0.2 m piece of clutter on it."""
    capacity = Capacity()
    layout = observation_layout(capacity)
    flat = np.zeros(layout["obstacles"].stop, np.float32)
    flat[layout["object_0"]] = [1, 0.0, 0.0, 0.8, 1.0, 1.0, 0.8, 0.035, 0.2, 0, 0]
    flat[layout["clutter_0"]] = [1, 0.9, 0.95, 1.1, 1.15, 0.1]  # centre (1.0, 1.05): covers the goal
    return flat


def test_push_scores_margins_follow_the_shifted_clutter():
    capacity = Capacity()
    scores = PushScores(capacity, PhaseLayout.for_postures(capacity=capacity))
    after, before, present = scores.margins(torch.as_tensor(_one_goal_one_clutter()[None]))
    assert present[0].tolist() == [True] + [False] * (capacity.clutter - 1)
    assert before[0, 0] == pytest.approx(-0.035)  # the goal lies inside the rectangle
    # Along +x by s cells the rectangle's min x is 0.9 + 0.05 s: clear of the goal disc once 0.05 s - 0.1 > 0.035.
    np.testing.assert_allclose(after[0, 0, 0].numpy(), [-0.035, -0.035, 0.015, 0.065, 0.115, 0.165], atol=1e-6)
    # Along +y the rectangle leaves the goal's side: min y 0.95 + 0.05 s against the goal's 1.0.
    np.testing.assert_allclose(after[0, 0, 1, :3].numpy(), [-0.035, 0.015, 0.065], atol=1e-6)


def test_push_scores_add_to_the_push_and_approach_candidates_only():
    capacity = Capacity()
    flat = _one_goal_one_clutter()
    config = BCConfig(hidden=16, relative=True, push_scores=True)
    network = build_network(config, capacity, 4080, torch.as_tensor(np.stack([flat, flat * 0.9])))
    assert isinstance(network.push, PushScores)
    layout = PhaseLayout.for_postures(capacity=capacity)
    extra = network.push(torch.as_tensor(flat[None]))[0]
    others = np.ones(layout.size, bool)
    others[layout.kind_slice("push")] = others[layout.kind_slice("approach")] = False
    assert not extra[torch.as_tensor(others)].any()
    pushes = extra[layout.kind_slice("push")].reshape(layout.shape("push"))
    assert not pushes[1:].any()  # empty clutter slots score nothing
    assert pushes[0, 0, 0, 0] != pushes[0, 0, 0, 3]  # strokes that do and do not clear differ
    again = build_network(config, capacity, 4080, torch.zeros(1, flat.size))
    again.load_state_dict(network.state_dict())
    torch.testing.assert_close(again(torch.as_tensor(flat[None])), network(torch.as_tensor(flat[None])))


def test_a_run_folder_from_before_the_new_fields_loads_as_it_was(push_state, tmp_path):
    import json

    from training import load_policy
    from training.learners.bc import train_bc

    flat, mask = push_state
    demos = Demonstrations(flat[None], mask[None], np.flatnonzero(mask)[:1])
    train_bc(demos, BCConfig(epochs=1, hidden=8, relative=False, avoid_repeats=False), Capacity(), out=tmp_path / "old")
    file = tmp_path / "old" / "config.json"
    saved = json.loads(file.read_text())
    for name in ("relative", "push_scores", "avoid_repeats"):
        del saved["config"][name]  # a config.json written before these fields existed
    file.write_text(json.dumps(saved))
    policy = load_policy(tmp_path / "old")
    assert not policy.config.relative and not policy.config.avoid_repeats and not policy.config.push_scores
    assert BCConfig().relative and BCConfig().avoid_repeats  # new runs get the new defaults


def test_the_policy_sets_subnormal_weights_to_zero():
    from training.learners.bc import flush_subnormal

    network = torch.nn.Linear(3, 2)
    with torch.no_grad():
        network.weight[0, 0] = 1e-40  # subnormal in float32
        network.weight[0, 1] = 2e-38  # normal
    BCPolicy(network, BCConfig(), Capacity())
    assert network.weight[0, 0].item() == 0 and network.weight[0, 1].item() == pytest.approx(2e-38)
    assert flush_subnormal(network) is network
