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

from typing import Any

import numpy as np
import torch

from training.learners.encoders import FlatMLP, ImageScorer, candidate_scores

REFUSED_LOGIT = -1e8  # sb3-contrib's score of a refused candidate (its probability is exactly 0 in float32)


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
        self.masks, self.columns = masks, columns
        refused = torch.tensor(REFUSED_LOGIT, dtype=scores.dtype)
        self.log_p = torch.log_softmax(torch.where(masks, scores, refused), dim=1)
        self.position = torch.full((candidates,), -1, dtype=torch.long)
        self.position[columns] = torch.arange(len(columns))

    def log_prob(self, actions: torch.Tensor) -> torch.Tensor:
        """Log-probability of each row's action (candidate indices, one per row); -inf-like for a refused one."""
        where = self.position[actions.long().reshape(-1)]
        if bool((where < 0).any()):
            raise ValueError("an action outside the candidates allowed in its batch")
        return self.log_p.gather(1, where[:, None]).squeeze(1)

    def entropy(self) -> torch.Tensor:
        """Entropy of each row's distribution (nats), refused candidates counted as 0, as sb3-contrib does."""
        p_log_p = torch.where(self.masks, self.log_p.exp() * self.log_p, torch.zeros((), dtype=self.log_p.dtype))
        return -p_log_p.sum(dim=1)

    def get_actions(self, deterministic: bool = False) -> torch.Tensor:
        """One candidate index per row: the most likely (the first of equals), or a draw."""
        drawn = torch.argmax(self.log_p, dim=1) if deterministic else None
        where = drawn if drawn is not None else torch.multinomial(self.log_p.exp(), 1).squeeze(1)
        return self.columns[where]


def allowed_distribution(network: Any, flat: torch.Tensor, masks: Any, candidates: int) -> AllowedCategorical:
    """``network``'s masked distribution over the ``candidates`` of the observations ``flat`` (B, F)."""
    masks = as_masks(masks, len(flat))
    columns = allowed_columns(masks)
    if isinstance(network, FlatMLP | ImageScorer) or len(flat) == 1:  # their candidate_scores take batches
        scores = candidate_scores(network, flat, columns)
    else:  # the set encoder scores a batch through its whole Transformer anyway
        scores = network(flat).index_select(1, columns)
    return AllowedCategorical(scores, masks.index_select(1, columns), columns, candidates)
