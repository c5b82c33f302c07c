"""A masked categorical over the candidates allowed somewhere in a batch: PPO's actor without the refused columns.

sb3-contrib's ``MaskableCategorical`` scores all 4,080 candidates of every row and then
sets the refused ones to -1e8, so that their probability is exactly 0 in float32, their
log-probability never enters the loss and their scores get a gradient of exactly 0. A
state allows some 30 candidates, and a minibatch of 64 states a few hundred between them:
:class:`AllowedCategorical` computes only the scores of the candidates that some row of
the batch allows (:func:`allowed_columns`, through the flat and image networks'
``candidate_scores``, which compute only those rows of their last layer; the set
encoder's batches go through its ``forward``) and is, up to the order of floating-point
sums, the same distribution: the same log-probabilities, entropy, argmax and gradients
(the columns left out get a gradient of 0, as before). A draw samples the same
probabilities from a shorter vector, so a seed gives other draws than the full one.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import torch

from training.learners.encoders import CandidateScorer, FlatMLP, ImageScorer, candidate_scores

REFUSED_LOGIT = -1e8  # sb3-contrib's score of a refused candidate (its probability is exactly 0 in float32)
Scorer = Callable[[torch.Tensor, torch.Tensor], torch.Tensor]  # (observations (B, F), columns (U,)) -> scores (B, U)


def allowed_columns(masks: torch.Tensor) -> torch.Tensor:
    """The candidates (column indices, ascending) that at least one row of ``masks`` (B, N) allows."""
    return torch.nonzero(masks.any(dim=0)).squeeze(1)


def as_masks(masks: np.ndarray | torch.Tensor, rows: int) -> torch.Tensor:
    """``masks`` as a boolean tensor of ``rows`` rows (SB3 hands them flat, numpy in rollouts, tensors in updates)."""
    return torch.as_tensor(masks, dtype=torch.bool).reshape(rows, -1)


class AllowedCategorical:
    """The masked softmax over the columns ``columns`` of the candidates (the others: probability 0).

    ``scores`` (B, U) are the network's scores of ``columns`` (U indices, ascending),
    ``masks`` (B, U) what each row allows among them. The methods are those
    MaskablePPO uses of its distribution: ``log_prob`` and ``get_actions`` in candidate
    indices (of all N), ``entropy`` in nats.
    """

    def __init__(self, scores: torch.Tensor, masks: torch.Tensor, columns: torch.Tensor, candidates: int) -> None:
        self.masks, self.columns, self.candidates = masks, columns, candidates
        self.log_p = torch.log_softmax(torch.where(masks, scores, _refused(scores.dtype)), dim=1)

    def log_prob(self, actions: torch.Tensor) -> torch.Tensor:
        """Log-probability of each row's action (candidate indices, one per row); -inf-like for a refused one."""
        position = torch.full((self.candidates,), -1, dtype=torch.long)
        position[self.columns] = torch.arange(len(self.columns))
        where = position[actions.long().reshape(-1)]
        if bool((where < 0).any()):
            raise ValueError("an action outside the candidates allowed in its batch")
        return self._log_prob_at(where)

    def _log_prob_at(self, where: torch.Tensor) -> torch.Tensor:
        """Log-probability of each row's column ``where`` (positions among ``columns``)."""
        return self.log_p.gather(1, where[:, None]).squeeze(1)

    def entropy(self) -> torch.Tensor:
        """Entropy of each row's distribution (nats), refused candidates counted as 0, as sb3-contrib does."""
        p_log_p = torch.where(self.masks, self.log_p.exp() * self.log_p, torch.zeros((), dtype=self.log_p.dtype))
        return -p_log_p.sum(dim=1)

    def get_actions(self, deterministic: bool = False) -> torch.Tensor:
        """One candidate index per row: the most likely (the first of equals), or a draw."""
        return self.columns[self._draw(deterministic)]

    def actions_and_log_prob(self, deterministic: bool = False) -> tuple[torch.Tensor, torch.Tensor]:
        """``get_actions`` and the ``log_prob`` of those actions, without mapping them back to columns."""
        where = self._draw(deterministic)
        return self.columns[where], self._log_prob_at(where)

    def _draw(self, deterministic: bool) -> torch.Tensor:
        """Per row, the position among ``columns`` of the most likely candidate (the first of equals), or a draw."""
        if deterministic:
            return torch.argmax(self.log_p, dim=1)
        return torch.multinomial(self.log_p.exp(), 1).squeeze(1)


_REFUSED: dict[torch.dtype, torch.Tensor] = {}


def _refused(dtype: torch.dtype) -> torch.Tensor:
    """:data:`REFUSED_LOGIT` as a scalar tensor of ``dtype`` (made once per dtype)."""
    if dtype not in _REFUSED:
        _REFUSED[dtype] = torch.tensor(REFUSED_LOGIT, dtype=dtype)
    return _REFUSED[dtype]


class TracedScores:
    """``candidate_scores`` of a flat MLP through a TorchScript trace per batch size, for calls without gradients.

    The trace (``torch.jit.trace`` of :class:`~training.learners.encoders.CandidateScorer`,
    made on the first call of each batch size) shares the network's parameters, so it
    follows every update; it runs the same operations on them, without the Python of each
    module call: the same scores bit for bit (``tests/training/test_ppo_allowed.py``), in
    less than half the time of one rollout step's eager call. With gradients enabled
    (PPO's updates) the eager network runs.
    """

    def __init__(self, network: FlatMLP) -> None:
        self.network = network
        self.traces: dict[int, torch.jit.ScriptModule] = {}

    def __call__(self, flat: torch.Tensor, columns: torch.Tensor) -> torch.Tensor:
        if torch.is_grad_enabled():
            return candidate_scores(self.network, flat, columns)
        trace = self.traces.get(len(flat))
        if trace is None:
            with warnings.catch_warnings():  # the batch size is baked in: one trace per batch size
                warnings.simplefilter("ignore", torch.jit.TracerWarning)
                trace = torch.jit.trace(CandidateScorer(self.network), (flat, columns), check_trace=False)
            self.traces[len(flat)] = trace
        return trace(flat, columns)


def allowed_distribution(
    network: Any, flat: torch.Tensor, masks: Any, candidates: int, scorer: Scorer | None = None
) -> AllowedCategorical:
    """``network``'s masked distribution over the ``candidates`` of the observations ``flat`` (B, F).

    ``scorer``, if given, computes the scores of the allowed columns in place of
    ``network``'s ``candidate_scores`` (the same numbers: :class:`TracedScores`).
    """
    masks = as_masks(masks, len(flat))
    columns = allowed_columns(masks)
    if scorer is not None:
        scores = scorer(flat, columns)
    elif isinstance(network, FlatMLP | ImageScorer) or len(flat) == 1:  # their candidate_scores take batches
        scores = candidate_scores(network, flat, columns)
    else:  # the set encoder scores a batch through its whole Transformer anyway
        scores = network(flat).index_select(1, columns)
    return AllowedCategorical(scores, masks.index_select(1, columns), columns, candidates)
