"""Seeded scenario families: the paper's layouts and variations of them.

Every family draws from the ``numpy.random.Generator`` it is given (the env passes its
``np_random``, seeded by ``reset(seed=...)``), so a seed gives the same scenario bit for
bit. A family only returns scenarios that pass every rule of ``docs/scenario-format.md`` and
whose every object and goal the robot can reach from at least one side
(:mod:`fetchcarry_env.reachability`); a layout that fails is drawn again.

=========  ==============================================================================
family     what it draws
=========  ==============================================================================
basic      the paper's V-B: a source and a goal table, one 0.4 m obstacle at random,
           with the tables, the object and the start jittered
push       V-C: clutter standing on the goal, plus long bars and small blocks around it
           that limit the push directions (the paper's Table I patterns A-E, Fig. 3)
corridor   IV-F: two rooms joined by an L-shaped or straight corridor; the rest of the
           room is obstacles
multi      2 to 4 objects between two or three tables (``multi-2`` ... ``multi-4``: fixed)
mixed      one of basic, push, corridor and multi, uniformly
training   one of basic, push, corridor and multi-2, uniformly: the families learners are
           trained on (one and two objects; the benchmark's ``iid`` split cycles through
           the same four)
=========  ==============================================================================

Held-out layouts (for evaluation, never drawn by the families above): ``turned-room``
and ``turned-corridor`` draw a basic or push room, or a corridor, and turn the whole
scenario a quarter turn counter-clockwise about the centre of the extent
(:func:`turn_quarter`). The robot then starts in the bottom-right corner, the rooms and
corridors run the other way, and no training family ever draws such a layout; the
lattice maps onto itself, so every action stays on it. The training families' draws do
not change (the same seed gives the same scenario as before these families existed).

The paper's Section V cases (the planner benchmark's scenarios, :data:`PAPER_FAMILIES`;
not in :data:`FAMILY_NAMES`, which ``mixed``, ``training`` and the command line list):
fixed tables and start, no jitter but what each case draws.

==================  ====================================================================
family              what it draws
==================  ====================================================================
paper-basic-I..V    V-B: start (0, 0), 0.6 m tables at (2, 2) and (4, 4), one 0.4 m
                    obstacle whose centre is drawn in one of five areas (the paper's Fig. 5
                    is not in our copy; these are ours): I between the start and the source
                    table, II between the tables, III beside the source table on the far
                    side from (4, 0), IV its mirror image, V behind the goal table
paper-push-A..E     V-C: V-B without the obstacle, a 0.12-0.16 m block on the goal and the
                    Table I neighbours of :func:`draw_push` (bars centred on their side)
paper-corridor      IV-F (Fig. 4): a 6 x 6 m room whose free floor is an L corridor 1 m wide
paper-multi-2..6    2-6 objects, each from one of three 0.7 m tables to another
paper-covered-2, 3  as paper-multi, with a 0.08 m block on every goal (each pushed first)
==================  ====================================================================

All families share one extent, so that ``mixed`` and a fixed action lattice work.
Units are metres.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TypeVar

import numpy as np

from fetchcarry_env.geometry import Rect
from fetchcarry_env.observation import Capacity
from fetchcarry_env.reachability import unreachable_targets
from fetchcarry_env.scenario import Scenario, check_rules
from fetchcarry_env.worlds.apartment import draw_apartment
from fetchcarry_env.worlds.base import EXTENT
from fetchcarry_env.worlds.ladder import draw_ladder
from fetchcarry_env.worlds.objects import MAX_OBJECTS, draw_objects
from fetchcarry_env.worlds.paper import (
    PAPER_AREAS,
    draw_paper_basic,
    draw_paper_corridor,
    draw_paper_covered,
    draw_paper_multi,
    draw_paper_push,
)
from fetchcarry_env.worlds.perturbed import DISTRACTORS_FACTOR, LAYOUT
from fetchcarry_env.worlds.physics import HOME, PhysicsVariation
from fetchcarry_env.worlds.pushable import pushes_possible
from fetchcarry_env.worlds.rooms import (
    PUSH_PATTERNS,
    draw_basic,
    draw_corridor,
    draw_mixed,
    draw_multi,
    draw_perturbed,
    draw_push,
    draw_training,
)
from fetchcarry_env.worlds.turned import draw_turned_corridor, draw_turned_room, turn_quarter
from fetchcarry_env.worlds.unseen import draw_unseen

MAX_ATTEMPTS = 200  # layouts drawn before a family gives up (never reached in tests)

Sampler = Callable[[np.random.Generator], Scenario]
T = TypeVar("T")


@dataclass(frozen=True)
class Family:
    """A named scenario generator, the floor extent its scenarios lie in, and what the env needs for them.

    ``capacity`` is the observation's room that holds every scenario the family draws
    (the env's default for the family; a draw that would not fit is drawn again), and
    ``physics`` the physics variation the env applies to its episodes, if any
    (:mod:`fetchcarry_env.worlds.physics`).
    """

    name: str
    description: str
    extent: Rect
    draw: Sampler
    capacity: Capacity = field(default_factory=Capacity)
    physics: PhysicsVariation | None = None

    def sample(self, rng: np.random.Generator) -> Scenario:
        """A valid, workable scenario drawn from ``rng`` that fits :attr:`capacity`."""
        for _ in range(MAX_ATTEMPTS):
            scenario = self.draw(rng)
            if (
                self.capacity.fits(scenario)
                and not check_rules(scenario)
                and not unreachable_targets(scenario)
                and pushes_possible(scenario)
            ):
                return scenario
        raise RuntimeError(f"family {self.name!r} drew no workable scenario in {MAX_ATTEMPTS} attempts")


# ---------------------------------------------------------------------- registry
def _family_per_value(
    name: str,
    description: str,
    draw: Callable[[np.random.Generator, T], Scenario],
    values: Iterable[T],
    capacity: Callable[[T], Capacity] = lambda _: Capacity(),
) -> list[Family]:
    """One family per value: ``{}`` in ``name`` and ``description`` stands for it; it is ``draw``'s second argument.

    ``capacity`` gives each family's observation capacity from its value.
    """
    return [
        Family(name.format(v), description.format(v), EXTENT, lambda rng, v=v: draw(rng, v), capacity(v))
        for v in values
    ]


def _objects_capacity(count: int) -> Capacity:
    """Room for ``count`` objects and as many pieces of clutter (at least the default's four and eight)."""
    default = Capacity()
    return Capacity(objects=max(default.objects, count), clutter=max(default.clutter, count))


OBJECT_COUNTS: tuple[int, ...] = tuple(range(1, MAX_OBJECTS + 1))  # the k of the objects-k families
GRADED: tuple[Family, ...] = (
    *(
        Family(
            f"objects-{k}",
            f"{k} object(s) over several tables in a room sized to fit, clutter on goals in half",
            EXTENT,
            lambda rng, k=k: draw_objects(rng, k),
            capacity=_objects_capacity(k),
        )
        for k in OBJECT_COUNTS
    ),
    Family(
        "apartment",
        "2-4 rooms joined by doors and corridors, 3-6 tables, 2-5 objects, clutter on some goals",
        EXTENT,
        draw_apartment,
        capacity=Capacity(objects=5),
    ),
    Family(
        "unseen-layouts", "held out: T-junction, U corridor, rooms in a row, table in a dead end", EXTENT, draw_unseen
    ),
    Family(
        "perturbed",
        "iid scenarios with tables and start moved, distractors, clutter mass and friction varied",
        EXTENT,
        draw_perturbed,
        physics=HOME,
    ),
    Family(
        "perturbed-layout",
        "perturbed's first factor alone: iid scenarios with tables and start moved",
        EXTENT,
        lambda rng: draw_perturbed(rng, frozenset({LAYOUT})),
    ),
    Family(
        "perturbed-distractors",
        "perturbed's second factor alone: iid scenarios with one to three distractors",
        EXTENT,
        lambda rng: draw_perturbed(rng, frozenset({DISTRACTORS_FACTOR})),
    ),
    Family(
        "perturbed-physics",
        "perturbed's third factor alone: iid scenarios with clutter mass and friction varied",
        EXTENT,
        lambda rng: draw_perturbed(rng, frozenset()),
        physics=HOME,
    ),
)
"""The graded worlds (:mod:`fetchcarry_env.worlds`): registered after the families above, drawn by none of them."""

FAMILIES: dict[str, Family] = {
    family.name: family
    for family in (
        Family("basic", "V-B: one object, two tables, one random obstacle", EXTENT, draw_basic),
        Family("push", "V-C: clutter on the goal to push aside, Table I neighbours", EXTENT, draw_push),
        Family("corridor", "IV-F: rooms joined by an L-shaped or straight corridor", EXTENT, draw_corridor),
        Family("multi", "2 to 4 objects over two or three tables", EXTENT, draw_multi),
        *_family_per_value("multi-{}", "{} objects over two or three tables", draw_multi, (2, 3, 4)),
        Family("mixed", "basic, push, corridor or multi, uniformly", EXTENT, draw_mixed),
        Family("training", "basic, push, corridor or multi-2, uniformly (one and two objects)", EXTENT, draw_training),
        Family("turned-room", "held out: a basic or push room turned a quarter turn", EXTENT, draw_turned_room),
        Family("turned-corridor", "held out: a corridor turned a quarter turn", EXTENT, draw_turned_corridor),
        *GRADED,
        Family("objects-1-4", "objects-k with k uniform in 1..4 (the ladder's training family)", EXTENT, draw_ladder),
    )
}
HELD_OUT_FAMILIES: tuple[str, ...] = ("turned-room", "turned-corridor")
"""Families whose layouts no training family draws (for the benchmark's ``layouts-v0`` split)."""
UNSEEN_LAYOUT_FAMILIES: tuple[str, ...] = ("unseen-layouts",)
"""Topologies no training family draws, not even turned (for a new version of the ``layouts`` split)."""
TRAINING_PREFIXES: tuple[str, ...] = ("basic", "push", "corridor", "multi", "turned-")
"""How the names of the training families' scenarios (and the turned ones) begin."""
TRAINING_FAMILIES: tuple[str, ...] = ("basic", "push", "corridor", "multi-2")
"""The families a learner trains on (the ``iid`` split's, the expert's and the mask's checks' default)."""
FAMILY_NAMES: tuple[str, ...] = tuple(FAMILIES)
DEFAULT_FAMILY = "push"

PAPER_MULTI_COUNTS: tuple[int, ...] = (2, 3, 4, 5, 6)  # objects of the paper-multi-N families
PAPER_COVERED_COUNTS: tuple[int, ...] = (2, 3)  # objects of the paper-covered-N families
PAPER_FAMILIES: dict[str, Family] = {
    family.name: family
    for family in (
        *_family_per_value("paper-basic-{}", "V-B: one object, the obstacle in area {}", draw_paper_basic, PAPER_AREAS),
        *_family_per_value(
            "paper-push-{}", "V-C: a block on the goal, Table I pattern {}", draw_paper_push, PUSH_PATTERNS
        ),
        Family("paper-corridor", "IV-F: the L corridor of Fig. 4", EXTENT, draw_paper_corridor),
        *_family_per_value(
            "paper-multi-{}",
            "{} objects over three fixed tables",
            draw_paper_multi,
            PAPER_MULTI_COUNTS,
            _objects_capacity,
        ),
        *_family_per_value(
            "paper-covered-{}",
            "{} objects, a block on every goal",
            draw_paper_covered,
            PAPER_COVERED_COUNTS,
            _objects_capacity,
        ),
    )
}
"""The planner benchmark's cases (the paper's Section V); not drawn by ``mixed`` or ``training``."""
PAPER_FAMILY_NAMES: tuple[str, ...] = tuple(PAPER_FAMILIES)


def get_family(name: str) -> Family:
    """The family called ``name``, in :data:`FAMILIES` or :data:`PAPER_FAMILIES`.

    ``ValueError`` lists the known names otherwise.
    """
    family = FAMILIES.get(name) or PAPER_FAMILIES.get(name)
    if family is None:
        known = ", ".join((*FAMILY_NAMES, *PAPER_FAMILY_NAMES))
        raise ValueError(f"unknown scenario family {name!r}; known: {known}")
    return family


__all__ = [  # the generators live in fetchcarry_env.worlds; the registry names them here too
    "DEFAULT_FAMILY", "EXTENT", "FAMILIES", "FAMILY_NAMES", "GRADED", "HELD_OUT_FAMILIES", "OBJECT_COUNTS",
    "PAPER_AREAS", "PAPER_FAMILIES", "PAPER_FAMILY_NAMES", "PUSH_PATTERNS", "TRAINING_FAMILIES", "TRAINING_PREFIXES",
    "UNSEEN_LAYOUT_FAMILIES", "Family", "draw_basic", "draw_corridor", "draw_mixed", "draw_multi", "draw_paper_basic",
    "draw_paper_corridor", "draw_paper_covered", "draw_paper_multi", "draw_paper_push", "draw_perturbed", "draw_push",
    "draw_training", "get_family", "turn_quarter",
]  # fmt: skip
