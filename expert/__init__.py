"""expert: the paper's MILP task-and-motion planner on SCIP, its plans and the expert policy.

``plan`` and ``ExpertPolicy`` are imported on first use, so that ``import expert`` (and
reading or validating plans) does not pay for importing the solver.
"""

from __future__ import annotations

import importlib
from typing import Any

from expert.plans import Phase, Plan, PlanFormatError

_LAZY = {
    "plan": "expert.planner",
    "ExpertPolicy": "expert.policy",
    "validate_plan": "expert.validate",
    "plan_to_actions": "expert.to_actions",
}

__all__ = ["ExpertPolicy", "Phase", "Plan", "PlanFormatError", "plan", "plan_to_actions", "validate_plan"]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'expert' has no attribute {name!r}")
