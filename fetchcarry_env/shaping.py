"""``LearningReward``: a reward to learn from, with the paper's cost kept next to it.

The env's reward is minus the task cost, one phase at a time (10 per object not yet
delivered, plus the travel cost); it is what the cost ratio to the expert is measured in,
so it stays as it is. It is a poor teacher: an impossible action costs 1 more than doing
nothing useful, less than any move longer than about a metre, so a learner that refuses
to act can lose less than one that explores. :class:`LearningReward` adds to it

* potential-based shaping on progress (Ng, Harada and Russell, 1999):
  ``F = gamma * Phi(s') - Phi(s)``, which leaves the optimal policy unchanged; and
* a refusal cost larger than the cost of any move, so that refusing is never cheaper
  than moving.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from fetchcarry_env.env import FetchCarryPushEnv
from fetchcarry_env.kinematics import INVALID_ACTION_PENALTY, travel_cost
from fetchcarry_env.observation import WorldState
from fetchcarry_env.rules import clutter_rect
from fetchcarry_env.scenario import Scenario

DEFAULT_GAMMA = 0.99  # the discount of the learner the shaping is made for
DEFAULT_STAGE = 5.0  # reward units per stage of progress (a pick, a place, a goal cleared of clutter)


def stages_left(scenario: Scenario, state: WorldState) -> int:
    """Stages of work left: a pick and a place per object not delivered (a place if held), a push per covered goal."""
    delivered = set(state.delivered(scenario))
    left = 0
    for obj in scenario.objects:
        if obj.id in delivered:
            continue
        left += 1 if obj.id == state.holding else 2
        left += any(clutter_rect(scenario, state, c.id).overlaps_disc(obj.goal, obj.radius) for c in scenario.clutter)
    return left


def next_distance(scenario: Scenario, state: WorldState) -> float:
    """The paper's travel cost from the base to what comes next (metres).

    The held object's goal when the hand holds one, else the nearest object not
    delivered, else nothing (0).
    """
    if state.holding is not None:
        return travel_cost(state.base, scenario.object(state.holding).goal)
    delivered = set(state.delivered(scenario))
    costs = [travel_cost(state.base, state.objects[o.id][:2]) for o in scenario.objects if o.id not in delivered]
    return min(costs, default=0.0)


def potential(scenario: Scenario, state: WorldState, stage: float = DEFAULT_STAGE) -> float:
    """``Phi(s) = -(stage * stages_left + next_distance)``: 0 when the task is done, lower the more is left."""
    return -(stage * stages_left(scenario, state) + next_distance(scenario, state))


class LearningReward(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """The env's reward plus potential-based shaping on progress, with refusals costing more than any move.

    ## Reward

    ``r = r_env + F + refusal``, where

    * ``r_env`` is the env's reward (minus the task cost: 10 per object not at its goal after
      the step, plus the travel cost ``|dx| + |dy| + 0.1 ||dx| - |dy||`` in metres, plus 1 per
      refused action), unchanged;
    * ``F = gamma * Phi(s') - Phi(s)`` with ``Phi(s) = -(stage * stages_left(s) +
      next_distance(s))``: ``stages_left`` counts a pick and a place per object not
      delivered (only the place for the held one) and a push per goal that clutter
      covers; ``next_distance`` is the travel cost from the base to the held object's
      goal, or to the nearest object not delivered. ``Phi`` is 0 once every object is
      delivered, so the shaping telescopes: over an episode it adds ``-Phi(s_0)`` (with
      ``gamma = 1``) whatever the policy does, and with the learner's ``gamma`` it leaves
      the optimal policy unchanged (Ng et al., 1999);
    * ``refusal = INVALID_ACTION_PENALTY - refusal_cost`` when the env refused the action
      (``info["invalid_action"]`` is set), else 0: a refused action then costs
      ``refusal_cost`` in all, by default the travel cost of the longest move the
      lattice allows plus 1, more than any move.

    ``info`` gains ``paper_reward`` (``r_env``, the cost the benchmark measures) and
    ``shaping`` (``F``). The shaped reward depends on the state, not only on the goals:
    do not use it with hindsight relabelling (HER), which recomputes rewards from goals.

    ## Arguments

    ``env``: a fetch-and-carry env (``FetchCarryPush-v0`` or ``FetchCarryPushPhases-v0``,
    wrapped or not); ``gamma``: the learner's discount; ``stage``: reward units per
    stage of progress; ``refusal_cost``: what a refused action costs in all (None: the
    default above).
    """

    def __init__(
        self,
        env: gym.Env,
        gamma: float = DEFAULT_GAMMA,
        stage: float = DEFAULT_STAGE,
        refusal_cost: float | None = None,
    ) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, gamma=gamma, stage=stage, refusal_cost=refusal_cost)
        gym.Wrapper.__init__(self, env)
        base = env.unwrapped
        if not isinstance(base, FetchCarryPushEnv):
            raise TypeError(f"LearningReward wraps a FetchCarryPushEnv, got {type(base).__name__}")
        if not 0.0 < gamma <= 1.0:
            raise ValueError(f"gamma must be in (0, 1], got {gamma}")
        if stage < 0:
            raise ValueError(f"stage must not be negative, got {stage}")
        self._base = base
        self.gamma = gamma
        self.stage = stage
        self.refusal_cost = self.longest_move_cost() + 1.0 if refusal_cost is None else float(refusal_cost)
        if self.refusal_cost <= self.longest_move_cost():
            raise ValueError(
                f"refusal_cost {self.refusal_cost} must exceed the longest move's cost {self.longest_move_cost():.2f}"
            )
        self._phi = 0.0

    def longest_move_cost(self) -> float:
        """The travel cost of the costliest move the lattice allows (metres).

        The cost is convex in the move, so the costliest one runs between two corners.
        """
        (x0, y0), (x1, y1) = (
            self._base.lattice.origin,
            self._base.lattice.point(*(n - 1 for n in self._base.lattice.shape)),
        )
        return max(travel_cost((x0, y0), end) for end in ((x1, y1), (x1, y0), (x0, y1)))

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        observation, info = self.env.reset(seed=seed, options=options)
        self._phi = potential(self._base.scenario, self._base.state, self.stage)
        return observation, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        observation, reward, terminated, truncated, info = self.env.step(action)
        phi = potential(self._base.scenario, self._base.state, self.stage)
        shaping = self.gamma * phi - self._phi
        self._phi = phi
        refusal = INVALID_ACTION_PENALTY - self.refusal_cost if info.get("invalid_action") is not None else 0.0
        info["paper_reward"] = reward
        info["shaping"] = shaping
        return observation, float(reward + shaping + refusal), terminated, truncated, info
