"""A saved plan executed open loop: each phase after the start becomes one action of ``FetchCarryPush-v0``.

:class:`SavedPlanPolicy` answers the plan's phases in order (:func:`expert.to_actions.plan_to_actions`),
whatever the env does with them: an action the env refuses is counted as invalid and the
next phase follows, as a plan executed without feedback would. Once the phases are all
taken and the episode has not ended, it reports a failure ("the plan has no phase left"),
which ends the episode in :func:`training.rollout.run_episode`. Its decisions carry the
plan's status and objective, so what the episode executed (an optimal plan, or one that
was not proven) is recorded with it. ``fetchcarry rollout --plan PLAN --scenario S`` runs it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from expert.plans import Plan
from expert.policy import Decision
from expert.to_actions import plan_to_actions
from fetchcarry_env.actions import Lattice
from fetchcarry_env.scenario import Scenario
from training.errors import BenchmarkError

PLAN_ENDED = "plan_ended"
"""The status of the decision after the plan's last phase (the episode ends, truncated)."""


class SavedPlanPolicy:
    """``predict`` answers the next phase of ``plan`` as the env's action (see the module docstring).

    ``lattice`` is the action lattice of the ``FetchCarryPush-v0`` env on ``scenario`` that the plan
    is executed in (``env.unwrapped.lattice``). A plan without phases, or one whose bases are off
    that lattice or name a posture the scenario's robot lacks, is a :class:`~training.errors.BenchmarkError`.
    """

    def __init__(self, plan: Plan, scenario: Scenario, lattice: Lattice) -> None:
        try:
            self.actions = [a.to_array() for a in plan_to_actions(plan, scenario, lattice)]
        except ValueError as error:
            raise BenchmarkError(f"the plan cannot be executed in this env: {error}") from None
        self.plan = plan
        self.taken = 0
        self.last_decision: Decision | None = None

    def reset(self, seed: int | None = None) -> None:
        """Start the plan again from its first phase."""
        self.taken = 0
        self.last_decision = None

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = False,
        action_masks: Any = None,
    ) -> tuple[np.ndarray, Any]:
        """The next phase's action; after the last one, the last again with a failure that ends the episode."""
        first = self.taken == 0
        if self.taken < len(self.actions):
            action = self.actions[self.taken]
            self.taken += 1
            self.last_decision = Decision(
                planned=first,
                replanned=False,
                reason="saved plan" if first else "following",
                status=self.plan.status if first else None,
                objective=self.plan.objective if first else None,
            )
            return action, state
        self.last_decision = Decision(
            planned=False, replanned=False, reason="done", status=PLAN_ENDED, failure="the plan has no phase left"
        )
        return self.actions[-1], state
