"""Phase recording projects an expert move no candidate expresses onto the nearest allowed move candidate."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import fetchcarry_env  # noqa: F401  (registers the env ids)
from benchmarks.studies.projection import check_projection, summarise_projection
from fetchcarry_env.actions import Mode
from fetchcarry_env.phase_env import PhaseActions
from training.policies.phase_expert import PROJECTED_INFO, UNEXPRESSIBLE, PhaseExpert, nearest_move
from training.rollout import run_episode

UNEXPRESSIBLE_SEED = 0  # basic seed 0: its expert made a move no candidate expresses (the episode used to end there)
MOVE_FIRST_SEED = 1  # basic seed 1: the expert's first action is a move


def _env() -> gym.Env:
    return gym.make("FetchCarryPushPhases-v0", family="basic")


def test_projected_episode_succeeds_with_allowed_actions_and_costs_about_the_experts() -> None:
    env = _env()
    record = run_episode(env, PhaseExpert(env, time_limit=10.0), UNEXPRESSIBLE_SEED, record_masks=True)
    env.close()
    assert record.figures.outcome == "delivered"
    assert record.infos[PROJECTED_INFO].sum() >= 1
    masks = record.infos["action_mask"]
    assert masks[np.arange(len(record.actions)), record.actions].all()
    assert record.figures.replans >= 1  # the expert planned again from where the projected move left the base
    (row,) = check_projection("basic", [UNEXPRESSIBLE_SEED])
    assert row.success and row.expert_success and row.projected >= 1
    assert abs(row.cost / row.expert_cost - 1.0) < 0.05
    summary = summarise_projection([row])
    assert summary["success"] == 1.0 and summary["projected_per_episode"] == row.projected


def _off_the_candidates() -> tuple[gym.Env, object, np.ndarray, np.ndarray]:
    """A reset env, its candidate table, its allowed moves, and a move one cell past the last of them."""
    env = _env()
    env.reset(seed=UNEXPRESSIBLE_SEED)
    table = env.get_wrapper_attr("table")
    moves = np.flatnonzero(table.mask & (table.actions[:, 4] == int(Mode.MOVE)))
    off = table.actions[moves[-1]].copy()
    off[1] += 1
    return env, table, moves, off


@pytest.mark.parametrize("rule", ["end", "detour"])
def test_nearest_move_rules_give_an_allowed_move(rule: str) -> None:
    env, table, _, off = _off_the_candidates()
    index = nearest_move(env, off, rule)
    assert index is not None and table.mask[index] and table.actions[index, 4] == int(Mode.MOVE)
    with pytest.raises(ValueError):
        nearest_move(env, off, "farthest")
    env.close()


def test_an_inexpressible_action_other_than_a_move_still_ends_the_episode(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(PhaseActions, "index_of", lambda self, action: None)  # nothing is expressible
    env = _env()
    record = run_episode(env, PhaseExpert(env, time_limit=10.0), MOVE_FIRST_SEED, record_masks=True)
    env.close()
    assert record.figures.outcome == UNEXPRESSIBLE and record.truncations[-1]
    masks = record.infos["action_mask"]
    allowed = masks[np.arange(len(record.actions)), record.actions]
    assert len(allowed) >= 2 and allowed[:-1].all() and not allowed[-1]  # projected moves, then the pick
    assert record.infos[PROJECTED_INFO][1:-1].all() and not record.infos[PROJECTED_INFO][-1]


LIVELOCK_SEED = 57  # training seed 57 (basic-684166): projected moves went back and forth for 50 steps


def test_projected_moves_never_go_back_to_a_cell_they_left() -> None:
    """The expert's move to (64, 51) had allowed ends at (60, 51) and (61, 51) only nearby: with nothing else
    changed, each projection undid the last, and the episode was cut off without a delivery. It delivers now."""
    env = gym.make("FetchCarryPushPhases-v0", family="training")
    record = run_episode(env, PhaseExpert(env, time_limit=10.0), LIVELOCK_SEED, record_masks=True)
    env.close()
    assert record.figures.outcome == "delivered" and len(record.actions) <= 6
    assert record.infos[PROJECTED_INFO].sum() >= 2


def test_a_move_that_would_only_go_back_is_left_out() -> None:
    env, table, moves, off = _off_the_candidates()
    first = nearest_move(env, off)
    cell = tuple(int(v) for v in table.actions[first, :2])
    second = nearest_move(env, off, avoid={cell})
    assert second is not None and tuple(int(v) for v in table.actions[second, :2]) != cell
    every = {tuple(int(v) for v in table.actions[m, :2]) for m in moves}
    assert nearest_move(env, off, avoid=every) is None
    env.close()
