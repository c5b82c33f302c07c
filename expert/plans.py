"""The planner's answer: :class:`Plan`, in the ``fetchcarry-plan/1`` format of ``docs/plan-format.md``.

A plan is a sequence of :class:`Phase` records. Phase 0 is the initial state
(``action == "start"``); each later phase is one step: the base slides along the
straight segment from the previous phase's base to this one's, then the arm does the
phase's action. Readers ignore keys they do not know, as the spec asks.

Units are metres.
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from fetchcarry_env.errors import InputError
from fetchcarry_env.geometry import HEADINGS, Heading, Point
from fetchcarry_env.jsontext import describe, read_json_or
from fetchcarry_env.kinematics import WAIT_COST, travel_cost
from fetchcarry_env.scenario import Scenario

FORMAT = "fetchcarry-plan/1"

Status = Literal["optimal", "feasible", "infeasible", "time_limit"]
STATUSES: tuple[str, ...] = ("optimal", "feasible", "infeasible", "time_limit")
PhaseAction = Literal["start", "move", "pick", "place", "push"]
PHASE_ACTIONS: tuple[str, ...] = ("start", "move", "pick", "place", "push")
MAX_FILE_BYTES = 64 * 2**20  # bytes: a plan file is refused unread beyond this


class PlanFormatError(InputError):
    """A plan file does not follow ``fetchcarry-plan/1``; the message names the field."""


@dataclass(frozen=True)
class Phase:
    """One phase: where the base ends, its heading, and what the arm did there."""

    base: Point
    heading: Heading
    action: PhaseAction
    target: str | None = None
    posture: str | None = None
    holding: str | None = None
    objects: dict[str, Point] = field(default_factory=dict)
    clutter: dict[str, Point] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            "base": list(self.base),
            "heading": self.heading,
            "action": self.action,
            "target": self.target,
            "posture": self.posture,
            "holding": self.holding,
            "objects": {k: list(v) for k, v in self.objects.items()},
            "clutter": {k: list(v) for k, v in self.clutter.items()},
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], where: str) -> Phase:
        if not isinstance(data, Mapping):
            raise PlanFormatError(f"{where} must be an object")
        heading = data.get("heading")
        if not isinstance(heading, str) or heading not in HEADINGS:
            raise PlanFormatError(f"{where}.heading must be one of {', '.join(HEADINGS)}, got {describe(heading)}")
        action = data.get("action")
        if not isinstance(action, str) or action not in PHASE_ACTIONS:
            raise PlanFormatError(f"{where}.action must be one of {', '.join(PHASE_ACTIONS)}, got {describe(action)}")
        return cls(
            base=_point(data.get("base"), f"{where}.base"),
            heading=heading,
            action=action,
            target=_optional_str(data.get("target"), f"{where}.target"),
            posture=_optional_str(data.get("posture"), f"{where}.posture"),
            holding=_optional_str(data.get("holding"), f"{where}.holding"),
            objects=_points(data.get("objects", {}), f"{where}.objects"),
            clutter=_points(data.get("clutter", {}), f"{where}.clutter"),
        )


@dataclass(frozen=True)
class Plan:
    """A plan for one scenario, as ``docs/plan-format.md`` defines it.

    ``status`` is ``optimal``, ``feasible`` (a plan, optimality not proven in time),
    ``infeasible`` (no plan up to the largest number of phases tried) or
    ``time_limit`` (no plan found in time). ``phases`` is empty when there is no plan.
    ``stats`` holds at least ``total_s``, the wall time of the planning call (seconds).
    """

    scenario: str
    status: Status
    objective: float | None
    phases: tuple[Phase, ...] = ()
    stats: dict[str, Any] = field(default_factory=dict)

    @property
    def found(self) -> bool:
        """True when the plan has phases to execute (status optimal or feasible)."""
        return self.status in ("optimal", "feasible") and bool(self.phases)

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": FORMAT,
            "scenario": self.scenario,
            "status": self.status,
            "objective": self.objective,
            "phases": [phase.to_dict() for phase in self.phases],
            "stats": dict(self.stats),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Plan:
        """Parse a ``fetchcarry-plan/1`` mapping; raise :class:`PlanFormatError` naming the bad field."""
        if not isinstance(data, Mapping):
            raise PlanFormatError("a plan must be a JSON object")
        if data.get("format") != FORMAT:
            raise PlanFormatError(f"'format' must be {FORMAT!r}, got {describe(data.get('format'))}")
        status = data.get("status")
        if not isinstance(status, str) or status not in STATUSES:
            raise PlanFormatError(f"'status' must be one of {', '.join(STATUSES)}, got {describe(status)}")
        scenario = _text(data.get("scenario", ""), "'scenario'")
        objective = data.get("objective")
        if objective is not None and (isinstance(objective, bool) or not isinstance(objective, int | float)):
            raise PlanFormatError(f"'objective' must be a number or null, got {describe(objective)}")
        phases = data.get("phases", [])
        if not isinstance(phases, list):
            raise PlanFormatError(f"'phases' must be a list, got {describe(phases)}")
        stats = data.get("stats", {})
        if not isinstance(stats, Mapping):
            raise PlanFormatError(f"'stats' must be an object, got {describe(stats)}")
        return cls(
            scenario=scenario,
            status=status,
            objective=None if objective is None else _float(objective),
            phases=tuple(Phase.from_dict(p, f"phases[{k}]") for k, p in enumerate(phases)),
            stats=dict(stats),
        )

    @classmethod
    def load(cls, path: str | Path) -> Plan:
        """Read a plan file; :class:`PlanFormatError` names the file and the problem.

        A file larger than ``MAX_FILE_BYTES``, not UTF-8 text, or not JSON is a
        :class:`PlanFormatError` too; ``OSError`` (a missing or unreadable file) passes through.
        """
        path = Path(path)
        data = read_json_or(path, MAX_FILE_BYTES, lambda error: PlanFormatError(f"{path}: {error}"))
        try:
            return cls.from_dict(data)
        except PlanFormatError as error:
            raise PlanFormatError(f"{path}: {error}") from None

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps(self.to_dict(), indent=2) + "\n")


def _point(value: Any, where: str) -> Point:
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise PlanFormatError(f"{where} must be a pair of finite numbers [x, y], got {describe(value)}")
    x, y = (_float(v) if isinstance(v, int | float) and not isinstance(v, bool) else math.nan for v in value)
    if not (math.isfinite(x) and math.isfinite(y)):
        raise PlanFormatError(f"{where} must be a pair of finite numbers [x, y], got {describe(value)}")
    return (x, y)


def _float(value: int | float) -> float:
    """``value`` as a float; an integer beyond float range becomes ``inf`` (then refused by the caller's rule)."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def _points(value: Any, where: str) -> dict[str, Point]:
    if not isinstance(value, Mapping):
        raise PlanFormatError(f"{where} must be an object of id -> [x, y], got {describe(value)}")
    points = {}
    for key, point in value.items():
        name = _text(key, f"{where} key")
        points[name] = _point(point, f"{where}.{name if name.isprintable() else describe(name)}")
    return points


def _optional_str(value: Any, where: str) -> str | None:
    return None if value is None else _text(value, where, "a string or null")


def _text(value: Any, where: str, expected: str = "a string") -> str:
    """``value`` if it is a string of valid Unicode (no lone surrogate), else :class:`PlanFormatError`."""
    if not isinstance(value, str):
        raise PlanFormatError(f"{where} must be {expected}, got {describe(value)}")
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise PlanFormatError(f"{where} {describe(value)} is not valid Unicode text (a lone surrogate)") from None
    return value


def phase_rows(plan: Plan, row: Callable[[int, Phase], str], limit: int, more: str) -> list[str]:
    """``row(k, phase)`` for the first ``limit`` phases of ``plan``, then ``more.format(n)`` when ``n`` are left out.

    The lines of a table of steps (the plot's step list, the command line's summary).
    """
    rows = [row(k, phase) for k, phase in enumerate(plan.phases[:limit])]
    if len(plan.phases) > limit:
        rows.append(more.format(len(plan.phases) - limit))
    return rows


GOAL_TOL = 1e-3  # metres: an object this close to its goal, and not held, counts as delivered


def waiting(scenario: Scenario, phase: Phase) -> int:
    """How many objects are not at their goals at the end of ``phase`` (held, elsewhere, or missing from it)."""
    return sum(
        1
        for obj in scenario.objects
        if phase.holding == obj.id
        or obj.id not in phase.objects
        or math.dist(phase.objects[obj.id], obj.goal) > GOAL_TOL
    )


def task_cost(scenario: Scenario, phases: tuple[Phase, ...]) -> float:
    """The task's cost of a plan (metres): its travel plus ``W1`` for each phase after the start that
    ends with an object not at its goal, one count per such object.

    ``sum_k travel_cost(base_{k-1}, base_k) + W1 * sum_{k >= 1} waiting(phase_k)``, with Eq. 2-3's
    ``travel_cost`` (``|dx| + |dy| + W2 ||dx| - |dy||``) and ``W1 = WAIT_COST``: the paper's Eq. 1
    counted over the whole task (``docs/formulation.md``, "The task cost"). The env charges
    the same one step at a time, so an episode's return is minus this; a plan's ``objective``
    is it. Idle phases after the last delivery cost nothing.
    """
    travel = sum(travel_cost(a.base, b.base) for a, b in itertools.pairwise(phases))
    return travel + WAIT_COST * sum(waiting(scenario, phase) for phase in phases[1:])


plan_objective = task_cost
"""The name :func:`task_cost` had while a plan's objective was the paper's Eq. 1 over its own phases."""


def eq1_value(scenario: Scenario, phases: tuple[Phase, ...], n_phases: int) -> float:
    """The paper's Eq. 1 of ``phases`` counted over ``n_phases`` phases (idle ones after its end), as the MILP's
    objective with ``n_phases`` phases measures it: ``-W1 * sum_{i,k} delta_{i,k} + travel``, phase 0 included.

    It differs from :func:`task_cost` by a constant of the model (:func:`eq1_offset`).
    """
    return task_cost(scenario, phases) - eq1_offset(scenario, phases[0], n_phases)


def eq1_offset(scenario: Scenario, start: Phase, n_phases: int) -> float:
    """``task cost - Eq. 1`` for every plan of a model with ``n_phases`` phases that starts at ``start``."""
    return WAIT_COST * (len(scenario.objects) * n_phases - waiting(scenario, start))


def plan_length(phases: int) -> str:
    """A plan's length as every command and picture words it: ``6 phases (the start and 5 steps)``.

    A plan's phases count its start (phase 0); each later phase is one step (one env action).
    """
    steps = phases - 1
    return f"{phases} phases (the start and {steps} step{'' if steps == 1 else 's'})"
