"""Policies that act in the candidate-phase interface (``FetchCarryPushPhases-v0``) for recording.

A dataset recorded with ``interface="phases"`` stores candidate indices as actions and
each state's candidate mask as the per-step info ``action_mask``
(:data:`MASK_INFO`), so a learner trains from the Minari dataset alone.

The expert plans in env actions; :class:`PhaseExpert` maps each of them to the allowed
candidate that stands for it (:meth:`PhaseActions.index_of`). Picks, places and pushes
always have one; an expert *move* may not (its waypoints lie anywhere along a line, the
candidates at fixed points). Such a move is *projected*: the allowed move candidate whose
end lies nearest the expert's is executed and recorded instead
(:func:`nearest_move`), the base ends off the expert's
plan, and the expert plans again from there (it replans when the state departs from its
plan). Every recorded action is then an allowed candidate and the episode runs to its
end; the per-step info ``projected`` (:data:`PROJECTED_INFO`) marks the projected steps.

Any other action that no allowed candidate expresses (none is known to occur) ends the
episode there, *unexpressible*: the recorded last step is a masked candidate (the env
refuses it and changes nothing; its mask row says it was not allowed, so learners drop
it) and the episode is truncated with the outcome ``unexpressible``. Recording the
expert's own env action instead would put an action outside ``Discrete(K)`` into the
dataset, and replay would no longer be exact.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np

from expert.policy import Decision, ExpertPolicy
from fetchcarry_env.actions import Mode
from fetchcarry_env.kinematics import travel_cost
from training.policies.protocol import MaskedPolicy

MASK_INFO = "action_mask"  # per-step info of a phases dataset: the state's candidate mask (bool, K)
PROJECTED_INFO = "projected"  # per-step info of a phases dataset: the step is a projected expert move (bool)
UNEXPRESSIBLE = "unexpressible"  # the failure status (and episode outcome) of an expert action no candidate expresses


class PhaseExpert(MaskedPolicy):
    """:class:`expert.ExpertPolicy` on a phase env, answering with candidate indices (``predict`` protocol)."""

    deterministic_default = True

    def __init__(self, env: Any, *, time_limit: float, rule: str = "end") -> None:
        self.env = env
        self.rule = rule  # how a move no candidate expresses is projected (see nearest_move)
        self.expert = ExpertPolicy(env, time_limit=time_limit)
        self.last_decision: Decision | None = None
        self.last_projected = False  # the last answer is a projected move (the nearest move candidate)
        self.projected = 0  # expert moves projected onto their nearest candidate this episode
        self.unexpressible = 0  # other expert actions no candidate expressed (one ends an episode)

    @property
    def stats(self) -> Any:
        return self.expert.stats

    def reset(self) -> None:
        self.expert.reset()
        self.last_decision = None
        self.last_projected = False
        self.projected = 0

    def act(self, observation: Any, action_masks: np.ndarray | None, episode_start: Any, deterministic: bool) -> Any:
        """The candidate that stands for the expert's action, the nearest move for a move none stands for.

        An action other than a move that no candidate stands for gets a masked candidate
        (the env refuses it) and a decision whose ``failure`` ends the episode.
        """
        action, _ = self.expert.predict(observation, episode_start=episode_start, deterministic=True)
        decision = self.expert.last_decision
        index = self.env.get_wrapper_attr("index_of")(action)
        self.last_projected = False
        if index is None and decision is not None and decision.failure is None:
            index = nearest_move(self.env, action, self.rule)
            if index is not None:
                self.projected += 1
                self.last_projected = True
                reason = f"{decision.reason}; move projected onto candidate {index}"
                self.last_decision = replace(decision, reason=reason)
                return np.int64(index)
        if index is None:
            self.unexpressible += 1
            mask = self.env_masks() if action_masks is None else np.asarray(action_masks, dtype=bool)
            masked = np.flatnonzero(~mask)
            if masked.size == 0:
                raise RuntimeError("every candidate is allowed: an unexpressible action has no masked stand-in")
            reason = f"{UNEXPRESSIBLE}: no allowed candidate stands for the expert's action {np.asarray(action)}"
            self.last_decision = Decision(
                planned=decision.planned if decision else False,
                replanned=decision.replanned if decision else False,
                reason=reason,
                planning_s=decision.planning_s if decision else 0.0,
                status=UNEXPRESSIBLE,
                objective=decision.objective if decision else None,
                failure=reason,
            )
            return np.int64(masked[0])
        self.last_decision = decision
        return np.int64(index)


NEAREST_RULES = ("end", "detour")  # how nearest_move ranks the allowed move candidates


def nearest_move(env: gym.Env, action: np.ndarray, rule: str = "end") -> int | None:
    """The allowed move candidate nearest the env move ``action``, or None (not a move, or no move allowed).

    A stand-in for an expert move that no candidate expresses (the expert's waypoints
    lie anywhere along a line, the candidates at fixed points). ``rule`` ``end``: the
    candidate whose end lies nearest the expert's end (lattice cells, Manhattan; ties to
    the lower index). ``detour``: the candidate that adds the least travel cost on the
    way from the base to the expert's end (the paper's cost, metres; ties to the nearer end).
    """
    if rule not in NEAREST_RULES:
        raise ValueError(f"unknown rule {rule!r}: choose one of {', '.join(NEAREST_RULES)}")
    if int(action[4]) != Mode.MOVE:
        return None
    table = env.get_wrapper_attr("table")
    moves = np.flatnonzero(table.mask & (table.actions[:, 4] == int(Mode.MOVE)))
    if moves.size == 0:
        return None
    gaps = np.abs(table.actions[moves, :2] - np.asarray(action[:2])).sum(axis=1)
    if rule == "end":
        return int(moves[int(np.argmin(gaps))])
    unwrapped = env.unwrapped
    lattice, base = unwrapped.lattice, unwrapped.state.base
    end = lattice.point(int(action[0]), int(action[1]))
    detours = []
    for index, gap in zip(moves, gaps, strict=True):
        via = lattice.point(int(table.actions[index, 0]), int(table.actions[index, 1]))
        detours.append((round(travel_cost(base, via) + travel_cost(via, end), 9), int(gap), int(index)))
    return min(detours)[2]
