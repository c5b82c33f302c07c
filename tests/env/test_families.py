"""Scenario families: valid, workable and reproducible for any seed."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fetchcarry_env.families import EXTENT, FAMILY_NAMES, PUSH_PATTERNS, draw_push, get_family
from fetchcarry_env.geometry import Rect
from fetchcarry_env.reachability import unreachable_targets
from fetchcarry_env.scenario import Obstacle, Scenario, check_rules

SEEDS = range(200)


@pytest.mark.parametrize("name", FAMILY_NAMES)
def test_every_seed_gives_a_valid_workable_scenario(name):
    family = get_family(name)
    for seed in SEEDS:
        scenario = family.sample(np.random.default_rng(seed))
        assert check_rules(scenario) == [], (name, seed)
        assert unreachable_targets(scenario) == [], (name, seed)
        assert EXTENT.contains_rect(scenario.area)
        # What a family makes survives the file format unchanged.
        assert Scenario.from_dict(scenario.to_dict()) == scenario


@pytest.mark.parametrize("name", FAMILY_NAMES)
def test_same_seed_same_scenario_and_seeds_differ(name):
    family = get_family(name)
    first = [family.sample(np.random.default_rng(seed)) for seed in range(5)]
    again = [family.sample(np.random.default_rng(seed)) for seed in range(5)]
    assert first == again
    assert len({s.to_dict().__repr__() for s in first}) == 5


def test_push_family_puts_clutter_on_every_goal():
    for seed in range(50):
        scenario = get_family("push").sample(np.random.default_rng(seed))
        goal = scenario.objects[0]
        assert any(c.rect.overlaps_disc(goal.goal, goal.radius) for c in scenario.clutter)


@pytest.mark.parametrize("pattern", sorted(PUSH_PATTERNS))
def test_push_patterns_follow_table_one(pattern):
    bars, blocks = PUSH_PATTERNS[pattern]
    scenario = draw_push(np.random.default_rng(3), pattern)
    ids = [c.id for c in scenario.clutter]
    assert sum(i.startswith("bar") for i in ids) == bars
    assert sum(i.startswith("small") for i in ids) == blocks


def test_multi_counts():
    for n in (2, 3, 4):
        scenario = get_family(f"multi-{n}").sample(np.random.default_rng(0))
        assert len(scenario.objects) == n


def test_unknown_family_lists_the_known_ones():
    with pytest.raises(ValueError, match="known: basic, push"):
        get_family("kitchen")


def test_unreachable_goal_is_detected(spec_example):
    walls = tuple(
        Obstacle(f"wall_{k}", r)
        for k, r in enumerate(
            [Rect(3.0, 3.0, 5.0, 3.2), Rect(3.0, 4.8, 5.0, 5.0), Rect(3.0, 3.2, 3.2, 4.8), Rect(4.8, 3.2, 5.0, 4.8)]
        )
    )
    boxed_in = replace(spec_example, obstacles=walls)
    assert "object 'bottle' goal" in unreachable_targets(boxed_in)


def test_training_family_draws_the_iid_families_with_one_or_two_objects():
    scenarios = [get_family("training").sample(np.random.default_rng(seed)) for seed in range(60)]
    kinds = {next(k for k in ("basic", "push", "corridor", "multi2") if s.name.startswith(k)) for s in scenarios}
    assert kinds == {"basic", "push", "corridor", "multi2"}, kinds
    assert {len(s.objects) for s in scenarios} == {1, 2}
