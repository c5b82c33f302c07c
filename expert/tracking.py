"""Following a plan in the env: the actions left, the state the world should be in, and departures from it.

A :class:`Track` is what :class:`expert.policy.ExpertPolicy` keeps per env: the plan's
remaining actions, each with the phase the world should be in after it, and the phase
it should be in now. :func:`departure` says how an observed state departs from a planned
one beyond tolerances (metres), which is when the expert plans again. :func:`on_lattice`
puts a decoded base back on the lattice point the env has it at: the observation is
float32, whose spacing far from the origin (7.6e-6 m at 64 m) exceeds the rules' 1e-6 m
tolerances.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from expert.plans import Phase, Plan
from expert.to_actions import plan_to_actions
from fetchcarry_env.actions import Action, Lattice
from fetchcarry_env.observation import WorldState
from fetchcarry_env.scenario import Scenario


@dataclass(frozen=True)
class PlannedAction:
    """One action of the plan and the phase the world should be in after it."""

    action: Action
    expected: Phase


@dataclass
class Track:
    """The plan being followed in one env of a batch."""

    steps: list[PlannedAction] = field(default_factory=list)  # actions not yet given
    now: Phase | None = None  # the phase the world should be in now
    started: bool = False  # the planner already ran in this episode
    replan: str | None = None  # a reason to replan at the next call, whatever the state
    failed_in: WorldState | None = None  # the state in which the expert could not act
    failure: str | None = None  # why

    def follow(self, plan: Plan, scenario: Scenario, lattice: Lattice) -> None:
        """Make ``plan`` (found or not) the plan to follow from now on."""
        self.started, self.replan, self.steps, self.now = True, None, [], None
        if plan.found:
            actions = plan_to_actions(plan, scenario, lattice)
            self.steps = [PlannedAction(a, p) for a, p in zip(actions, plan.phases[1:], strict=True)]
            self.now = plan.phases[0]

    def fail(self, world: WorldState, failure: str) -> None:
        """Forget the plan: the expert cannot act in ``world`` (it will not plan again until the state changes)."""
        self.steps, self.now, self.failed_in, self.failure = [], None, world, failure

    def advance(self) -> Action:
        """The next action; the world should then be in its phase."""
        step = self.steps.pop(0)
        self.now = step.expected
        return step.action

    def why_plan(self, world: WorldState, base_tolerance: float, item_tolerance: float) -> str | None:
        """Why the expert must plan now in ``world``, or None to follow the plan."""
        if self.now is None:
            return "retry after a failure" if self.started else "episode_start"
        gap = departure(self.now, world, base_tolerance, item_tolerance)
        if gap is not None:
            return f"departed: {gap}"
        if self.replan is not None:
            return self.replan
        if not self.steps:
            return "plan used up"
        return None


def departure(
    expected: Phase | WorldState, world: WorldState, base_tolerance: float, item_tolerance: float
) -> str | None:
    """How ``world`` departs from ``expected`` beyond the tolerances (metres), or None."""
    gap = math.dist(expected.base, world.base)
    if gap > base_tolerance + 1e-9:
        return f"base {gap * 100:.1f} cm from the plan"
    if expected.holding != world.holding:
        return f"holding {world.holding} instead of {expected.holding}"
    for planned, seen in ((expected.objects, world.objects), (expected.clutter, world.clutter)):
        for item, position in planned.items():
            if item == world.holding or item not in seen:
                continue
            gap = math.dist(position[:2], seen[item][:2])
            if gap > item_tolerance:
                return f"{item} {gap * 100:.1f} cm from the plan"
    return None


def solved(scenario: Scenario, world: WorldState) -> bool:
    """Every object delivered and the hand empty."""
    return world.holding is None and len(world.delivered(scenario)) == len(scenario.objects)


def on_lattice(scenario: Scenario, world: WorldState, lattice: Lattice) -> tuple[Scenario, WorldState]:
    """``(scenario, world)`` with the base on its lattice point when float32 rounding is all that separates them.

    A base the env stopped on a lattice point is observed as that point rounded to
    float32; a coordinate within one float32 spacing (``np.spacing(np.float32(x))``,
    metres) of the nearest lattice point's is that point's exact value. A base elsewhere
    (stopped at a contact, after a push that stalled) is left as observed.
    """
    point = lattice.snap(world.base)
    if point == world.base or any(
        abs(p - b) > abs(float(np.spacing(np.float32(b)))) for p, b in zip(point, world.base, strict=True)
    ):
        return scenario, world
    robot = replace(scenario.robot, start=point)
    return replace(scenario, robot=robot), replace(world, base=point)
