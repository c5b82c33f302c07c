"""Behaviour cloning on the candidate-phase interface: the expert's choices as a classification.

The expert's actions, labelled as candidates of ``FetchCarryPushPhases-v0``
(:func:`record_demonstrations`), train a network that scores every candidate from
the observation; the scores of masked candidates are set to minus infinity, in the
loss and when acting, so the policy always picks an allowed candidate (never a phase
the env would refuse). Two encoders (:mod:`training.learners.encoders`): ``mlp``, a
flat MLP over the observation vector, and ``set``, an object-centric set encoder.

:func:`fit` is the training loop (with a checkpoint after every epoch if asked), which
``fetchcarry train bc`` and DAgger use too; :func:`train_bc` trains on demonstrations
in memory and can write a run folder (:mod:`training.learners.runs`), which
:func:`training.load_policy` reads back as a :class:`BCPolicy` (stable-baselines3's
``predict`` protocol).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from fetchcarry_env.observation import FIELDS, Capacity, observation_layout
from fetchcarry_env.phases import PhaseLayout
from training.data.expert_labels import Demonstrations, record_demonstrations  # noqa: F401  (re-exported)
from training.learners import runs
from training.learners.encoders import CandidateScorer, build_network, network_input
from training.learners.options import BCConfig
from training.policies.protocol import MaskedPolicy

CHECKPOINT_FIELDS = ("network", "optimiser", "order", "metrics", "epoch")  # what fit saves after every epoch
METRIC_COLUMNS = ("epoch", "loss", "accuracy", "seconds")  # a metrics row of an epoch (seconds since the start)


class BCPolicy(MaskedPolicy):
    """A trained scorer of candidates behind stable-baselines3's ``predict`` protocol.

    ``predict(observation, action_masks=mask)`` returns the allowed candidate with the
    highest score (``deterministic=True``) or one drawn from the softmax over allowed
    candidates; without ``action_masks`` it asks ``env`` (if given) for them.

    With ``config.avoid_repeats``, the policy remembers, within an episode, the candidates
    it chose in each state (its observation vector): back in a state it has been in, it
    leaves out the candidates it chose there before, as long as any other is allowed. In
    the deterministic env a deterministic policy that meets a state again would
    otherwise repeat the same round for good.

    With ``config.avoid_returns``, it also skips a move that would take it back to a state
    it has been in, before it gets there: the end of an ``approach`` or ``waypoint`` move
    depends only on the world (the clutter, the objects not in the hand, the heading),
    not on where the base starts (:mod:`fetchcarry_env.phases`), so each such move it
    has made this episode, from a world, teaches it that move's end state in that world
    (:class:`ReturnMemory`). Back in the same world, a move whose known end is a state
    it has met is left out, as long as any other candidate is allowed: a round
    A -> B -> A is cut at B instead of at A's second visit.

    With ``config.push_after_approach``, an approach move (a move to a pose from which a
    push of a piece is accepted) is not followed by another approach move, as long as any
    other candidate is allowed: in the expert's demonstrations an approach is always
    followed by a push (176 of 176 approaches in the 1,000 episodes of the ``training``
    family), while a learner was seen hopping from one approach pose to the next, up to
    ten times in a row, each hop adding travel.

    With ``config.skip_delivered``, a pick of an object whose ``delivered`` flag is set is
    left out, as long as any other candidate is allowed: the expert never picks a delivered
    object, while a set-encoder learner trained on ``objects-1-4`` was seen picking the
    object it had just delivered and placing it back, until the env's 50 phases ran out
    (the object lands a little elsewhere each time, so ``avoid_repeats`` never meets the
    same state again).

    The memory is per episode: it is cleared by :meth:`reset` and by ``episode_start``
    true; batched calls (one row per env) do not use it.

    One observation's decision computes the scores of the candidates it chooses from only
    (:meth:`candidate_scores`); a batch's, every score (:meth:`scores`).
    """

    deterministic_default = True

    def __init__(self, network: nn.Module, config: BCConfig, capacity: Capacity, env: Any = None) -> None:
        self.network = flush_subnormal(network).eval()
        self.config = config
        self.capacity = capacity
        self.env = env
        self.rng = torch.Generator().manual_seed(config.seed)
        self.chosen: dict[bytes, set[int]] = {}  # this episode: state (observation bytes) -> candidates chosen there
        self.traced: dict[int, torch.jit.ScriptModule] = {}  # batch size -> the network as a TorchScript trace
        self._candidate_trace: torch.jit.ScriptModule | None = None  # candidate_scores of one row, traced
        self.returns = ReturnMemory(capacity, config.avoid_returns)
        self.last: int | None = None  # this episode: the candidate chosen at the previous decision
        self._approaches: np.ndarray | None = None  # the approach candidates' indices (push_after_approach)

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "traced": {}, "_candidate_trace": None}  # traces do not pickle: made again on use

    def reset(self) -> None:
        """Forget the episode's states (a new episode starts)."""
        self.chosen = {}
        self.returns.reset()
        self.last = None

    def env_masks(self) -> np.ndarray:
        """The masks of the env the policy was loaded with; a ``ValueError`` saying how to give them if none.

        ``predict`` never sees the env a caller steps (stable-baselines3's
        ``evaluate_policy(policy, env)`` gives it observations only), and the masks are
        not a function of the observation the policy could compute exactly, so the
        policy needs that env: ``load_policy(run, env)``.
        """
        if self.env is None:
            raise ValueError(
                "no action masks: give predict(..., action_masks=...), or load the policy with its env, "
                "load_policy(run, env), so that it asks the env (as stable-baselines3's evaluate_policy needs)"
            )
        return super().env_masks()

    def act(self, observation: Any, action_masks: np.ndarray | None, episode_start: Any, deterministic: bool) -> Any:
        """The best-scoring allowed candidate (sampled from the scores' softmax unless ``deterministic``)."""
        flat = network_input(observation, self.config.obs_mode) if isinstance(observation, dict) else observation
        flat = np.asarray(flat, np.float32)
        batched = flat.ndim == 2
        masks = self.env_masks() if action_masks is None else np.asarray(action_masks, dtype=bool)
        masks = masks.reshape(len(flat) if batched else 1, -1)
        if batched:
            return self._predict_rows(flat, masks, deterministic)
        if episode_start is not None and bool(np.asarray(episode_start).reshape(-1)[0]):
            self.reset()
        allowed = self._allowed(flat, masks[0])
        with torch.inference_mode():
            scores = self.candidate_scores(torch.as_tensor(flat[None]), torch.as_tensor(allowed))[0]
            if deterministic:
                pick = int(scores.argmax())
            else:
                pick = int(torch.multinomial(torch.softmax(scores, dim=0), 1, generator=self.rng)[0])
        action = int(allowed[pick])
        if self.config.avoid_repeats or self.config.avoid_returns or self.config.push_after_approach:
            self.chosen.setdefault(flat.tobytes(), set()).add(action)
            self.returns.leave(action)
            self.last = action
        return np.int64(action)

    def _allowed(self, flat: np.ndarray, mask: np.ndarray) -> np.ndarray:
        """The indices of the candidates to choose from in the state ``flat``: the allowed ones, less the memory's.

        The memory (``avoid_repeats``, ``avoid_returns``, ``push_after_approach``) leaves
        candidates out only as long as another one is allowed. With none allowed at all,
        every candidate (the env refuses whichever is chosen).
        """
        left_out: list[int] = []
        if self.config.avoid_repeats:
            left_out += self.chosen.get(flat.tobytes(), ())
        if self.config.avoid_returns:
            left_out += self.returns.arrive(flat, len(mask))
        if self.config.skip_delivered:
            left_out += delivered_picks(self.capacity, flat, len(mask)).tolist()
        if self.config.push_after_approach and self.last is not None:
            approaches = self._approach_indices(len(mask))
            if self.last in approaches:
                left_out += approaches.tolist()
        allowed = np.flatnonzero(mask)
        fresh = np.setdiff1d(allowed, left_out) if left_out else allowed
        if len(fresh):
            return fresh
        return allowed if len(allowed) else np.arange(len(mask))

    def _predict_rows(self, flat: np.ndarray, masks: np.ndarray, deterministic: bool) -> np.ndarray:
        """One action per row of a batch (one row per env), without the per-episode memory."""
        with torch.inference_mode():
            logits = self.scores(torch.as_tensor(flat)).masked_fill(~torch.as_tensor(masks), -torch.inf)
            if deterministic:
                actions = logits.argmax(dim=1)
            else:
                actions = torch.multinomial(torch.softmax(logits, dim=1), 1, generator=self.rng)[:, 0]
        return actions.numpy().astype(np.int64)

    def candidate_scores(self, flat: torch.Tensor, candidates: torch.Tensor) -> torch.Tensor:
        """The network's scores of ``candidates`` (indices) for one observation vector (a row).

        Only those candidates' scores are computed (``candidate_scores`` of
        :mod:`training.learners.encoders`: the flat MLP reads only their rows of its last
        layer, the set encoder mixes only the slots present): the same order as
        :meth:`scores` gives them, up to a constant for an ensemble. A decision needs the
        allowed candidates only (some 30 of 4,080); through the benchmark (25 ``iid``
        episodes, one worker, a quiet machine) this took a flat MLP from 1.59 to 0.73 ms
        a decision, the set encoder from 2.14 to 1.41 ms and an ensemble of three flat
        MLPs from 2.56 to 1.08 ms. Through a TorchScript trace, like :meth:`scores`, with
        subnormals flushed.
        """
        if self._candidate_trace is None:
            self._candidate_trace = _trace(CandidateScorer(self.network), (flat, candidates))
        with subnormals_flushed():
            return self._candidate_trace(flat, candidates)

    def scores(self, observations: torch.Tensor) -> torch.Tensor:
        """The network's scores of every candidate for a batch of observation vectors (rows).

        Runs a TorchScript trace of the network, made on the first call with each batch
        size (some 10-50 ms): the same operations on the same parameters, without the
        Python of every module call, which is most of a single decision's time (the set
        encoder: 1.6 against 1.15 ms on one core).

        The CPU flushes subnormal floats to zero during the call (``torch.set_flush_denormal``,
        off again afterwards: the env's physics runs in the same thread). Weight decay
        leaves the weights of candidates that never win tiny, and their products fall into
        float32's subnormal range, where arithmetic is many times slower: on one state
        asked again and again (warm caches), the flat MLP's last layer took 1.28 ms with
        them and an ensemble of three flat MLPs 3.2 against 1.0 ms. Through the benchmark,
        where the env steps between decisions, a decision also waits for its weights from
        memory, and the gain is small (a flat MLP 1.0-2.2 ms either way). Their share of a
        score is below 1e-35: the benchmark episodes of published runs took the same
        decisions with and without (two runs, 600 episodes).
        """
        traced = self.traced.get(len(observations))
        if traced is None:
            traced = self.traced[len(observations)] = _trace(self.network, observations)  # one per batch size
        with subnormals_flushed():
            return traced(observations)

    def _approach_indices(self, candidates: int) -> np.ndarray:
        if self._approaches is None:
            self._approaches = np.flatnonzero(candidates_of_kinds(self.capacity, candidates, ("approach",)))
        return self._approaches


class ReturnMemory:
    """Within an episode: where each approach and waypoint move went, per world, and the states met.

    A world is the observation with the base's x, y and the held object's position left
    out (what a move changes); the heading stays in (a move keeps it). Used by
    :class:`BCPolicy` with ``avoid_returns``; inactive (no work) when ``active`` is false.
    """

    def __init__(self, capacity: Capacity, active: bool) -> None:
        self.active = active
        self.visited: set[bytes] = set()
        self.ends: dict[bytes, dict[int, bytes]] = {}  # world -> move candidate -> the state it ended in
        self._last: tuple[bytes, int] | None = None  # the world and the move of the previous decision
        self._world_now = b""  # the world of the state last given to arrive
        self._moves: np.ndarray | None = None  # (K,) bool: the approach and waypoint candidates
        if active:
            layout = observation_layout(capacity)
            self._base = np.arange(layout["robot"].start, layout["robot"].start + 2)  # x, y
            width = len(FIELDS["object"])
            starts = np.arange(layout["objects"].start, layout["objects"].stop, width)
            self._held = starts + FIELDS["object"].index("held")
            self._position = starts[:, None] + np.arange(1, 4)  # x, y, z of each object slot
            self._capacity = capacity

    def reset(self) -> None:
        self.visited, self.ends, self._last = set(), {}, None

    def arrive(self, flat: np.ndarray, candidates: int) -> list[int]:
        """Note the state ``flat`` (one observation vector); the moves that would lead back to a state met."""
        if not self.active:
            return []
        key = flat.tobytes()
        self.visited.add(key)
        world = self._world(flat)
        if self._last is not None and self._last[0] == world:  # a move leaves the world as it was
            self.ends.setdefault(self._last[0], {})[self._last[1]] = key
        self._last = None
        self._world_now = world
        if self._moves is None or len(self._moves) != candidates:
            self._moves = candidates_of_kinds(self._capacity, candidates, ("approach", "waypoint"))
        return [move for move, end in self.ends.get(world, {}).items() if end in self.visited]

    def leave(self, candidate: int) -> None:
        """Note the candidate chosen in the state last given to :meth:`arrive`."""
        if self.active and self._moves is not None and self._moves[candidate]:
            self._last = (self._world_now, candidate)

    def _world(self, flat: np.ndarray) -> bytes:
        world = flat.copy()
        world[self._base] = 0.0
        held = world[self._held] > 0.5
        world[self._position[held].reshape(-1)] = 0.0
        return world.tobytes()


def delivered_picks(capacity: Capacity, flat: np.ndarray, candidates: int) -> np.ndarray:
    """The indices of the pick candidates of the objects that ``flat`` (one observation vector) shows delivered."""
    objects = flat[observation_layout(capacity)["objects"]].reshape(capacity.objects, len(FIELDS["object"]))
    fields = FIELDS["object"]
    delivered = (objects[:, fields.index("present")] > 0.5) & (objects[:, fields.index("delivered")] > 0.5)
    return _picks_per_object(capacity, candidates)[delivered].reshape(-1)


@lru_cache(maxsize=8)
def _picks_per_object(capacity: Capacity, candidates: int) -> np.ndarray:
    """(objects, picks per object): the pick candidates' indices, one row per object slot."""
    picks = np.flatnonzero(candidates_of_kinds(capacity, candidates, ("pick",)))
    return picks.reshape(capacity.objects, -1)


def candidates_of_kinds(capacity: Capacity, candidates: int, kinds: tuple[str, ...]) -> np.ndarray:
    """(K,) bool: the candidates of the phase layout's ``kinds`` (``"approach"``, ``"waypoint"``, ...)."""
    layout = PhaseLayout.for_postures(capacity=capacity)
    if layout.size != candidates:
        raise ValueError(f"the network scores {candidates} candidates, the phase layout has {layout.size}")
    chosen = np.zeros(candidates, dtype=bool)
    for kind in kinds:
        chosen[layout.kind_slice(kind)] = True
    return chosen


def _trace(module: nn.Module, example: Any) -> torch.jit.ScriptModule:
    """``module`` as a TorchScript trace on ``example`` inputs (the batch size is baked in: no warning about it)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", torch.jit.TracerWarning)
        return torch.jit.trace(module, example, check_trace=False)


@contextmanager
def subnormals_flushed() -> Iterator[None]:
    """While the block runs, this thread's CPU treats subnormal floats as zero (off again afterwards).

    Where the CPU cannot (``torch.set_flush_denormal`` returns False), nothing changes.
    """
    flushing = torch.set_flush_denormal(True)
    try:
        yield
    finally:
        if flushing:
            torch.set_flush_denormal(False)


def flush_subnormal(network: nn.Module) -> nn.Module:
    """Set the network's subnormal weights (below float32's smallest normal, ~1.2e-38) to zero, in place.

    Weight decay drives the weights of candidates that never win towards zero, through
    the subnormal range, where CPU arithmetic is many times slower: a trained flat MLP's
    decision took 2.1 ms with them and 0.2 ms without (one thread). Their share of any
    score is below 1e-37, so no decision changes.
    """
    with torch.no_grad():
        for parameter in network.parameters():
            if parameter.is_floating_point():
                parameter[parameter.abs() < torch.finfo(parameter.dtype).tiny] = 0.0
    return network


def fit(
    demonstrations: Demonstrations,
    config: BCConfig,
    capacity: Capacity,
    *,
    checkpoint: dict[str, Any] | None = None,
    save: Callable[[dict[str, Any]], None] | None = None,
    on_epoch: Callable[[dict[str, Any]], None] | None = None,
    checkpoint_file: Path | None = None,
) -> tuple[nn.Module, list[dict[str, Any]]]:
    """Train a fresh network for ``config.epochs`` epochs; return it and one metrics row per epoch.

    ``checkpoint`` (what ``save`` was last given) resumes training after its epoch;
    ``save`` is called with the training state after every epoch. Deterministic on CPU
    for one ``config.seed``, interrupted or not. A checkpoint is checked field by field
    against the network, optimiser and generator it resumes (:func:`check_checkpoint`)
    before any of it is loaded: :class:`~training.learners.runs.RunFolderError` (bad input)
    naming ``checkpoint_file`` (the file it was read from) and the field.

    The CPU flushes subnormal floats to zero while it trains (``torch.set_flush_denormal``,
    off again afterwards): weight decay drives the weights of candidates that never win
    into float32's subnormal range, where arithmetic is many times slower. The published
    dataset's flat MLP trains its 60 epochs in 36 s instead of 107 s, with the same
    loss and accuracy at every epoch; its weights differ by less than 4e-30.
    """
    if len(demonstrations) == 0:
        raise ValueError("no labelled demonstrations to learn from")
    with subnormals_flushed():
        return _fit(demonstrations, config, capacity, checkpoint, save, on_epoch, checkpoint_file)


def _fit(
    demonstrations: Demonstrations,
    config: BCConfig,
    capacity: Capacity,
    checkpoint: dict[str, Any] | None,
    save: Callable[[dict[str, Any]], None] | None,
    on_epoch: Callable[[dict[str, Any]], None] | None,
    checkpoint_file: Path | None,
) -> tuple[nn.Module, list[dict[str, Any]]]:
    torch.set_num_threads(1)  # faster here than two threads, and the same sums every run
    torch.manual_seed(config.seed)
    observations = torch.as_tensor(demonstrations.observations)
    masks = torch.as_tensor(demonstrations.masks)
    labels = torch.as_tensor(demonstrations.labels)
    network = build_network(config, capacity, masks.shape[1], observations)
    optimiser = torch.optim.Adam(network.parameters(), lr=config.learning_rate, weight_decay=config.weight_decay)
    order = torch.Generator().manual_seed(config.seed)
    metrics: list[dict[str, Any]] = []
    first = 0
    elapsed = 0.0
    if checkpoint is not None:
        file = checkpoint_file or Path(runs.CHECKPOINT_FILE)
        check_checkpoint(file, checkpoint, config.epochs, network, optimiser, order)
        network.load_state_dict(checkpoint["network"])
        optimiser.load_state_dict(checkpoint["optimiser"])
        order.set_state(checkpoint["order"])
        metrics = [dict(row) for row in checkpoint["metrics"]]
        first = int(checkpoint["epoch"])
        elapsed = float(metrics[-1]["seconds"]) if metrics else 0.0
    start = time.perf_counter() - elapsed
    for epoch in range(first, config.epochs):
        network.train()
        total = correct = 0
        loss_sum = 0.0
        for batch in torch.randperm(len(labels), generator=order).split(config.batch_size):
            logits = network(observations[batch]).masked_fill(~masks[batch], -1e9)
            loss = nn.functional.cross_entropy(logits, labels[batch])
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            loss_sum += loss.item() * len(batch)
            correct += int((logits.argmax(dim=1) == labels[batch]).sum())
            total += len(batch)
        row = {"epoch": epoch + 1, "loss": loss_sum / total, "accuracy": correct / total,
               "seconds": time.perf_counter() - start}  # fmt: skip
        metrics.append(row)
        if save is not None:
            save({"network": network.state_dict(), "optimiser": optimiser.state_dict(), "order": order.get_state(),
                  "metrics": metrics, "epoch": epoch + 1})  # fmt: skip
        if on_epoch is not None:
            on_epoch(row)
    return network.eval(), metrics


def check_checkpoint(
    file: Path, checkpoint: Any, epochs: int, network: nn.Module, optimiser: torch.optim.Adam, order: torch.Generator
) -> None:
    """:class:`~training.learners.runs.RunFolderError` naming ``file`` and the field, unless ``checkpoint`` fits.

    A checkpoint of :func:`fit` holds exactly :data:`CHECKPOINT_FIELDS`: ``network`` (the
    fresh ``network``'s tensors: names, shapes, dtypes), ``optimiser`` (``optimiser``'s
    state: its settings, each parameter's moments), ``order`` (a state the ``order``
    generator takes), ``epoch`` (from 0 to ``epochs``) and ``metrics`` (one row of
    :data:`METRIC_COLUMNS` per epoch done).
    """
    if not isinstance(checkpoint, dict):
        raise runs.RunFolderError(f"{file} does not hold a training checkpoint (a dict of its state)")
    runs.check_checkpoint_fields(file, checkpoint, CHECKPOINT_FIELDS)
    runs.check_module_state(file, "network", checkpoint["network"], network)
    runs.check_adam_state(file, "optimiser", checkpoint["optimiser"], optimiser)
    runs.check_generator_state(file, "order", checkpoint["order"], order)
    epoch = runs.checkpoint_counter(file.parent, checkpoint, "epoch", epochs)
    runs.check_metric_rows(file, "metrics", checkpoint["metrics"], METRIC_COLUMNS, epoch)


def train_bc(
    demonstrations: Demonstrations,
    config: BCConfig,
    capacity: Capacity,
    out: str | Path | None = None,
    progress: Callable[[dict[str, Any]], None] | None = None,
) -> BCPolicy:
    """Train on ``demonstrations`` with :func:`fit`; write a ``bc`` run folder to ``out`` (a new folder).

    Deterministic on CPU for one ``config.seed``. ``progress``, if given, is called
    with each epoch's metrics (a dict). The run folder (:mod:`training.learners.runs`)
    loads with :func:`training.load_policy`; :class:`~training.learners.runs.RunFolderError`
    (bad input) if ``out`` holds a run already.
    """
    candidates, features = demonstrations.masks.shape[1], demonstrations.observations.shape[1]
    folder = None
    if out is not None:
        config_json = runs.run_config("bc", asdict(config), config, capacity, candidates, features,
                                      demonstrations.stats)  # fmt: skip
        folder, _ = runs.start_run(out, config_json, resume=False)
    network, metrics = fit(demonstrations, config, capacity, on_epoch=progress)
    if folder is not None:
        runs.write_metrics(folder, metrics)
        runs.finish_run(folder, network, config_json)
    return BCPolicy(network, config, capacity)
