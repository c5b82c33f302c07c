"""The splits over the graded worlds: their sources, and the capacity and physics every policy acts in."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fetchcarry_env.families import OBJECT_COUNTS, get_family
from fetchcarry_env.observation import Capacity
from training.errors import BenchmarkError
from training.evaluation import episodes, references, runner
from training.evaluation.references import part_references
from training.evaluation.splits import (
    APARTMENT_EPISODES,
    DEV_EPISODES,
    OBJECTS_EPISODES,
    TEST_EPISODES,
    folder_scenarios,
    get_split,
    split_scenarios,
)
from training.resolve import PolicySpec, resolve

V1_OBJECT_COUNTS = tuple(range(1, 9))  # objects-v1: objects-1 .. objects-8
GRADED = {  # split version -> (its families, the capacity's objects and clutter, its physics)
    "objects-v1": (tuple(f"objects-{k}" for k in V1_OBJECT_COUNTS), (8, 8), None),
    "layouts-v2": (("unseen-layouts",), (4, 8), None),
    "apartment-v1": (("apartment",), (5, 8), None),
    "perturbed-v1": (("perturbed",), (4, 8), "home"),
    "objects-v2": (tuple(f"objects-{k}" for k in range(1, 13)), (12, 12), None),
    "layouts-v3": (("unseen-layouts",), (4, 8), None),
    "apartment-v2": (("apartment",), (5, 8), None),
    "perturbed-v2": (("perturbed",), (4, 8), "home"),
    "perturbed-layout-v2": (("perturbed-layout",), (4, 8), None),
    "perturbed-distractors-v2": (("perturbed-distractors",), (4, 8), None),
    "perturbed-physics-v2": (("perturbed-physics",), (4, 8), "home"),
}
SHORT_TESTS = {  # test parts of fewer than 300 episodes: their references were slow to compute (docs/protocol.md)
    "objects-v1:test": OBJECTS_EPISODES["test"],
    "apartment-v1:test": APARTMENT_EPISODES["test"],
    "objects-v2:test": TEST_EPISODES,
    "apartment-v2:test": TEST_EPISODES,
}


@pytest.mark.parametrize("version", list(GRADED))
def test_a_graded_split_cycles_its_families_with_their_capacity_and_physics(version: str) -> None:
    families, (objects, clutter), physics = GRADED[version]
    for part in ("dev", "test"):
        split = get_split(f"{version}:{part}")
        assert [s.name for s in split.sources] == list(families)
        assert (split.capacity.objects, split.capacity.clutter) == (objects, clutter) and split.physics == physics
        items = split_scenarios(split, len(families) + 1)
        assert [i.source for i in items] == [*families, families[0]]
        for item in items:
            assert item.capacity == split.capacity and item.capacity.fits(item.scenario)
            assert item.env_options == {"capacity": split.capacity, "physics": physics or "none"}
        assert len(part_references(split)) == split.episodes  # its reference file holds the whole part


def test_objects_episode_k_has_k_mod_12_plus_1_objects_and_names_the_newest_versions() -> None:
    assert len(OBJECT_COUNTS) == 12 and OBJECT_COUNTS[-1] == 12
    assert [len(i.scenario.objects) for i in split_scenarios("objects", 24)] == [*OBJECT_COUNTS] * 2
    assert [len(i.scenario.objects) for i in split_scenarios("objects-v1", 16)] == [*V1_OBJECT_COUNTS] * 2
    assert get_split("objects").name == "objects-v2:test" and get_split("layouts").name == "layouts-v3:test"
    assert get_split("apartment").name == "apartment-v2:test" and get_split("perturbed").name == "perturbed-v2:test"
    assert get_split("layouts-v1").sources[0].name == "turned-room"  # the old versions stay as they were
    assert get_split("layouts-v2").name == "layouts-v2:test" and get_split("objects-v1").episodes == 160
    assert get_split("layouts:dev").name == "layouts-v3:dev"


def test_test_parts_hold_300_episodes_but_where_the_reference_did_not_fit() -> None:
    for version in GRADED:
        test = get_split(f"{version}:test")
        assert test.episodes == SHORT_TESTS.get(test.name, TEST_EPISODES)
    # as many episodes of every object count, in each part
    assert all(n % len(V1_OBJECT_COUNTS) == 0 for n in OBJECTS_EPISODES.values())
    assert get_split("objects:dev").episodes == DEV_EPISODES
    assert get_split("apartment:dev").episodes == DEV_EPISODES


def test_the_split_capacity_is_the_largest_of_its_families() -> None:
    assert get_split("objects").capacity == get_family("objects-12").capacity
    assert (get_split("objects").capacity.objects, get_split("objects").capacity.clutter) == (12, 12)
    assert get_split("objects-v1").capacity == get_family("objects-8").capacity  # as it was published
    assert get_split("iid").capacity == Capacity()  # the splits of the training families act in the default env


def _run_folder(tmp_path: Path, encoder: str) -> PolicySpec:
    folder = tmp_path / encoder
    folder.mkdir()
    (folder / "config.json").write_text(json.dumps({"kind": "bc", "config": {"encoder": encoder}}))
    return PolicySpec(encoder, "phases", run=str(folder), env_options={"capacity": {"objects": 4}})


def test_a_set_encoder_acts_at_the_split_capacity_and_a_flat_network_is_refused(tmp_path: Path) -> None:
    items = split_scenarios("objects", 8)
    expert = runner.acting_spec(resolve("expert"), items[0])
    assert expert.env_options == {"capacity": get_family("objects-12").capacity, "physics": "none"}
    set_run, flat_run = _run_folder(tmp_path, "set"), _run_folder(tmp_path, "mlp")
    assert runner.acting_spec(set_run, items[0]).env_options["capacity"] == items[0].capacity
    assert runner.acting_spec(flat_run, items[0]).env_options["capacity"] == Capacity(objects=4)
    runner.check_fits([set_run], items)
    runner.check_fits([flat_run], items[:4])  # one to four objects fit its own capacity
    with pytest.raises(BenchmarkError, match="mlp cannot act in objects-5"):
        runner.check_fits([flat_run], items)
    iid = split_scenarios("iid", 1)[0]  # its own capacity holds the split's: it keeps it
    assert runner.acting_spec(set_run, iid).env_options["capacity"] == Capacity(objects=4)


def test_the_benchmark_builds_each_split_env_with_its_capacity_and_physics(tmp_path: Path, monkeypatch) -> None:
    built = []

    def recording(*args, **options):
        env = make_env(*args, **options)
        built.append((env.unwrapped.capacity, env.unwrapped.physics))
        return env

    make_env = episodes.make_env
    monkeypatch.setattr(episodes, "make_env", recording)
    report = runner.run_benchmark(["greedy"], split=["objects", "perturbed"], episodes=1, out=tmp_path)
    assert {(r["policy"], r["split"]) for r in report.records} == {
        (p, s) for p in ("expert", "random-phases", "greedy") for s in ("objects-v2:test", "perturbed-v2:test")
    }
    twelve, home = get_family("objects-12").capacity, get_family("perturbed").physics
    assert set(built) == {(twelve, None), (Capacity(), home)}
    assert len(built) == 6  # one env per policy and split
    assert all(r["success"] for r in report.records if r["policy"] == "expert")


def test_a_folder_env_holds_every_file_of_the_folder(tmp_path: Path) -> None:
    for item in split_scenarios("objects:dev", 8)[3:6]:  # four to six objects
        item.scenario.save(tmp_path / f"{item.source}.json")
    items = folder_scenarios(tmp_path)
    assert {i.capacity.objects for i in items} == {6} and {i.physics for i in items} == {None}


def test_extending_a_reference_file_keeps_its_records_and_runs_only_the_new_episodes(monkeypatch) -> None:
    calls = []
    original = references._reference_task
    monkeypatch.setattr(references, "_reference_task", lambda task: calls.append(task[1].index) or original(task))
    first = part_references("iid-v2:dev")[0]
    kept = {"split": "iid-v2", "time_limit_s": 5.0, "parts": {"dev": [first, {**first, "index": 1}]}}
    content = references.compute_references("iid-v2", episodes={"dev": 2, "test": 1}, time_limit=5.0, keep=kept)
    assert content["parts"]["dev"][0] == first  # kept as it was, planning time and all
    assert calls == [1, 0]  # dev episode 1 (the kept record is another scenario's), then test episode 0
    assert content["parts"]["dev"][1]["seed"] == first["seed"] + 1
    with pytest.raises(references.ReferenceFileError, match=r"6 s limit, not of iid-v2 with 5\.0 s"):
        references.compute_references("iid-v2", episodes={"dev": 1, "test": 1}, time_limit=6.0, keep=kept)
