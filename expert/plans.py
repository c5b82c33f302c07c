"""The planner's answer: :class:`Plan`, in the ``fetchcarry-plan/1`` format of ``spec/plan.md``.

A plan is a sequence of :class:`Phase` records. Phase 0 is the initial state
(``action == "start"``); each later phase is one step: the base slides along the
straight segment from the previous phase's base to this one's, then the arm does the
phase's action. Readers ignore keys they do not know, as the spec asks.

Units are metres.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from fetchcarry_env.geometry import HEADINGS, Heading, Point

FORMAT = "fetchcarry-plan/1"

Status = Literal["optimal", "feasible", "infeasible", "time_limit"]
STATUSES: tuple[str, ...] = ("optimal", "feasible", "infeasible", "time_limit")
PhaseAction = Literal["start", "move", "pick", "place", "push"]
PHASE_ACTIONS: tuple[str, ...] = ("start", "move", "pick", "place", "push")


class PlanFormatError(ValueError):
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
        if heading not in HEADINGS:
            raise PlanFormatError(f"{where}.heading must be one of {', '.join(HEADINGS)}, got {heading!r}")
        action = data.get("action")
        if action not in PHASE_ACTIONS:
            raise PlanFormatError(f"{where}.action must be one of {', '.join(PHASE_ACTIONS)}, got {action!r}")
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
    """A plan for one scenario, as ``spec/plan.md`` defines it.

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
            raise PlanFormatError(f"'format' must be {FORMAT!r}, got {data.get('format')!r}")
        status = data.get("status")
        if status not in STATUSES:
            raise PlanFormatError(f"'status' must be one of {', '.join(STATUSES)}, got {status!r}")
        objective = data.get("objective")
        if objective is not None and (isinstance(objective, bool) or not isinstance(objective, int | float)):
            raise PlanFormatError(f"'objective' must be a number or null, got {objective!r}")
        phases = data.get("phases", [])
        if not isinstance(phases, list):
            raise PlanFormatError("'phases' must be a list")
        stats = data.get("stats", {})
        if not isinstance(stats, Mapping):
            raise PlanFormatError("'stats' must be an object")
        return cls(
            scenario=str(data.get("scenario", "")),
            status=status,
            objective=None if objective is None else float(objective),
            phases=tuple(Phase.from_dict(p, f"phases[{k}]") for k, p in enumerate(phases)),
            stats=dict(stats),
        )

    @classmethod
    def load(cls, path: str | Path) -> Plan:
        path = Path(path)
        try:
            data = json.loads(path.read_text())
        except json.JSONDecodeError as error:
            raise PlanFormatError(f"{path}: not valid JSON: {error}") from None
        try:
            return cls.from_dict(data)
        except PlanFormatError as error:
            raise PlanFormatError(f"{path}: {error}") from None

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps(self.to_dict(), indent=2) + "\n")


def _point(value: Any, where: str) -> Point:
    if (
        not isinstance(value, list | tuple)
        or len(value) != 2
        or not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value)
    ):
        raise PlanFormatError(f"{where} must be a pair of finite numbers [x, y], got {value!r}")
    return (float(value[0]), float(value[1]))


def _points(value: Any, where: str) -> dict[str, Point]:
    if not isinstance(value, Mapping):
        raise PlanFormatError(f"{where} must be an object of id -> [x, y]")
    return {str(k): _point(v, f"{where}.{k}") for k, v in value.items()}


def _optional_str(value: Any, where: str) -> str | None:
    if value is not None and not isinstance(value, str):
        raise PlanFormatError(f"{where} must be a string or null, got {value!r}")
    return value
