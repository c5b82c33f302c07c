"""Scenario families: valid, workable and reproducible for any seed."""

from __future__ import annotations

import hashlib
import json
from dataclasses import replace

import numpy as np
import pytest

from fetchcarry_env.families import (
    EXTENT,
    FAMILY_NAMES,
    GRADED,
    PAPER_AREAS,
    PAPER_FAMILY_NAMES,
    PUSH_PATTERNS,
    draw_paper_push,
    draw_push,
    get_family,
)
from fetchcarry_env.geometry import Rect
from fetchcarry_env.reachability import unreachable_targets
from fetchcarry_env.scenario import Obstacle, Scenario, check_rules

SEEDS = range(200)
PAPER_SEEDS = range(30)

DIGESTS: dict[str, tuple[str, ...]] = {  # sha256 of each seed's sorted JSON, seeds 0-4, before the paper families
    "basic": (
        "ef284c3372bf7438be0cfca1ab4cb6ddb2de87121f4626d08827ed8079f4fb4c",
        "5b99b0b47837071292ee5b16e946f487d17d5d74cebfb9bc2057bb0c91e2cee3",
        "be73fda15ff3cf391831f0ffd9c7f9df969565d353f5bdf2046fa82fe67d5ac8",
        "9b12e980f5a0a8e11fd55cde6968576097e7ec2b446eca8f67fe6d4551914c67",
        "2f334f2f109465be3f300d0eee555d518d73a2919d225c26b205c896b4b376e0",
    ),
    "push": (
        "2be37dde55154d65e98e09c8d36eae8e19c0083f64a683bab70e887b60d55b82",
        "83d0cb6cc30833c1fc1e00d556a614de39c55d806c2c985194ad39f752e88063",
        "135525ac94b9bc867586e3e66b45072ab404bba5ee55edf1bff48d5402ee5df9",
        "e7e550b806237ee88b56b1c3b862d8faec5eb4c77bf45df4f85b5102b080c872",
        "0f756bc934293c76fd5e5721e88d2ae16703a5e469248856040dbbe194cb16f7",
    ),
    "corridor": (
        "5425c8a441ab1504577eb6ef61daeb171dd9d85ace36d53595be5ce8b211e210",
        "fb63d5f2e356061bf67a358bb837c17e350c738571c562d33a04e6267b058e5e",
        "0241055c06f48a0813cd782bd50365f2eda0b0b33332a441c77ef0f9dfe93a01",
        "f049c5cf6b340013f699e69b374f5b188ba47826781316e3851056877f3838c0",
        "af9170007d2dc9a2337150053119e96870f9b7562bdc90af7ff23dfc83932037",
    ),
    "multi": (
        "587312dfd2092e10549bc4ee73bd9c6d9a27f881cdc594cbfed9c38eb2712c1c",
        "b118aba21ea91f684ade62cde41dbe839ed00346a096a0071c282ab1fa2e2660",
        "34f230fc8b70b2c4b201f3b9122c1639521068089f24a739b967b41be8125588",
        "c19b3dfb199443b531e436401c65fa4473a58c427b9b90fa9493757520ac0ded",
        "4bdc63414a04a8424200e23a457060af2cbe24ab7ec57661037088cc16bf49c5",
    ),
    "multi-2": (
        "72cf2c8cf43b3b16c17b47bcc59626a989f87864699c2955329fa94cab6dbeff",
        "24ffac4dbfd077334620a867917250bad00c8584be69c0bf90dc2d7d742c583b",
        "63f4e8b7bf2834e75b39a8a6ea252eff1fb14474b55c91248a8fbd95de54b8b3",
        "9ce6772510b0cf92c176e398163ade7178093016d4f416353ae40eea510a287e",
        "4bbd678d608a7bbba25016b7b9d074ee9575de8ef64beedeb2a3a3f5562d1265",
    ),
    "multi-3": (
        "83e24f5294e6a93474fdfd1ef37a99869c6eda3c2613a2b66671793300bdc4fb",
        "e0dfc917950b898970a96efd7356c42ac1f39f391141083c407ea179d44f158b",
        "0a440b60c2d2a3afebfa5453e550463c4e16fa4bb60310b9a44033ac3c032e1e",
        "a2008e2c22a2226b7be4784768550dda9a70468b4f50f375696810e1ca88e12f",
        "68b1ef5eb66eaa6b462f1ca37d8c254493df22a043d5a970c12eb4270c6bedd4",
    ),
    "multi-4": (
        "707fa01ff389dc92075c583efa8b46cd6d331f7cd8c06b4aad93b8b7aa51f00b",
        "0e21d0230465b309c811865cca47a9425d6596b1f5ab64c423901709e55b53d6",
        "9ed0e3d4fac48c511f0a173ec4bcb6b072dbe8f552d0778c305b1e194741e24d",
        "97830f5f5fba4651972a5101109dee8d9bd39fe538a917fd06a07d104d20ec94",
        "ae191902fb1b52c137eae7176eb6a4fea6a364e48cfdc1ae9f97aa456a57da01",
    ),
    "mixed": (
        "0a270728ab1ce0a1ee598c66bf94a549f61c56ffbf4c81f0cb1d20f163478d6c",
        "cecfd692818391df1dce07efd498321487f3400621ba560e9b5dd3908b3999c2",
        "9bf1119a26384d0d3262e793503f82f17c14ba0e1f3f81af552737cb0b07e78c",
        "2482de6b3ad48c7a6fe897f994f335d786e413cf73b98fef1389b700c17d3a92",
        "e59369bbb912f161049d15dca71006249fecd087b49eb8e77804835068308fbb",
    ),
    "training": (
        "dc6e191e23ccec10eb725901a7b3b9d5f23c337b98b157088df421dd6d627620",
        "cecfd692818391df1dce07efd498321487f3400621ba560e9b5dd3908b3999c2",
        "94635512f800a2fb287c542a0b3174dd06f8a3d80d513b815ee84d8151ccfc35",
        "81fff2b64cb7c940d8aed28eba8da868cca634456a37f9764304f25cf0a0ab11",
        "e59369bbb912f161049d15dca71006249fecd087b49eb8e77804835068308fbb",
    ),
    "turned-room": (
        "3adba6d90fbeb8813180af6ebc08cb43daad7063ce669da99816f749c3a6b475",
        "b2ff58b5c3229f4eace68b4b0d83eb66c85a2813b09b7d8a963b1cf337487007",
        "bc4c198147401d5b4ee71c0c303cfdc3d77e8e56ba0b2c8ce911f864b3f61502",
        "9144e2f3ebffbfad6009cd502b2c3b04b1479522b9b3d42d50c6c54111bbb7e9",
        "3382a22702edcfae63691f1960c3b28a65209309594a9e0d5294a6f678a727fc",
    ),
    "turned-corridor": (
        "1437d0f81cce9e6cd77fc3f04f69314fd70ae4b05347b4aa9632fd5e9fbb6eeb",
        "1d1d56777dc7c6624df2361f3239c4c7823e77fe8841dc0d638b60e032147611",
        "2ee891933cd7ad3615b6e851aa8dcd71a7b20a14a8e0828b264ff610a6289933",
        "8aa401bad68bb13be731ed1b431190463c3033c651525955fd4e256976d21c68",
        "282d25d047783e6b229cf49b596f730d6d9c890ac5d8ccb1440f656b170302d1",
    ),
}


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


@pytest.mark.parametrize("name", DIGESTS)
def test_seeds_give_the_same_scenarios_as_before_the_paper_families(name):
    family = get_family(name)
    digests = tuple(
        hashlib.sha256(
            json.dumps(family.sample(np.random.default_rng(seed)).to_dict(), sort_keys=True).encode()
        ).hexdigest()
        for seed in range(5)
    )
    assert digests == DIGESTS[name]


def test_paper_families_are_apart_from_the_env_families():
    # FAMILY_NAMES is what mixed, training and the CLI list; the graded worlds have their own pins,
    # and so does the ladder's training family (tests/training/test_ladder.py)
    assert set(DIGESTS) | {family.name for family in GRADED} | {"objects-1-4"} == set(FAMILY_NAMES)
    assert not set(PAPER_FAMILY_NAMES) & set(FAMILY_NAMES)
    expected = {f"paper-basic-{a}" for a in PAPER_AREAS} | {f"paper-push-{p}" for p in PUSH_PATTERNS}
    expected |= {"paper-corridor", *(f"paper-multi-{n}" for n in range(2, 7)), "paper-covered-2", "paper-covered-3"}
    assert set(PAPER_FAMILY_NAMES) == expected


@pytest.mark.parametrize("name", PAPER_FAMILY_NAMES)
def test_paper_families_give_valid_workable_reproducible_scenarios(name):
    family = get_family(name)
    for seed in PAPER_SEEDS:
        scenario = family.sample(np.random.default_rng(seed))
        assert check_rules(scenario) == [] and unreachable_targets(scenario) == [], (name, seed)
        assert EXTENT.contains_rect(scenario.area)
        assert scenario == family.draw(np.random.default_rng(seed))  # no redraw: the generator's first scenario
        assert Scenario.from_dict(scenario.to_dict()) == scenario


@pytest.mark.parametrize("pattern", sorted(PUSH_PATTERNS))
def test_paper_push_neighbours_follow_table_one(pattern):
    bars, blocks = PUSH_PATTERNS[pattern]
    scenario = draw_paper_push(np.random.default_rng(5), pattern)
    block, *neighbours = scenario.clutter
    assert block.id == "block" and block.rect.overlaps_disc(scenario.objects[0].goal, scenario.objects[0].radius)
    assert [c.id[:4] for c in neighbours] == ["obs1"] * bars + ["obs2"] * blocks
    assert {c.height for c in neighbours} <= {0.10, 0.08}
    for bar in neighbours[:bars]:  # centred on the block's side
        along = 0 if bar.rect.size[0] > bar.rect.size[1] else 1
        assert bar.rect.center[along] == pytest.approx(block.rect.center[along])


@pytest.mark.parametrize("count", [2, 3])
def test_paper_covered_scenarios_cover_every_goal(count):
    scenario = get_family(f"paper-covered-{count}").sample(np.random.default_rng(count))
    assert len(scenario.objects) == count
    for obj in scenario.objects:
        assert any(c.rect.overlaps_disc(obj.goal, obj.radius) for c in scenario.clutter), obj.id


def test_paper_multi_draws_any_number_of_objects():
    from fetchcarry_env.families import draw_paper_multi

    scenario = draw_paper_multi(np.random.default_rng(0), 8)
    assert len(scenario.objects) == 8 and check_rules(scenario) == []
