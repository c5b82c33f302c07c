"""The MILP expert in the candidate-phase interface (``FetchCarryPushPhases-v0``): the benchmark's ``expert-phases``.

:class:`PhaseExpert` is :class:`expert.ExpertPolicy` on a phases env, by name: the expert
itself answers there with the candidate that stands for each of its plan's env actions
(:mod:`expert.candidates`: a move no candidate expresses is *projected* onto the nearest
allowed move, the expert replans from where the base ends; an action no allowed candidate
expresses is *unexpressible* and ends the episode, its last step a masked candidate).

It is the expert to run where a policy acts in candidate phases, as learners do: in
datasets recorded with ``interface="phases"`` (candidate indices as actions, each state's
candidate mask as the per-step info ``action_mask``, :data:`MASK_INFO`, the projected steps
marked by the per-step info ``projected``, :data:`PROJECTED_INFO`), so a learner trains
from the Minari dataset alone; and in the benchmark, next to ``expert`` (which acts in the
env's own actions), to see what the candidate interface costs the expert.
"""

from __future__ import annotations

from typing import Any

from expert.candidates import NEAREST_RULES, UNEXPRESSIBLE, nearest_move
from expert.policy import DEFAULT_TIME_LIMIT, ExpertPolicy

MASK_INFO = "action_mask"  # per-step info of a phases dataset: the state's candidate mask (bool, K)
PROJECTED_INFO = "projected"  # per-step info of a phases dataset: the step is a projected expert move (bool)

__all__ = ["MASK_INFO", "NEAREST_RULES", "PROJECTED_INFO", "UNEXPRESSIBLE", "PhaseExpert", "nearest_move"]


class PhaseExpert(ExpertPolicy):
    """:class:`expert.ExpertPolicy` on a phases env, answering candidate indices (``predict`` protocol).

    ``time_limit`` (seconds per planning call) defaults to the expert's
    (:data:`expert.policy.DEFAULT_TIME_LIMIT`); ``rule`` says which allowed move stands in
    for a move no candidate expresses (:func:`expert.candidates.nearest_move`). An env
    that does not act in candidate phases is refused (``ValueError``).
    """

    def __init__(self, env: Any, *, time_limit: float = DEFAULT_TIME_LIMIT, rule: str = "end") -> None:
        super().__init__(env, time_limit=time_limit, interface="phases", projection=rule)

    @property
    def rule(self) -> str:
        """How a move no candidate expresses is projected (:data:`NEAREST_RULES`)."""
        return self.projection
