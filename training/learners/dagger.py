"""DAgger into a run folder (``fetchcarry train dagger``), labelling on the worker pool of ``fetchcarry generate``.

Iteration 0 is behaviour cloning on ``demonstrations`` expert episodes (seeds ``0 ..
demonstrations-1`` of the family: the seeds ``fetchcarry generate`` uses by default,
so BC on such a dataset and DAgger start from the same scenarios), or, with ``dataset``,
on the first ``demonstrations`` episodes of that phases dataset (the labels BC trains
on, with the projected moves; no expert episode is run again). Each later
iteration runs the current learner (deterministic, masked) for
``episodes_per_iteration`` episodes on new seeds (from :data:`LEARNER_SEED_BASE`); at
every state it visits, :class:`expert.ExpertPolicy` says what it would do, mapped to
the allowed candidate that stands for it (an expert action no candidate expresses, or
the expert's idle fallback, gives no label, unless ``nearest_moves``: then an expert move
no candidate expresses is labelled with the allowed move nearest it,
:func:`benchmarks.studies.projection.nearest_move`; a state visited again in the same episode,
as by a learner going round in circles, is labelled once). ``learner_families`` aims the
learner episodes at chosen families (episode ``k`` of an iteration draws from the
``k``-th, cycled; for example ``push`` and ``multi-2``, the ``training`` family's sources
where the learners fail most), while iteration 0 and the held-out measurement stay on
``family``. The labelled states join the aggregate
and the network is trained afresh on all of it (``epochs`` epochs, seed fixed), as in
Ross et al. (2011) with beta = 0 after the first iteration.

Labelling episodes run on the worker pool (or Ray) of ``fetchcarry generate``
(:func:`training.data.generate.run_episodes`): the learner's weights travel with the task.
After each iteration the learner is measured on held-out seeds (from
:data:`HELDOUT_SEED_BASE`, never trained on) and ``metrics.csv`` gains a row: the
expert labels so far and the held-out success. A checkpoint after every iteration
(the aggregate, the weights, the metrics) lets an interrupted run resume.

With ``config.obs_mode`` ``topdown`` or ``rgbd`` (the cnn encoder), every env of the run
is made in that mode: the expert still plans from the state the observation holds, and
the labelled states stored for the learner are its images (uint8, flattened).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

import fetchcarry_env  # noqa: F401  (registers the env ids)
from expert.policy import ExpertPolicy
from fetchcarry_env.observation import Capacity
from training.envs import make_env
from training.learners import runs
from training.learners.bc import BCConfig, BCPolicy, Demonstrations, fit
from training.learners.encoders import build_network, input_size, network_input
from training.learners.heldout import heldout_success
from training.learners.options import DaggerOptions, ImageOptions
from training.policies.phase_expert import nearest_move
from training.rollout import run_episode

LEARNER_SEED_BASE = 500_000  # learner episode k of iteration i uses LEARNER_SEED_BASE + (i-1) * per_iteration + k


@dataclass(frozen=True)
class LabelTask:
    """One labelling job for a worker: whose episodes (expert or learner) on which seeds (picklable)."""

    family: str
    seed_base: int  # episode k uses seed_base + k
    time_limit: float
    network: dict[str, Any] | None = None  # None: the expert acts; else config, capacity, candidates, features, weights
    nearest_moves: bool = False  # label an expert move no candidate expresses with the nearest allowed move
    families: tuple[str, ...] = ()  # episode k draws from families[k % len(families)]; () = family
    env_options: dict[str, Any] = field(default_factory=dict)  # gym.make's: obs mode, images, capacity ({}: state)

    def family_of(self, index: int) -> str:
        """The family episode ``index`` draws from."""
        return self.families[index % len(self.families)] if self.families else self.family


@dataclass
class LabelledEpisode:
    """The labelled states of one episode."""

    observations: np.ndarray  # (n, D) float32
    masks: np.ndarray  # (n, K) bool
    labels: np.ndarray  # (n,) int64
    steps: int  # steps of the episode
    success: bool
    unexpressible: int  # states whose expert action no allowed candidate expressed (no label)


def label_episode(task: LabelTask, index: int) -> LabelledEpisode:
    """Run episode ``index`` of ``task`` and label every visited state with the expert (a worker's job)."""
    torch.set_num_threads(1)
    env = make_env(runs.INTERFACE, family=task.family_of(index), **task.env_options)
    try:
        expert = ExpertPolicy(env, time_limit=task.time_limit, interface="env")  # env actions: the labeller maps them
        obs_mode = task.env_options.get("obs_mode", "state")
        labeller = _Labeller(env, expert, task.nearest_moves, acting=task.network is None, obs_mode=obs_mode)
        if task.network is None:  # the expert's own episode, whether or not a candidate expresses its action
            policy, step = expert, env.get_wrapper_attr("step_env_action")
        else:
            policy, step = _learner(task.network), None
        record = run_episode(env, policy, task.seed_base + index, stop_on_failure=False, step=step, observe=labeller)
        size, features = env.action_space.n, input_size(env.observation_space, obs_mode)
    finally:
        env.close()
    return labeller.episode(size, features, record.figures.steps, bool(record.info.get("is_success", False)))


class _Labeller:
    """The expert's label of every state an episode visits (an observer of :func:`training.rollout.run_episode`).

    ``acting``: the expert is the episode's policy, so its action at the state is the one
    to label; otherwise it is asked here. An action no allowed candidate expresses (or the
    expert's idle fallback) gives no label, unless ``nearest_moves`` labels an inexpressible
    move with the allowed move nearest it. A state visited again in the same episode (a
    learner going round in circles) is labelled once. The expert plans from the state; what is
    stored for the learner is what its network reads in ``obs_mode`` (the state vector, or
    the images flattened: :func:`~training.learners.encoders.network_input`).
    """

    def __init__(self, env: Any, expert: ExpertPolicy, nearest_moves: bool, *, acting: bool,
                 obs_mode: str = "state") -> None:  # fmt: skip
        self.env, self.expert, self.nearest_moves, self.acting = env, expert, nearest_moves, acting
        self.obs_mode = obs_mode
        self.index_of = env.get_wrapper_attr("index_of")
        self.observations: list[np.ndarray] = []
        self.masks: list[np.ndarray] = []
        self.labels: list[int] = []
        self.seen: set[bytes] = set()
        self.steps = self.unexpressible = 0  # states the expert was asked about; states without a label

    def __call__(self, observation: dict[str, np.ndarray], action: Any, mask: np.ndarray) -> None:
        if not self.acting:
            action, _ = self.expert.predict(observation, episode_start=np.array([self.steps == 0]), deterministic=True)
            self.steps += 1
        decision = self.expert.last_decision
        planned = decision is None or decision.failure is None
        label = self.index_of(action) if planned else None
        if label is None and self.nearest_moves and planned:
            label = nearest_move(self.env, action)
        key = np.asarray(observation["observation"]).tobytes()
        if label is None:
            self.unexpressible += 1
        elif key not in self.seen:
            self.seen.add(key)
            self.observations.append(network_input(observation, self.obs_mode))
            self.masks.append(mask)
            self.labels.append(int(label))

    def episode(self, size: int, features: int, steps: int, success: bool) -> LabelledEpisode:
        """The labelled states (``size`` candidates, ``features`` observation entries: also an episode with none)."""
        n = len(self.labels)
        dtype = np.float32 if self.obs_mode == "state" else np.uint8
        return LabelledEpisode(np.asarray(self.observations, dtype).reshape(n, features),
                               np.asarray(self.masks, bool).reshape(n, size), np.asarray(self.labels, np.int64),
                               steps, success, self.unexpressible)  # fmt: skip


def _dataset_episodes(dataset: str, episodes: int, candidates: int, features: int,
                      obs_mode: str = "state") -> LabelledEpisode:  # fmt: skip
    """The labelled states of the first ``episodes`` of the phases dataset ``dataset``, as one block."""
    from training.learners.imitation import demonstrations_from_dataset

    demonstrations, _ = demonstrations_from_dataset(dataset, episodes, obs_mode)
    if demonstrations.masks.shape[1] != candidates or demonstrations.observations.shape[1] != features:
        raise ValueError(f"dataset {dataset!r} was recorded with another capacity than the family's env")
    stats = demonstrations.stats
    return LabelledEpisode(demonstrations.observations, demonstrations.masks, demonstrations.labels,
                           int(stats["steps"]), False, int(stats["dropped"]))  # fmt: skip


def _learner(network: dict[str, Any]) -> BCPolicy:
    config = BCConfig(**network["config"])
    capacity = Capacity(**network["capacity"])
    model = build_network(config, capacity, network["candidates"], torch.zeros(1, network["features"]))
    model.load_state_dict({k: torch.as_tensor(v) for k, v in network["weights"].items()})
    return BCPolicy(model, config, capacity)


def _network_task(model: torch.nn.Module, config: BCConfig, capacity: Capacity, candidates: int, features: int):
    weights = {k: v.detach().numpy().copy() for k, v in model.state_dict().items()}
    return {"config": asdict(config), "capacity": asdict(capacity), "candidates": candidates, "features": features,
            "weights": weights}  # fmt: skip


def _resumed(
    folder: Path,
    checkpoint: dict[str, Any],
    iterations: int,
    config: BCConfig,
    capacity: Capacity,
    sizes: tuple[int, int],
) -> tuple[Demonstrations, list[dict[str, Any]], Any]:
    """The labelled states, rows and network of a checked DAgger checkpoint; RunFolderError if they do not fit."""
    file = folder / runs.CHECKPOINT_FILE
    rows = [dict(r) for r in checkpoint["metrics"]]
    if len(rows) > iterations:
        raise runs.RunFolderError(f"{file}: {len(rows):,} iterations done, more than this run's {iterations}")
    candidates, features = sizes
    arrays = [checkpoint.get(key) for key in ("observations", "masks", "labels")]
    shapes = [(features,), (candidates,), ()]
    if not all(isinstance(a, torch.Tensor) and a.ndim == 1 + len(s) and tuple(a.shape[1:]) == s
               for a, s in zip(arrays, shapes, strict=True)) or len({len(a) for a in arrays}) != 1:  # fmt: skip
        raise runs.RunFolderError(f"{file}: its labelled states do not fit this run ({candidates} candidates)")
    aggregate = Demonstrations(arrays[0].numpy(), arrays[1].numpy().astype(bool), arrays[2].numpy())
    network = build_network(config, capacity, candidates, torch.zeros(1, features))
    try:
        network.load_state_dict(checkpoint.get("network"))
    except (RuntimeError, TypeError, AttributeError, KeyError) as error:
        raise runs.RunFolderError(f"{file}: its network does not fit this run ({type(error).__name__})") from None
    return aggregate, rows, network


def _probe(family: str, env_options: dict[str, Any]) -> tuple[Capacity, int, int]:
    """The capacity, candidates and network input size of ``family``'s phases env in ``env_options``."""
    probe = make_env(runs.INTERFACE, family=family, **env_options)
    try:
        space = probe.observation_space
        return probe.unwrapped.capacity, int(probe.action_space.n), input_size(space, config_mode(env_options))
    finally:
        probe.close()


def config_mode(env_options: dict[str, Any]) -> str:
    """The observation mode ``env_options`` (``gym.make`` keywords) name: ``state`` without one."""
    return env_options.get("obs_mode", "state")


def _empty(features: int, candidates: int, obs_mode: str) -> Demonstrations:
    dtype = np.float32 if obs_mode == "state" else np.uint8
    return Demonstrations(np.zeros((0, features), dtype), np.zeros((0, candidates), bool), np.zeros(0, np.int64))


def train_dagger(
    family: str,
    options: DaggerOptions,
    config: BCConfig,
    out: str | Path,
    images: ImageOptions | None = None,
    *,
    workers: int = 1,
    backend: str = "process",
    resume: bool = False,
    progress: bool = True,
) -> list[dict[str, Any]]:
    """DAgger into the run folder ``out``; its metrics rows (one per iteration, 0 first). The dagger learner's train.

    The expert always plans from the state; the learner sees ``config.obs_mode`` (with
    ``images``' options for topdown or rgbd): its episodes, the labelled states it trains
    on and its held-out episodes run in envs of that mode.
    """
    from training.data.generate import run_episodes

    config = BCConfig(**{**asdict(config), "epochs": options.epochs})
    image_options = (images or ImageOptions()).env_options(config.obs_mode)  # what the run records
    env_options = {**image_options, "capacity": options.capacity}  # what its envs are made with (None: the family's)
    capacity, candidates, features = _probe(family, env_options)
    from_dataset = None  # read before the run folder is made: a bad dataset leaves nothing behind
    if options.dataset is not None:
        from_dataset = _dataset_episodes(options.dataset, options.demonstrations, candidates, features,
                                         config.obs_mode)  # fmt: skip
    run_options = {"family": family, **asdict(options), **asdict(config)}
    run_options["learner_families"] = list(options.learner_families)  # as config.json reads back, for --resume
    if options.capacity is None:
        del run_options["capacity"]  # the family's: config.json as before --capacity existed
    if image_options:
        run_options["images"] = {k: v for k, v in image_options.items() if k != "obs_mode"}
    config_json = runs.run_config("dagger", run_options, config, capacity, candidates, features, {},
                                  observation=image_options or {"obs_mode": "state"})  # fmt: skip
    folder, checkpoint = runs.start_run(out, config_json, resume=resume)
    if runs.read_config(folder).get("complete"):
        return runs.read_metrics(folder)
    total = options.demonstrations + options.iterations * options.episodes_per_iteration
    if checkpoint is not None:
        episodes_done = runs.checkpoint_counter(folder, checkpoint, "episodes", total)
        aggregate, rows, network = _resumed(folder, checkpoint, options.iterations + 1, config, capacity,
                                            (candidates, features))  # fmt: skip
    else:
        aggregate, rows, episodes_done, network = _empty(features, candidates, config.obs_mode), [], 0, None
    started = time.perf_counter() - (rows[-1]["seconds"] if rows else 0.0)
    with tqdm(total=total, initial=episodes_done, desc=f"dagger {folder.name}", unit="episode",
              disable=not progress) as bar:  # fmt: skip
        for iteration in range(len(rows), options.iterations + 1):
            if iteration == 0:
                task = LabelTask(family, 0, options.time_limit, env_options=env_options)
                count = options.demonstrations
            else:
                base = LEARNER_SEED_BASE + (iteration - 1) * options.episodes_per_iteration
                task = LabelTask(family, base, options.time_limit,
                                 _network_task(network, config, capacity, candidates, features),
                                 options.nearest_moves, options.learner_families, env_options)  # fmt: skip
                count = options.episodes_per_iteration
            if iteration == 0 and from_dataset is not None:
                bar.update(count)
                ordered = [from_dataset]
            else:
                labelled: dict[int, LabelledEpisode] = {}
                for index, episode in run_episodes(task, list(range(count)), workers=workers, backend=backend,
                                                   episode=label_episode):  # fmt: skip
                    labelled[index] = episode
                    bar.update(1)
                ordered = [labelled[k] for k in range(count)]
            aggregate = _joined(aggregate, ordered)
            episodes_done += count
            network, fit_rows = fit(aggregate, config, capacity)
            success, cost = heldout_success(BCPolicy(network, config, capacity), family, options.eval_episodes,
                                            **env_options)  # fmt: skip
            rows.append(_row(iteration, episodes_done, aggregate, ordered, fit_rows[-1], success, cost, started))
            runs.save_checkpoint(folder, {
                "observations": torch.as_tensor(aggregate.observations), "masks": torch.as_tensor(aggregate.masks),
                "labels": torch.as_tensor(aggregate.labels), "network": network.state_dict(), "metrics": rows,
                "episodes": episodes_done,
            })  # fmt: skip
            runs.write_metrics(folder, rows)
            bar.set_postfix_str(f"labels {len(aggregate)} held-out success {success:.0%}", refresh=False)
    config_json["data"] = {"expert_labels": len(aggregate), "episodes": episodes_done}
    runs.finish_run(folder, network, config_json)
    return rows


def _joined(aggregate: Demonstrations, episodes: list[LabelledEpisode]) -> Demonstrations:
    """``aggregate`` with the labelled states of ``episodes`` appended."""
    return Demonstrations(
        np.concatenate([aggregate.observations, *(e.observations for e in episodes)]),
        np.concatenate([aggregate.masks, *(e.masks for e in episodes)]),
        np.concatenate([aggregate.labels, *(e.labels for e in episodes)]),
    )


def _row(iteration: int, episodes: int, aggregate: Demonstrations, ordered: list[LabelledEpisode],
         fitted: dict[str, Any], success: float, cost: float, started: float) -> dict[str, Any]:  # fmt: skip
    """The metrics row of one iteration (the last epoch's loss and accuracy; the held-out success and cost)."""
    return {
        "iteration": iteration,
        "episodes": episodes,
        "expert_labels": len(aggregate),
        "unexpressible": sum(e.unexpressible for e in ordered),
        "learner_success": float(np.mean([e.success for e in ordered])) if iteration else float("nan"),
        "loss": fitted["loss"],
        "accuracy": fitted["accuracy"],
        "heldout_success": success,
        "heldout_cost": cost,
        "seconds": time.perf_counter() - started,
    }
