"""The expert's env actions as candidate phases: what :class:`~expert.policy.ExpertPolicy` answers on a phases env.

``FetchCarryPushPhases-v0`` acts in ``Discrete(K)`` candidate phases, the expert plans in
the plain env's ``MultiDiscrete`` actions. :func:`candidate_answer` maps each of the
expert's actions to the allowed candidate that stands for it (the env's ``index_of``).
Picks, places and pushes always have one; an expert *move* may not (its waypoints lie
anywhere along a line, the candidates at fixed points). Such a move is *projected*: the
allowed move candidate whose end lies nearest the expert's is executed instead
(:func:`nearest_move`), the base ends off the expert's plan, and the expert plans again
from there (it replans when the state departs from its plan). Every answer is then an
allowed candidate and the episode runs to its end. A projected move never ends in a cell
that projected moves left since the expert's last other answer (``avoid``): with nothing
else changed, the same state would give the same answer again, and the base went back
and forth between two candidates until the episode was cut off (2 of 600 `training`
episodes did); when every allowed move is such a cell, the move is unexpressible.

Any other action that no allowed candidate expresses (none is known to occur; the
expert's idle fallback may be one) is *unexpressible*: the answer is a masked candidate
(the env refuses it and changes nothing) with the reason, which the expert makes its
decision's failure (status :data:`UNEXPRESSIBLE`): the episode ends there. Answering
the expert's own env action instead would put an action outside ``Discrete(K)`` into a
dataset, and replay would no longer be exact.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium import spaces

from fetchcarry_env.actions import Mode
from fetchcarry_env.kinematics import travel_cost

UNEXPRESSIBLE = "unexpressible"  # the failure status (and episode outcome) of an expert action no candidate expresses
NEAREST_RULES = ("end", "detour")  # how nearest_move ranks the allowed move candidates


@dataclass(frozen=True)
class CandidateAnswer:
    """The candidate that answers for one expert action."""

    index: int  # the candidate phase executed
    projected: bool = False  # a move no candidate expresses, projected onto the nearest allowed move
    unexpressible: str | None = None  # why no allowed candidate stands for the action (``index`` is masked)


def acts_in_candidates(env: Any) -> bool:
    """Whether ``env`` (wrapped or not, or a vector env) acts in candidate indices (a ``Discrete`` action space)."""
    return isinstance(getattr(env, "single_action_space", env.action_space), spaces.Discrete)


def candidate_answer(
    env: Any,
    action: np.ndarray,
    *,
    project: bool,
    rule: str = "end",
    mask: np.ndarray | None = None,
    avoid: Collection[tuple[int, int]] = (),
) -> CandidateAnswer:
    """The candidate of phases env ``env`` (in its current state) that answers for the expert's env ``action``.

    ``project``: a move no candidate stands for becomes the nearest allowed move (``rule``,
    :func:`nearest_move`) that does not end in a lattice cell of ``avoid``; else, or when
    no such move is allowed, the answer is unexpressible. ``mask`` is the state's candidate
    mask if the caller has it (else the env's).
    """
    index = env.get_wrapper_attr("index_of")(action)
    if index is not None:
        return CandidateAnswer(int(index))
    if project:
        nearest = nearest_move(env, action, rule, avoid)
        if nearest is not None:
            return CandidateAnswer(nearest, projected=True)
    allowed = np.asarray(env.get_wrapper_attr("action_masks")() if mask is None else mask, dtype=bool)
    masked = np.flatnonzero(~allowed.reshape(-1))
    if masked.size == 0:
        raise RuntimeError("every candidate is allowed: an unexpressible action has no masked stand-in")
    reason = f"{UNEXPRESSIBLE}: no allowed candidate stands for the expert's action {np.asarray(action)}"
    return CandidateAnswer(int(masked[0]), unexpressible=reason)


def nearest_move(
    env: Any, action: np.ndarray, rule: str = "end", avoid: Collection[tuple[int, int]] = ()
) -> int | None:
    """The allowed move candidate nearest the env move ``action``, or None (not a move, or no move allowed).

    A stand-in for an expert move that no candidate expresses (the expert's waypoints
    lie anywhere along a line, the candidates at fixed points). ``rule`` ``end``: the
    candidate whose end lies nearest the expert's end (lattice cells, Manhattan; ties to
    the lower index). ``detour``: the candidate that adds the least travel cost on the
    way from the base to the expert's end (the paper's cost, metres; ties to the nearer end).
    Moves that end in a lattice cell ``(i, j)`` of ``avoid`` are left out.
    """
    if rule not in NEAREST_RULES:
        raise ValueError(f"unknown rule {rule!r}: choose one of {', '.join(NEAREST_RULES)}")
    if int(action[4]) != Mode.MOVE:
        return None
    table = env.get_wrapper_attr("table")
    moves = np.flatnonzero(table.mask & (table.actions[:, 4] == int(Mode.MOVE)))
    if avoid:
        ends = table.actions[moves, :2]
        moves = moves[[(int(i), int(j)) not in avoid for i, j in ends]]
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
