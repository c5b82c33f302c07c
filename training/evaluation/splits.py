"""Fixed, versioned lists of evaluation scenarios (splits), and folders of scenario files.

A split is a list of scenario *sources* (a family, or a sampler of one Table I push
pattern) that its episodes cycle through: episode ``k`` draws from source
``k % len(sources)`` with the seed ``EVAL_SEED_BASE + split.offset + k``, through
``Family.sample(numpy.random.default_rng(seed))``. The same split name, version and
episode count give the same scenarios on every machine.

Seeds: evaluation seeds start at :data:`EVAL_SEED_BASE` (10^9), each split in its own
block of :data:`SPLIT_BLOCK` seeds. Training runs and datasets use seeds below
:data:`EVAL_SEED_BASE` (``fetchcarry generate`` counts up from ``--seed``, default 0;
the learning checks hold out seeds from 100,000), so no evaluation scenario is drawn
from a seed a learner was trained on.

=====================  ===========================================================
split                  scenarios
=====================  ===========================================================
``iid-v0``             unseen seeds of the training families ``basic``, ``push``,
                       ``corridor``, ``multi-2``
``more-objects-v0``    three and four objects (``multi-3``, ``multi-4``)
``layouts-v0``         layouts held out from training (``turned-room``,
                       ``turned-corridor``: the rooms and corridors turned a quarter
                       turn, which no training family draws)
``push-required-v0``   the five Table I push patterns A-E in turn; every scenario
                       has clutter on a goal, so every solution pushes at least once
``objects-v1``         the graded worlds ``objects-1`` .. ``objects-8`` in turn (episode
                       ``k`` has ``k % 8 + 1`` objects, on several tables, clutter on the
                       goals in half): success and cost ratio against the object count,
                       past the four a training family holds (capacity 8 objects)
``layouts-v2``         ``unseen-layouts``: topologies no training family draws, not even
                       turned (a T-junction, a U corridor, rooms in a row, a table in a
                       dead end); tests layouts, where ``layouts-v0``/``-v1`` test a turn
``apartment-v1``       ``apartment``: two to four rooms joined by doors and corridors of
                       varied width, three to six tables, two to five objects (capacity 5):
                       long horizons in a procedural home
``perturbed-v1``       ``perturbed``: ``iid`` scenarios with the tables and start moved a
                       little, one to three distractors, and the physics variation
                       ``home`` (each piece of clutter's mass and friction drawn per
                       episode, so a push lands elsewhere than planned): robustness
=====================  ===========================================================

Version 2 (``layouts-v3``) of every split: ``iid-v2``, ``more-objects-v2``,
``push-required-v2``, ``layouts-v3``, ``perturbed-v2``, ``objects-v2`` (``objects-1`` ..
``objects-12`` in turn) and ``apartment-v2``, on fresh seeds (blocks 8 to 14), each with a
``dev`` part of 100 and a ``test`` part of 300 episodes,
referenced under this release's task cost and the env's octagon rule. ``perturbed-v2``'s
three factors also stand alone, on its seeds: ``perturbed-layout-v2`` (tables and start
moved), ``perturbed-distractors-v2`` (distractors added) and ``perturbed-physics-v2`` (the
physics variation ``home``); episode ``k`` of each is ``perturbed-v2``'s episode ``k``
without the other two factors. Earlier versions
were referenced under release 0.2's task (a reward of +10 per delivery, the expert's
Eq. 1 over its own phases): their files stay as published, and the benchmark reports
them apart (:mod:`training.evaluation.references`).

A name without a version (``iid``) means the newest version. A new version gets a new
entry here; an existing version never changes.

Dev and test (version 1): every ``-v1`` split has two parts with disjoint seeds,
``NAME-v1:dev`` (episode ``k``: seed ``EVAL_SEED_BASE + offset + k``, the seeds of
``-v0``, on which recipes were tuned) for choosing recipes, and ``NAME-v1:test``
(episode ``k``: seed ``EVAL_SEED_BASE + offset + TEST_SHIFT + k``, never used before
version 1) for reporting, 300 episodes by default. A version without a part
(``iid-v1``, ``iid``) means its ``test`` part; ``iid:dev`` is the newest version's
``dev`` part. Each part's scenarios are pinned by the digest of every scenario in the
split's reference file (:mod:`training.evaluation.references`).

The splits over the graded worlds (``objects-v1``, ``layouts-v2``, ``apartment-v1``,
``perturbed-v1``) have the same two parts, both on fresh seeds of their own block
(``dev``: ``offset + k``, ``test``: ``offset + TEST_SHIFT + k``). Their test parts are
smaller than 300 where the reference did not fit the time there was (``objects-v1``:
16 dev and 160 test episodes, ``apartment-v1``: 10 and 30; docs/protocol.md).

Every policy acts in an env of the split's capacity (:attr:`Split.capacity`, the largest
of its families', which holds every scenario the split draws) and physics
(:attr:`Split.physics`, its families' variation): :attr:`EvalScenario.env_options`.
A name without a version means the newest: ``layouts`` is ``layouts-v2:test``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from fetchcarry_env.families import (
    EXTENT,
    HELD_OUT_FAMILIES,
    OBJECT_COUNTS,
    TRAINING_FAMILIES,
    UNSEEN_LAYOUT_FAMILIES,
    Family,
    draw_push,
    get_family,
)
from fetchcarry_env.observation import Capacity
from fetchcarry_env.scenario import Scenario, ScenarioError
from fetchcarry_env.worlds.physics import NO_VARIATION
from training.data.generate import EVAL_SEED_BASE  # first evaluation seed; training and dataset seeds stay below it
from training.errors import BenchmarkError

SPLIT_BLOCK = 1_000_000  # seeds reserved per split (episode k of a split uses base + offset + k)
SCENARIO_FILES = "*.json"  # what --scenarios reads from a folder
TEST_SHIFT = SPLIT_BLOCK // 2  # a v1 split's test part starts this far into its block
DEV, TEST = "dev", "test"  # the parts of a v1 split: choose recipes on dev, report on test


@dataclass(frozen=True)
class Source:
    """Where a split's scenarios come from: a name (shown in results) and a family to sample."""

    name: str
    family: Family


@dataclass(frozen=True)
class Split:
    """A versioned list of scenarios: its sources, cycled, and its seed block."""

    name: str  # e.g. "iid-v0"
    description: str
    sources: tuple[Source, ...]
    offset: int  # this split's seeds start at EVAL_SEED_BASE + offset
    episodes: int = 100  # the default number of episodes

    part: str = ""  # "dev" or "test" for a v1 split's part, "" for a v0 split (one part)

    def __post_init__(self) -> None:
        physics = {source.family.physics for source in self.sources}
        if len(physics) > 1:
            raise ValueError(f"split {self.name!r}: its sources name different physics variations")

    @property
    def capacity(self) -> Capacity:
        """The observation capacity that holds every scenario of the split: the largest of its sources' families'."""
        return largest(source.family.capacity for source in self.sources)

    @property
    def physics(self) -> str | None:
        """The physics variation the split's envs apply (its families', e.g. ``home``), ``None`` for none."""
        variation = self.sources[0].family.physics
        return variation.name if variation is not None else None

    @property
    def base_name(self) -> str:
        """The name without its version and part (``iid`` for ``iid-v0`` and ``iid-v1:test``)."""
        return self.version.rsplit("-v", 1)[0]

    @property
    def version(self) -> str:
        """The name without its part (``iid-v1`` for ``iid-v1:test``): what a reference file is named after."""
        return self.name.split(":", 1)[0]

    @property
    def version_number(self) -> int:
        """The version as a number (1 for ``iid-v1:dev``)."""
        return int(self.version.rsplit("-v", 1)[1])

    def seed(self, index: int) -> int:
        """The seed of episode ``index``."""
        room = SPLIT_BLOCK - TEST_SHIFT if self.part else SPLIT_BLOCK
        if not 0 <= index < room:
            raise BenchmarkError(f"a split has at most {room} episodes, asked for episode {index}")
        return EVAL_SEED_BASE + self.offset + index


@dataclass(frozen=True)
class EvalScenario:
    """One scenario to evaluate every policy on."""

    index: int  # position in the split (0, 1, ...)
    split: str  # the split's name, or "scenarios:FOLDER"
    source: str  # the family it was drawn from, or the file it was read from
    seed: int  # the env's reset seed (and the random policy's)
    scenario: Scenario
    capacity: Capacity = field(default_factory=Capacity)  # the env's capacity: holds the whole split
    physics: str | None = None  # the env's physics variation (a name of fetchcarry_env.worlds.physics), or none

    @property
    def env_options(self) -> dict[str, object]:
        """The ``gym.make`` options of the env every policy acts in on this scenario: capacity and physics."""
        return {"capacity": self.capacity, "physics": self.physics or NO_VARIATION}

    @property
    def floor(self) -> dict[str, object]:
        """Where the env's action lattice lies: the families' extent (the env of family ``basic``), or, for a
        scenario larger than that, the scenario's own area (the env of that scenario)."""
        if EXTENT.contains_rect(self.scenario.area):
            return {"family": "basic"}
        return {"scenario": self.scenario}


def largest(capacities: Iterable[Capacity]) -> Capacity:
    """The smallest capacity that covers every one of ``capacities`` (the default's for none)."""
    fields = [asdict(c) for c in capacities]
    if not fields:
        return Capacity()
    return Capacity(**{key: max(f[key] for f in fields) for key in fields[0]})


def _families(*names: str) -> tuple[Source, ...]:
    return tuple(Source(name, get_family(name)) for name in names)


def _push_pattern(pattern: str) -> Source:
    draw: Callable[[np.random.Generator], Scenario] = lambda rng: draw_push(rng, pattern)  # noqa: E731
    return Source(f"push-{pattern}", Family(f"push-{pattern}", f"Table I pattern {pattern}", EXTENT, draw))


_V0 = (
    Split("iid-v0", "unseen seeds of the training families", _families(*TRAINING_FAMILIES), 0 * SPLIT_BLOCK),
    Split("more-objects-v0", "three and four objects", _families("multi-3", "multi-4"), 1 * SPLIT_BLOCK),
    Split("layouts-v0", "room and corridor layouts held out", _families(*HELD_OUT_FAMILIES), 2 * SPLIT_BLOCK),
    Split(
        "push-required-v0",
        "every scenario needs a push, Table I patterns A-E",
        tuple(_push_pattern(p) for p in "ABCDE"),
        3 * SPLIT_BLOCK,
    ),
)
DEV_EPISODES, TEST_EPISODES = 100, 300  # a v1 part's default episodes (the published table: 300 per test split)


def _parts(v0: Split) -> tuple[Split, Split]:
    """Version 1 of ``v0``: its dev part (v0's seeds) and its test part (fresh seeds), same sources."""
    name = f"{v0.base_name}-v1"
    return (
        Split(f"{name}:{DEV}", v0.description, v0.sources, v0.offset, DEV_EPISODES, DEV),
        Split(f"{name}:{TEST}", v0.description, v0.sources, v0.offset + TEST_SHIFT, TEST_EPISODES, TEST),
    )


def _graded(
    version: str, description: str, sources: tuple[Source, ...], block: int, dev: int, test: int
) -> tuple[Split, Split]:
    """The dev and test parts of a split over the graded worlds: fresh seeds in block ``block``, both parts."""
    offset = block * SPLIT_BLOCK
    return (
        Split(f"{version}:{DEV}", description, sources, offset, dev, DEV),
        Split(f"{version}:{TEST}", description, sources, offset + TEST_SHIFT, test, TEST),
    )


# Fewer than 300 test episodes where the reference could not be computed in the time there was: the expert
# needs up to its 60 s limit for a plan of six to eight objects or of an apartment (docs/protocol.md).
OBJECTS_EPISODES = {DEV: 16, TEST: 160}  # 2 and 20 per object count
APARTMENT_EPISODES = {DEV: 10, TEST: 30}
_GRADED = (
    *_graded(
        "objects-v1",
        "k objects for k = 1..8 (objects-1 .. objects-8 in turn): success and cost ratio against k",
        _families(*(f"objects-{k}" for k in range(1, 9))),
        4,
        OBJECTS_EPISODES[DEV],
        OBJECTS_EPISODES[TEST],
    ),
    *_graded(
        "layouts-v2",
        "topologies no training family draws: T-junction, U corridor, rooms in a row, table in a dead end",
        _families(*UNSEEN_LAYOUT_FAMILIES),
        5,
        DEV_EPISODES,
        TEST_EPISODES,
    ),
    *_graded(
        "apartment-v1",
        "2-4 rooms joined by doors and corridors, 3-6 tables, 2-5 objects",
        _families("apartment"),
        6,
        APARTMENT_EPISODES[DEV],
        APARTMENT_EPISODES[TEST],
    ),
    *_graded(
        "perturbed-v1",
        "iid scenarios moved a little, with distractors and clutter mass and friction varied (physics home)",
        _families("perturbed"),
        7,
        DEV_EPISODES,
        TEST_EPISODES,
    ),
)

PERTURBED_BLOCK = 12  # perturbed-v2's seeds, shared by its one-factor splits (paired on purpose)

# Version 2 of every split (layouts: 3): the task cost (docs/formulation.md, "The task cost") and the env's
# octagon rule, on fresh seeds (blocks 8 to 14), 100 dev and 300 test episodes each (docs/protocol.md).
_V2 = (
    *_graded("iid-v2", _V0[0].description, _families(*TRAINING_FAMILIES), 8, DEV_EPISODES, TEST_EPISODES),
    *_graded("more-objects-v2", _V0[1].description, _families("multi-3", "multi-4"), 9, DEV_EPISODES, TEST_EPISODES),
    *_graded("push-required-v2", _V0[3].description, _V0[3].sources, 10, DEV_EPISODES, TEST_EPISODES),
    *_graded(
        "layouts-v3",
        "topologies no training family draws: T-junction, U corridor, rooms in a row, table in a dead end",
        _families(*UNSEEN_LAYOUT_FAMILIES),
        11,
        DEV_EPISODES,
        TEST_EPISODES,
    ),
    *_graded(
        "perturbed-v2",
        "iid scenarios moved a little, with distractors and clutter mass and friction varied (physics home)",
        _families("perturbed"),
        PERTURBED_BLOCK,
        DEV_EPISODES,
        TEST_EPISODES,
    ),
    *_graded(
        "objects-v2",
        "k objects for k = 1..12 (objects-1 .. objects-12 in turn): success and cost ratio against k",
        _families(*(f"objects-{k}" for k in OBJECT_COUNTS)),
        13,
        DEV_EPISODES,
        TEST_EPISODES,
    ),
    *_graded(
        "apartment-v2",
        "2-4 rooms joined by doors and corridors, 3-6 tables, 2-5 objects",
        _families("apartment"),
        14,
        DEV_EPISODES,
        TEST_EPISODES,
    ),
    # perturbed-v2's three factors one at a time, on perturbed-v2's own seeds (block 12): episode k of each is
    # perturbed-v2's episode k without the other two factors, so the factors compare paired.
    *_graded(
        "perturbed-layout-v2",
        "iid scenarios with the tables and start moved a little (perturbed's layout alone)",
        _families("perturbed-layout"),
        PERTURBED_BLOCK,
        DEV_EPISODES,
        TEST_EPISODES,
    ),
    *_graded(
        "perturbed-distractors-v2",
        "iid scenarios with one to three distractors (perturbed's distractors alone)",
        _families("perturbed-distractors"),
        PERTURBED_BLOCK,
        DEV_EPISODES,
        TEST_EPISODES,
    ),
    *_graded(
        "perturbed-physics-v2",
        "iid scenarios with clutter mass and friction varied (perturbed's physics alone: home)",
        _families("perturbed-physics"),
        PERTURBED_BLOCK,
        DEV_EPISODES,
        TEST_EPISODES,
    ),
)

SPLITS: dict[str, Split] = {
    split.name: split for split in (*_V0, *(p for v0 in _V0 for p in _parts(v0)), *_GRADED, *_V2)
}
"""Every split (and part) by its full name: ``iid-v0``, ``iid-v1:dev``, ``iid-v1:test``, ..."""


def get_split(name: str) -> Split:
    """The split called ``name``; :class:`BenchmarkError` otherwise.

    ``iid`` means its newest version, a version of two parts without one (``iid-v1``)
    its ``test`` part, and ``iid:dev`` the newest version's ``dev`` part.
    """
    if name in SPLITS:
        return SPLITS[name]
    stem, _, part = name.partition(":")
    if f"{stem}:{part or TEST}" in SPLITS:
        return SPLITS[f"{stem}:{part or TEST}"]
    versions = sorted((s for s in SPLITS.values() if s.base_name == stem), key=lambda s: s.version_number)
    if versions:
        newest = [s for s in versions if s.version_number == versions[-1].version_number]
        chosen = [s for s in newest if s.part == (part or (TEST if s.part else ""))]
        if chosen:
            return chosen[0]
    known = ", ".join(sorted({s.base_name for s in SPLITS.values()} | set(SPLITS)))
    raise BenchmarkError(f"unknown split {name!r}; known: {known}")


def published_splits() -> list[Split]:
    """The splits and parts that ship a reference file (every v1 part), in table order."""
    return [s for s in SPLITS.values() if s.part]


def split_scenarios(split: Split | str, episodes: int | None = None) -> list[EvalScenario]:
    """The first ``episodes`` scenarios of ``split`` (its default count if ``None``)."""
    split = get_split(split) if isinstance(split, str) else split
    count = split.episodes if episodes is None else episodes
    if count < 1:
        raise BenchmarkError(f"the number of episodes must be at least 1, got {count}")
    out = []
    capacity, physics = split.capacity, split.physics
    for index in range(count):
        source = split.sources[index % len(split.sources)]
        seed = split.seed(index)
        scenario = source.family.sample(np.random.default_rng(seed))
        out.append(EvalScenario(index, split.name, source.name, seed, scenario, capacity, physics))
    return out


SHOWN_PROBLEMS = 5  # a folder's unusable files named in the message; the rest are counted


def folder_scenarios(folder: str | Path, episodes: int | None = None) -> list[EvalScenario]:
    """The scenario files (``*.json``, in name order) of ``folder``, the first ``episodes`` of them.

    Their env's capacity is the default's, grown to hold every file's scenario; no physics variation
    (the scenario format has no masses or frictions). A scenario whose area lies inside the
    families' extent is played on that extent's lattice (as the splits are), a larger one on its
    own area's (:attr:`EvalScenario.floor`). Every file must be a valid scenario;
    :class:`BenchmarkError` names every file that is not.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise BenchmarkError(f"{folder} is not a folder of scenario files")
    files = sorted(folder.glob(SCENARIO_FILES))
    if not files:
        raise BenchmarkError(f"{folder} holds no scenario files ({SCENARIO_FILES})")
    files = files[:episodes] if episodes is not None else files
    problems, out = [], []
    for index, path in enumerate(files):
        try:
            scenario = Scenario.load(path)
        except (ScenarioError, OSError) as error:
            problems.append(str(error))  # it names the file
            continue
        out.append(EvalScenario(index, f"scenarios:{folder.name}", path.name, EVAL_SEED_BASE + index, scenario))
    capacity = Capacity()
    for item in out:
        capacity = capacity.holding(item.scenario)
    out = [replace(item, capacity=capacity) for item in out]
    if problems:
        shown = problems[:SHOWN_PROBLEMS]
        if len(problems) > SHOWN_PROBLEMS:
            shown.append(f"... and {len(problems) - SHOWN_PROBLEMS} more unusable files of {len(files)}")
        raise BenchmarkError(f"{len(problems)} unusable scenario files in {folder}:\n" + "\n".join(shown))
    return out
