"""``PhaseActions``: the env with ``Discrete(K)`` actions, one per candidate phase, and exact masks.

``gym.make("FetchCarryPushPhases-v0", ...)`` is ``FetchCarryPush-v0`` seen through this
wrapper. The candidates and when they are allowed are those of
:mod:`fetchcarry_env.phases`; the observation, the reward, ``info`` and the episode's
end are the env's own.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from fetchcarry_env.actions import Action, Mode
from fetchcarry_env.candidate_mask import FastPhases
from fetchcarry_env.env import FetchCarryPushEnv
from fetchcarry_env.phases import PhaseLayout, PhaseTable
from fetchcarry_env.rules import check_action
from fetchcarry_env.shaping import DEFAULT_GAMMA, LearningReward


class PhaseActions(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """The fetch-and-carry env with one ``Discrete(K)`` action per candidate phase.

    ## Action Space

    ``Discrete(layout.size)``: candidate ``k`` is the phase :meth:`PhaseLayout.describe`
    names (pick, place, push, approach move, waypoint or edge move; see
    :mod:`fetchcarry_env.phases` for the numbering). With the default layout and
    capacity, K = 4,080.

    :meth:`action_masks` (MaskablePPO's convention: one bool per candidate) is True
    exactly for the candidates allowed in the current state: their env action is
    accepted by the env's checks (:func:`fetchcarry_env.rules.check_action`), acts on
    the candidate's own item, reaches its end without a contact, stands for no
    earlier candidate's env action, and is not a move that goes nowhere. So an allowed
    candidate always executes as asked, and allowed candidates and env actions are one
    to one (:meth:`index_of`, :meth:`env_action`). The mask is computed once per state, when first asked for,
    in array operations (:mod:`fetchcarry_env.candidate_mask`), decision for decision as
    :func:`~fetchcarry_env.phases.enumerate_phases` (the reference) decides it.

    A masked candidate is refused: the world does not change and the env's penalty
    for an impossible action applies (``info["invalid_action"]`` says which candidate).
    An index outside ``[0, K)`` raises ``ValueError``.

    ## Observation, Rewards, Episode End

    The wrapped env's, unchanged (the paper's cost; :class:`~fetchcarry_env.shaping.LearningReward`
    adds a shaped reward for learners). ``info`` gains ``candidate`` (the index
    stepped) and ``masked`` (whether it was masked).

    ## Arguments

    ``env``: a :class:`~fetchcarry_env.env.FetchCarryPushEnv` (possibly wrapped, but
    under this wrapper no time limit should count steps twice); ``layout``: the
    numbering (by default :meth:`PhaseLayout.for_postures` of the default postures at
    the env's resolution, with the env's capacity).
    """

    def __init__(self, env: gym.Env, layout: PhaseLayout | None = None) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, layout=layout)
        gym.Wrapper.__init__(self, env)
        base = env.unwrapped
        if not isinstance(base, FetchCarryPushEnv):
            raise TypeError(f"PhaseActions wraps a FetchCarryPushEnv, got {type(base).__name__}")
        self._base = base
        if layout is None:
            layout = PhaseLayout.for_postures(resolution=base.lattice.resolution, capacity=base.capacity)
        if layout.capacity != base.capacity:
            raise ValueError(f"the layout's capacity {layout.capacity} is not the env's {base.capacity}")
        self.layout = layout
        self.action_space = spaces.Discrete(layout.size)
        self._table: PhaseTable | None = None
        self._phases: FastPhases | None = None  # what the current scenario decides once (its static geometry)

    # ------------------------------------------------------------------ Gymnasium API
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        self._table = None
        return self.env.reset(seed=seed, options=options)

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        index = self._check_index(action)
        table = self.table
        masked = not table.mask[index]
        env_action = self._refused_action() if masked else table.actions[index]
        self._table = None
        observation, reward, terminated, truncated, info = self.env.step(env_action)
        info["candidate"] = index
        info["masked"] = masked
        if masked:
            candidate = self.layout.describe(index)
            info["invalid_action"] = f"candidate {index} ({candidate.kind}, slot {candidate.slot}) is masked here"
        return observation, reward, terminated, truncated, info

    def compute_reward(self, achieved_goal: np.ndarray, desired_goal: np.ndarray, info: Any) -> np.ndarray | float:
        """The env's reward from the goals and ``info`` (batches too): the rewards are the env's own."""
        return self._base.compute_reward(achieved_goal, desired_goal, info)

    def action_masks(self) -> np.ndarray:
        """One bool per candidate: True exactly for the candidates allowed in the current state."""
        return self.table.mask.copy()

    # ------------------------------------------------------------------ candidates and env actions
    @property
    def table(self) -> PhaseTable:
        """The current state's candidates (computed once per state).

        :class:`~fetchcarry_env.candidate_mask.FastPhases` computes them, one per scenario:
        the same table as :func:`~fetchcarry_env.phases.enumerate_phases` (the reference,
        one candidate at a time), in array operations.
        """
        if self._table is None:
            base = self._base
            phases = self._phases
            if phases is None or phases.scenario is not base.scenario or phases.lattice != base.lattice:
                phases = self._phases = FastPhases(self.layout, base.scenario, base.lattice)
            self._table = phases.table(base.state)
        return self._table

    def index_of(self, action: np.ndarray | Sequence[int] | Action) -> int | None:
        """The allowed candidate that stands for the env action ``action`` in the current state, or None."""
        return self.table.index_of(action)

    def env_action(self, index: int) -> np.ndarray | None:
        """The env action (``MultiDiscrete`` vector) candidate ``index`` stands for now, or None if it is masked."""
        index = self._check_index(index)
        table = self.table
        return table.actions[index].copy() if table.mask[index] else None

    def step_env_action(self, action: np.ndarray | Sequence[int]) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """Step the wrapped env with an env action directly (for an expert whose action has no candidate).

        ``info["candidate"]`` is the allowed candidate that stands for ``action`` (None if
        none does) and ``info["masked"]`` whether there was none.
        """
        index = self.index_of(action)
        self._table = None
        observation, reward, terminated, truncated, info = self.env.step(np.asarray(action))
        info["candidate"] = index
        info["masked"] = index is None
        return observation, reward, terminated, truncated, info

    # ------------------------------------------------------------------ internals
    def _check_index(self, action: Any) -> int:
        array = np.asarray(action)
        if array.size != 1 or not np.issubdtype(array.dtype, np.integer):
            raise ValueError(f"action must be one integer index in [0, {self.layout.size}), got {action!r}")
        index = int(array.reshape(-1)[0])
        if not 0 <= index < self.layout.size:
            raise ValueError(f"action {index} is outside [0, {self.layout.size})")
        return index

    def _refused_action(self) -> np.ndarray:
        """An env action the env refuses without changing anything: a move to a lattice corner, outside the area.

        The area lies within the lattice's extent, so the base disc at a corner of the
        lattice never fits in it.
        """
        base = self._base
        nx, ny = base.lattice.shape
        for cell in ((0, 0), (nx - 1, ny - 1), (0, ny - 1), (nx - 1, 0)):
            action = Action(cell, base.state.heading, 0, Mode.MOVE)
            if isinstance(check_action(base.scenario, base.state, base.lattice, action), str):
                return action.to_array()
        raise RuntimeError("no env action is refused in this state: a masked candidate cannot be refused")


REWARDS = ("paper", "learning")


def make_phase_env(
    layout: PhaseLayout | None = None, reward: str = "paper", gamma: float = DEFAULT_GAMMA, **env_options: Any
) -> gym.Env:
    """``FetchCarryPushPhases-v0``'s entry point: ``FetchCarryPushEnv(**env_options)`` behind :class:`PhaseActions`.

    ``reward="paper"`` keeps the env's reward; ``reward="learning"`` adds
    :class:`~fetchcarry_env.shaping.LearningReward` (shaping for a learner of discount ``gamma``).
    """
    if reward not in REWARDS:
        raise ValueError(f"reward must be one of {', '.join(REWARDS)}, got {reward!r}")
    env: gym.Env = PhaseActions(FetchCarryPushEnv(**env_options), layout)
    return LearningReward(env, gamma=gamma) if reward == "learning" else env
