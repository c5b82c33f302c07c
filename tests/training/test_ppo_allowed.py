"""PPO's actor scored over the allowed candidates only is sb3-contrib's masked distribution: same loss and gradients."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("sb3_contrib")

from sb3_contrib.common.maskable.distributions import MaskableCategoricalDistribution  # noqa: E402

from fetchcarry_env.observation import Capacity, observation_size  # noqa: E402
from fetchcarry_env.phases import PhaseLayout  # noqa: E402
from training.learners.allowed import allowed_distribution  # noqa: E402
from training.learners.encoders import build_network  # noqa: E402
from training.learners.options import BCConfig  # noqa: E402


def _batch(seed: int, rows: int, candidates: int, allowed: int) -> tuple[torch.Tensor, np.ndarray, torch.Tensor]:
    """Random observations, masks allowing about ``allowed`` candidates a row, and one allowed action per row."""
    rng = np.random.default_rng(seed)
    masks = rng.random((rows, candidates)) < allowed / candidates
    masks[np.arange(rows), rng.integers(0, candidates, rows)] = True  # at least one per row
    actions = torch.tensor([rng.choice(np.flatnonzero(row)) for row in masks])
    flat = torch.as_tensor(rng.normal(size=(rows, observation_size(Capacity()))), dtype=torch.float32)
    return flat, masks, actions


def _network(encoder: str, candidates: int, flat: torch.Tensor) -> torch.nn.Module:
    torch.manual_seed(0)
    return build_network(BCConfig(encoder=encoder, hidden=64), Capacity(), candidates, flat)


@pytest.mark.parametrize("encoder", ["mlp", "set"])
def test_allowed_distribution_is_the_masked_one(encoder: str) -> None:
    candidates = PhaseLayout.for_postures(capacity=Capacity()).size
    flat, masks, actions = _batch(1, 16, candidates, 30)
    network = _network(encoder, candidates, flat)
    full = MaskableCategoricalDistribution(candidates).proba_distribution(network(flat))
    full.apply_masking(masks)
    mine = allowed_distribution(network, flat, masks, candidates)
    assert torch.allclose(mine.log_prob(actions), full.log_prob(actions), atol=1e-5)
    assert torch.allclose(mine.entropy(), full.entropy(), atol=1e-5)
    assert torch.equal(mine.get_actions(deterministic=True), full.get_actions(deterministic=True))
    drawn = mine.get_actions()
    assert bool(torch.as_tensor(masks)[torch.arange(len(drawn)), drawn].all())  # a draw is always allowed


def test_the_image_network_scores_a_batch_of_allowed_candidates_as_its_forward_does() -> None:
    candidates = 300
    flat = torch.as_tensor(np.random.default_rng(4).integers(0, 256, (8, 7 * 16 * 16)), dtype=torch.float32)
    torch.manual_seed(0)
    network = build_network(BCConfig(encoder="cnn", obs_mode="topdown", hidden=16), Capacity(), candidates, flat)
    _, masks, actions = _batch(5, 8, candidates, 30)
    full = MaskableCategoricalDistribution(candidates).proba_distribution(network(flat))
    full.apply_masking(masks)
    mine = allowed_distribution(network, flat, masks, candidates)
    assert torch.allclose(mine.log_prob(actions), full.log_prob(actions), atol=1e-5)


@pytest.mark.parametrize("encoder", ["mlp", "set"])
def test_allowed_gradients_are_the_masked_ones(encoder: str) -> None:
    """The PPO loss's gradient on every weight, the refused candidates' rows of the last layer included (zero)."""
    candidates = PhaseLayout.for_postures(capacity=Capacity()).size
    flat, masks, actions = _batch(2, 64, candidates, 30)
    network = _network(encoder, candidates, flat)
    advantages = torch.as_tensor(np.random.default_rng(3).normal(size=64), dtype=torch.float32)

    def gradients(distribution) -> dict[str, torch.Tensor]:
        network.zero_grad()
        loss = -(distribution.log_prob(actions) * advantages).mean() - 0.01 * distribution.entropy().mean()
        loss.backward()
        return {name: p.grad.clone() for name, p in network.named_parameters() if p.grad is not None}

    full = MaskableCategoricalDistribution(candidates).proba_distribution(network(flat))
    full.apply_masking(masks)
    expected = gradients(full)
    got = gradients(allowed_distribution(network, flat, masks, candidates))
    assert expected.keys() == got.keys()
    for name in expected:
        assert torch.allclose(got[name], expected[name], atol=1e-6, rtol=1e-4), name


def test_an_action_outside_the_allowed_columns_is_refused() -> None:
    candidates = 50
    flat = torch.zeros(2, observation_size(Capacity()))
    masks = np.zeros((2, candidates), bool)
    masks[:, 3] = True
    network = torch.nn.Linear(flat.shape[1], candidates)
    with pytest.raises(ValueError, match="outside the candidates"):
        allowed_distribution(network, flat, masks, candidates).log_prob(torch.tensor([3, 4]))


def test_the_traced_rollout_scores_are_the_eager_ones_bit_for_bit() -> None:
    """TracedScores (a rollout step's scores) equals the network's own, through weight updates and batch sizes."""
    from training.learners.allowed import TracedScores
    from training.learners.encoders import candidate_scores

    candidates = PhaseLayout.for_postures(capacity=Capacity()).size
    flat, masks, actions = _batch(7, 8, candidates, 30)
    network = _network("mlp", candidates, flat)
    traced = TracedScores(network)
    optimiser = torch.optim.SGD(network.parameters(), lr=0.1)
    for step in range(4):  # the trace shares the parameters: it follows every update
        for rows in (1, 2, 1):
            batch, mask = flat[step : step + rows], torch.as_tensor(masks[step : step + rows])
            columns = torch.nonzero(mask.any(dim=0)).squeeze(1)
            with torch.no_grad():
                assert torch.equal(traced(batch, columns), candidate_scores(network, batch, columns))
                mine = allowed_distribution(network, batch, mask, candidates, traced)
                eager = allowed_distribution(network, batch, mask, candidates)
                drawn, log_p = mine.actions_and_log_prob(deterministic=True)
                assert torch.equal(drawn, eager.get_actions(deterministic=True))
                assert torch.equal(log_p, eager.log_prob(drawn))
        loss = allowed_distribution(network, flat, masks, candidates, traced).log_prob(actions).sum()
        optimiser.zero_grad()
        (-loss).backward()  # with gradients the eager network runs (TracedScores falls back to it)
        optimiser.step()
    assert set(traced.traces) == {1, 2}
