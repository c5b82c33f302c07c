"""The fast candidate mask (fetchcarry_env.candidate_mask) is the reference's (phases.enumerate_phases), exactly.

Every test compares whole tables, the mask, every env action and the lookup, on states
reached by random masked steps from seeded resets of every family, with a bias
towards picks, places and pushes (pushes jam against neighbours and walls there) and
some refused candidates; and the region bits of many points at once against the scalar
rules' on lattice points and on hand points within float noise of a side.
``python tests/env/test_phase_mask_fast.py --states N`` runs the walk comparison longer
(not collected by pytest: the module runs as a script).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

import gymnasium as gym
import numpy as np
import pytest

import fetchcarry_env  # noqa: F401  (registers the ids)
from fetchcarry_env.actions import Mode
from fetchcarry_env.candidate_mask import FastPhases
from fetchcarry_env.families import FAMILY_NAMES
from fetchcarry_env.phases import PhaseTable, enumerate_phases
from fetchcarry_env.regions import (
    cells_bits,
    grid_bits,
    hand_bits,
    hands_bits,
    octagon_bits,
    octagon_rows,
    side_bits,
    side_rows,
)
from fetchcarry_env.rules import move_blockers

ENV_ID = "FetchCarryPushPhases-v0"
STATES_PER_FAMILY = 90  # x 11 families, plus the refused steps' states


@dataclass
class Tally:
    """How much a comparison covered."""

    states: int = 0
    candidates: int = 0
    allowed: int = 0
    pushes: int = 0  # push steps taken
    jams: int = 0  # pushes whose piece stopped short
    refused: int = 0  # refused steps taken


def same_table(got: PhaseTable, want: PhaseTable) -> bool:
    return (
        np.array_equal(got.mask, want.mask) and np.array_equal(got.actions, want.actions) and got.lookup == want.lookup
    )


def _choose(rng: np.random.Generator, mask: np.ndarray, actions: np.ndarray, size: int, pushy: bool) -> int:
    """A candidate: sometimes a masked one, often a pick, place or push when one is allowed, else any allowed.

    ``pushy``: a push whenever one is allowed, seven times in ten, and never a masked one.
    """
    allowed = np.flatnonzero(mask)
    if pushy:
        pushes = allowed[actions[allowed, 4] == Mode.PUSH]
        return int(rng.choice(pushes)) if pushes.size and rng.random() < 0.7 else int(rng.choice(allowed))
    if rng.random() < 0.06:
        return int(rng.integers(size))
    acting = allowed[actions[allowed, 4] != Mode.MOVE]
    if acting.size and rng.random() < 0.5:
        return int(rng.choice(acting))
    return int(rng.choice(allowed))


def compare_walk(family: str, seed: int, states: int, tally: Tally, pushy: bool = False) -> list[str]:
    """Walk ``states`` states of ``family`` from ``seed``; the states where the two tables differ."""
    env = gym.make(ENV_ID, family=family)
    wrapper = env.unwrapped
    phase_env = env
    while not hasattr(phase_env, "layout"):
        phase_env = phase_env.env
    layout = phase_env.layout
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    fast, differ = None, []
    for step in range(states):
        scenario, state, lattice = wrapper.scenario, wrapper.state, wrapper.lattice
        if fast is None or fast.scenario is not scenario:
            fast = FastPhases(layout, scenario, lattice)
        want = enumerate_phases(layout, scenario, state, lattice)
        got = fast.table(state)
        if not same_table(got, want):
            differ.append(f"{family} seed {seed} step {step}: {np.flatnonzero(got.mask != want.mask)[:8].tolist()}")
        assert same_table(phase_env.table, want)  # the wrapper's own table too
        tally.states += 1
        tally.candidates += layout.size
        tally.allowed += int(want.mask.sum())
        index = _choose(rng, want.mask, want.actions, layout.size, pushy)
        push = bool(want.mask[index] and want.actions[index, 4] == Mode.PUSH)
        tally.pushes += push
        tally.refused += not want.mask[index]
        before = dict(state.clutter)
        _obs, _r, terminated, truncated, _info = env.step(index)
        if push:  # jammed: the piece stopped short of the stroke, against a neighbour or a wall
            moved = max(float(np.hypot(*np.subtract(wrapper.state.clutter[k], before[k]))) for k in before)
            tally.jams += moved < layout.describe(index).a * lattice.resolution - 1e-3
        if terminated or truncated:
            env.reset()
    env.close()
    return differ


@pytest.mark.parametrize("family", FAMILY_NAMES)
def test_fast_mask_is_the_reference_mask_on_random_walks(family):
    tally = Tally()
    differ = compare_walk(family, seed=FAMILY_NAMES.index(family), states=STATES_PER_FAMILY, tally=tally)
    assert differ == []
    assert tally.states == STATES_PER_FAMILY and tally.allowed > 0
    assert tally.refused > 0  # states after refused candidates are compared too


def test_the_masks_after_pushes_that_jam_are_the_reference_masks():
    tally = Tally()
    assert compare_walk("push", seed=0, states=100, tally=tally, pushy=True) == []
    assert tally.pushes >= 20 and tally.jams >= 1


def _array(rects) -> np.ndarray:
    return np.array([(r.min_x, r.min_y, r.max_x, r.max_y) for r in rects], dtype=float)


def _scenario(family: str, seed: int):
    env = gym.make("FetchCarryPush-v0", family=family)
    env.reset(seed=seed)
    return env.unwrapped.scenario, env.unwrapped.lattice


@pytest.mark.parametrize("family", ["basic", "corridor", "push"])
def test_the_octagon_bits_of_every_lattice_point_are_the_scalar_rule_s(family):
    """grid_bits and cells_bits against octagon_bits and side_bits, point by point, on lattice and random cells."""
    scenario, lattice = _scenario(family, 5)
    radius = scenario.robot.radius
    walls = [rect for _, rect in move_blockers(scenario)]
    rows = np.array([octagon_rows(lattice, r, radius) for r in walls], dtype=np.int64)
    grid = grid_bits(rows, lattice.shape)
    rng = np.random.default_rng(7)
    cells = rng.integers(0, lattice.shape, size=(400, 2))
    for i, j in cells.tolist():
        point = lattice.point(i, j)
        assert grid[i, j].tolist() == [octagon_bits(lattice, r, radius, point) for r in walls]
    assert np.array_equal(cells_bits(rows, cells[:, 0], cells[:, 1]), grid[cells[:, 0], cells[:, 1]])
    sides = np.array([side_rows(lattice, r) for r in walls], dtype=np.int64)
    got = cells_bits(sides, cells[:, 0], cells[:, 1])
    want = [[side_bits(lattice, r, lattice.point(i, j)) for r in walls] for i, j in cells.tolist()]
    assert got.tolist() == want


def test_the_hand_bits_of_many_points_are_hand_bits():
    """hands_bits against hand_bits on random points and on points within float noise of the sides."""
    scenario, _lattice = _scenario("push", 2)
    rects = [o.rect for o in scenario.obstacles] + [c.rect for c in scenario.clutter]
    rng = np.random.default_rng(3)
    area = scenario.area
    points = rng.uniform((area.min_x, area.min_y), (area.max_x, area.max_y), size=(2000, 2))
    for k, rect in enumerate(rects):  # hands on and around the sides, within the tolerance and just outside it
        for n, noise in enumerate((0.0, 4e-7, 6e-7, -4e-7, -6e-7)):
            points[10 * k + n] = (rect.max_x + noise, rect.center[1])
            points[10 * k + n + 5] = (rect.center[0], rect.min_y + noise)
    got = hands_bits(_array(rects), points[:, 0], points[:, 1])
    assert got.tolist() == [[hand_bits(r, tuple(p)) for r in rects] for p in points.tolist()]


def main(argv: list[str] | None = None) -> int:
    """The longer check: ``--states`` states of each family from ``--seeds`` seeds each."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, default=1000, help="states per family and seed (default 1000)")
    parser.add_argument("--seeds", type=int, default=2, help="seeds per family, every second one pushy (default 2)")
    args = parser.parse_args(argv)
    tally, differ = Tally(), []
    for family in FAMILY_NAMES:
        for seed in range(args.seeds):
            differ += compare_walk(family, 100 + seed, args.states, tally, pushy=seed % 2 == 1)
    print(
        f"{tally.states} states, {tally.candidates} candidates compared ({tally.allowed} allowed), "
        f"{tally.pushes} pushes ({tally.jams} jammed), {tally.refused} refused steps taken; {len(differ)} differ"
    )
    print("\n".join(differ[:20]))
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())


def test_a_pick_decided_by_the_rules_is_cached_apart_from_where_the_base_stands():
    """Two objects within reach of one pose: check_action decides which the pick takes, and what it decides about
    the pick must not depend on the base it was first asked from (the move there is the move rule's, per base)."""
    from dataclasses import replace

    from sim_worlds import room

    scenario = room(
        start=(2.5, 1.5),
        objects=[
            {"id": "near", "start": [1.8, 1.5], "goal": [1.3, 1.2]},
            {"id": "far", "start": [1.7, 1.5], "goal": [1.3, 1.8]},
        ],
    )
    env = gym.make(ENV_ID, scenario=scenario)
    env.reset(seed=0)
    layout, lattice = env.get_wrapper_attr("layout"), env.unwrapped.lattice
    behind = replace(env.unwrapped.state, base=lattice.point(*lattice.index((0.5, 1.5))))  # the poses are not one move
    fast = FastPhases(layout, scenario, lattice)
    fast.table(behind)  # fills the per-items cache from a base the poses are not one move from
    here = env.unwrapped.state
    assert same_table(fast.table(here), enumerate_phases(layout, scenario, here, lattice))
    env.close()
