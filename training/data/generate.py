"""Generate a Minari dataset of episodes, in parallel, resumable.

Episode ``k`` of a dataset uses the seed ``seed + k``: the env draws its scenario from
``reset(seed=seed + k)`` (a family) or uses the fixed scenario, so any episode replays
exactly from its seed. Each episode runs in a fresh env (so that an episode does not
depend on the ones before it in the same worker) and comes back to this process,
which stages it at once (:mod:`training.data.staging`); when all are staged the dataset is
assembled (:mod:`training.data.datasets`) and the staging is removed.

Evaluation seeds are not for training: a dataset whose seeds reach :data:`EVAL_SEED_BASE`
(10^9, where every benchmark split's seeds start) is refused with
:class:`EvaluationSeedError` unless ``allow_evaluation_seeds`` (research on purpose).

Backends: ``process`` (default) runs episodes on a local process pool (``workers``
processes; one worker runs in this process); ``ray`` runs the same episode function
as Ray tasks, on a local Ray instance or the cluster ``ray_address`` names (Ray is an
optional extra: ``pip install ray``).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from typing import Any

from tqdm import tqdm

from fetchcarry_env.errors import InputError
from training.cluster import ray_session
from training.data.datasets import (
    REPLACED_FOLDER,
    assemble,
    check_free_space,
    dataset_exists,
    finished_with,
    publish,
    recover_replaced,
    validate_dataset_id,
)
from training.data.sources import (
    DEFAULT_TIME_LIMIT,
    ENV_ID,
    POLICIES,
    EpisodeSource,
    GenerationConfig,
)
from training.data.staging import DatasetLock, Staging, StagingError
from training.pool import first_finished, local_pool
from training.rollout import EpisodeRecord, run_episode

EVAL_SEED_BASE = 1_000_000_000  # the first evaluation seed; training and dataset seeds stay below it


class EvaluationSeedError(InputError):
    """Training data asked for on evaluation seeds (or a split's scenario) without the explicit override."""


def check_training_seeds(first: int, count: int, allow_evaluation_seeds: bool = False) -> None:
    """Refuse seeds ``first .. first + count - 1`` that reach :data:`EVAL_SEED_BASE` (unless allowed)."""
    last = first + count - 1
    if last >= EVAL_SEED_BASE and not allow_evaluation_seeds:
        raise EvaluationSeedError(
            f"seeds {first}..{last} reach the evaluation seeds (from {EVAL_SEED_BASE}, the benchmark's splits): "
            f"give a seed below {EVAL_SEED_BASE - count + 1}, or --allow-evaluation-seeds to train on them on purpose"
        )


__all__ = [
    "DATASET_TIME_LIMIT",
    "DEFAULT_TIME_LIMIT",
    "ENV_ID",
    "EVAL_SEED_BASE",
    "POLICIES",
    "EpisodeSource",
    "EvaluationSeedError",
    "GenerationConfig",
    "GenerationReport",
    "generate",
    "run_dataset_episode",
    "run_episodes",
    "run_indexed_episode",
]

BACKENDS = ("process", "ray")
DATASET_TIME_LIMIT = 120.0  # seconds: generate's safety stop a planning call, far above what the node budget takes


@dataclass(frozen=True)
class GenerationReport:
    """What a generation run did."""

    dataset_id: str
    episodes: int  # episodes in the dataset
    resumed: int  # episodes found staged from an earlier run
    generated: int  # episodes made by this run
    workers: int
    backend: str
    wall_s: float  # seconds of this run, assembly included
    assembly_s: float  # seconds spent writing the Minari dataset from the staged episodes
    figures: list[dict[str, Any]] = field(default_factory=list)  # EpisodeFigures of the episodes made now
    set_aside: list[str] = field(default_factory=list)  # staged episode files that could not be read (made again)
    already_complete: bool = False  # the dataset was already there, whole, with the same options


class DatasetExistsError(InputError):
    """A dataset with this id exists (and was made with other options)."""


class StagingMismatchError(InputError):
    """A partly generated dataset of this id was made with other options."""


class ClockDecidedError(InputError):
    """An expert's plan in an episode was decided by its safety stop (the wall clock), so not reproducible."""


def run_indexed_episode(source: EpisodeSource, index: int) -> EpisodeRecord:
    """Run episode ``index`` of ``source`` in a fresh env (the function every backend runs)."""
    return _run(source, index)[0]


def run_dataset_episode(source: EpisodeSource, index: int) -> EpisodeRecord:
    """:func:`run_indexed_episode` for a dataset: raises :class:`ClockDecidedError` when the
    safety stop (``source.time_limit``) decided a plan of the episode, since a dataset holds only
    episodes the planner's counted budgets decided (the same command writes the same dataset at
    any load).
    """
    record, policy = _run(source, index)
    if getattr(getattr(policy, "stats", None), "clock_stopped", 0):
        raise ClockDecidedError(
            f"episode {index} (seed {source.episode_seed(index)}): the safety stop of {source.time_limit:g} s "
            "decided a plan of the expert under this machine's load, and a dataset holds only plans that the "
            "planner's node budget decided; run the same command with a larger --time-limit (the finished "
            "episodes are kept)"
        )
    return record


def _run(source: EpisodeSource, index: int) -> tuple[EpisodeRecord, Any]:
    """Episode ``index`` of ``source`` in a fresh env, and the policy that acted in it."""
    env = source.build_env()
    try:
        policy = source.build_policy(env)
        record = run_episode(env, policy, source.episode_seed(index), record_masks=source.interface == "phases")
    finally:
        env.close()
    return record, policy


def generate(
    config: GenerationConfig,
    *,
    workers: int = 1,
    backend: str = "process",
    overwrite: bool = False,
    progress: bool = True,
    ray_address: str | None = None,
    on_episode: Callable[[int, EpisodeRecord], None] | None = None,
    allow_evaluation_seeds: bool = False,
) -> GenerationReport:
    """Make (or finish) the dataset ``config.dataset_id`` and return what was done.

    Holds the dataset id's lock for the whole run (:class:`DatasetBusyError` if another
    run holds it). A dataset that is already complete with the same options is left as
    it is (``already_complete`` in the report; a leftover staging is removed). Raises
    :class:`DatasetExistsError` when another dataset has the id (unless ``overwrite``:
    the new one is built aside and swapped in, so the old one stays until the new one is
    whole) and :class:`StagingMismatchError` when a staging of the id was made with
    other options. Staged episodes that cannot be read are set aside and made again
    (``set_aside`` in the report). ``on_episode`` is called after each episode is
    staged (tests use it to interrupt a run). Seeds that reach the evaluation seeds are an
    :class:`EvaluationSeedError` unless ``allow_evaluation_seeds``.
    """
    validate_dataset_id(config.dataset_id)
    check_training_seeds(config.source.seed, config.episodes, allow_evaluation_seeds)  # a fixed scenario: the CLI
    # checks its digest against the splits' (training.evaluation.protocol), which this layer cannot read
    if workers < 1:
        raise InputError(f"the number of workers must be at least 1, got {workers}")
    started = time.perf_counter()
    with DatasetLock(config.dataset_id):
        staging = Staging(config.dataset_id)
        recover_replaced(config.dataset_id, staging.path / REPLACED_FOLDER)
        if dataset_exists(config.dataset_id) and not overwrite:
            if finished_with(config.dataset_id, config.manifest(), config.episodes):
                staging.remove()
                return GenerationReport(
                    config.dataset_id, config.episodes, config.episodes, 0, workers, backend,
                    wall_s=time.perf_counter() - started, assembly_s=0.0, already_complete=True,
                )  # fmt: skip
            raise DatasetExistsError(f"dataset {config.dataset_id!r} already exists with other options")
        _check_staging(staging, config, overwrite)
        staging.start(config.manifest())
        set_aside = [str(source) for source, _ in staging.set_aside_corrupt()]
        done = {k for k in staging.staged() if k < config.episodes}
        missing = [k for k in range(config.episodes) if k not in done]
        with progress_bar(config.episodes, config.dataset_id, initial=len(done), enabled=progress) as bar:
            episodes = run_episodes(
                config.source, missing, workers=workers, backend=backend, ray_address=ray_address,
                episode=run_dataset_episode,
            )  # fmt: skip
            figures = _stage_episodes(staging, episodes, bar, on_episode)
        assembly_s = _assemble_and_publish(config, staging)
    return GenerationReport(
        dataset_id=config.dataset_id,
        episodes=config.episodes,
        resumed=len(done),
        generated=len(missing),
        workers=workers,
        backend=backend,
        wall_s=time.perf_counter() - started,
        assembly_s=assembly_s,
        figures=figures,
        set_aside=set_aside,
    )


def _stage_episodes(
    staging: Staging,
    episodes: Iterator[tuple[int, EpisodeRecord]],
    bar: tqdm,
    on_episode: Callable[[int, EpisodeRecord], None] | None,
) -> list[dict[str, Any]]:
    """Stage each of ``episodes`` as it finishes, advancing ``bar``; the figures of every episode staged."""
    figures: list[dict[str, Any]] = []
    for index, record in episodes:
        staging.write(index, record)
        figures.append(record.figures.to_dict())
        bar.update(1)
        bar.set_postfix_str(_postfix(figures), refresh=False)
        if on_episode is not None:
            on_episode(index, record)
    return figures


def _assemble_and_publish(config: GenerationConfig, staging: Staging) -> float:
    """Write the Minari dataset from the staging, move it into place and remove the staging; the seconds it took."""
    started = time.perf_counter()
    check_free_space(staging)
    built = assemble(config, staging)
    publish(built, config.dataset_id, staging.path / REPLACED_FOLDER)
    staging.remove()
    return time.perf_counter() - started


def _check_staging(staging: Staging, config: GenerationConfig, overwrite: bool) -> None:
    try:
        manifest = staging.manifest()
    except StagingError:
        if not overwrite:
            raise
        staging.remove()
        return
    if manifest is None or manifest == config.manifest():
        return
    if overwrite:
        staging.remove()
        return
    differences = sorted(
        k for k in set(manifest) | set(config.manifest()) if manifest.get(k) != config.manifest().get(k)
    )
    raise StagingMismatchError(
        f"a partly generated {config.dataset_id!r} exists with other options ({', '.join(differences)} differ)"
    )


def run_episodes(
    source: EpisodeSource,
    indices: list[int],
    *,
    workers: int = 1,
    backend: str = "process",
    ray_address: str | None = None,
    episode: Callable[[Any, int], Any] | None = None,
) -> Iterator[tuple[int, Any]]:
    """Episodes ``indices`` of ``source`` as ``(index, record)``, as they finish (not in order when parallel).

    ``episode(source, index)`` is what each worker runs (default :func:`run_indexed_episode`);
    another module-level function (DAgger's labelling) runs on the same pool or Ray backend,
    with ``source`` any picklable task description.
    """
    episode = run_indexed_episode if episode is None else episode
    if workers < 1:
        raise InputError(f"the number of workers must be at least 1, got {workers}")
    if backend not in BACKENDS:
        raise InputError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")
    if not indices:
        return
    if backend == "ray":
        yield from _run_ray(source, indices, workers, ray_address, episode)
    elif workers == 1:
        for index in indices:
            yield index, episode(source, index)
    else:
        yield from _run_pool(source, indices, workers, episode)


def _run_pool(
    source: Any, indices: list[int], workers: int, episode: Callable[[Any, int], Any]
) -> Iterator[tuple[int, Any]]:
    with local_pool(workers) as pool:
        pending = {pool.submit(episode, source, index): index for index in indices}
        while pending:
            for future in first_finished(pending):
                yield pending.pop(future), future.result()


def _run_ray(
    source: Any, indices: list[int], workers: int, address: str | None, episode: Callable[[Any, int], Any]
) -> Iterator[tuple[int, Any]]:
    with ray_session(workers, address) as ray:
        remote = ray.remote(num_cpus=1)(episode)
        in_flight_limit = 2 * workers  # keep few episodes in flight: an interruption loses only those
        queue = list(indices)
        pending: dict[Any, int] = {}
        try:
            while queue or pending:
                while queue and len(pending) < in_flight_limit:
                    index = queue.pop(0)
                    pending[remote.remote(source, index)] = index
                finished, _ = ray.wait(list(pending), num_returns=1)
                for ref in finished:
                    yield pending.pop(ref), ray.get(ref)
        finally:
            for ref in pending:
                ray.cancel(ref)


def _postfix(figures: list[dict[str, Any]]) -> str:
    successes = sum(f["success"] for f in figures)
    return f"success {successes}/{len(figures)}"


def progress_bar(total: int, description: str, *, initial: int = 0, enabled: bool = True) -> tqdm:
    """A tqdm bar over episodes (on stderr)."""
    return tqdm(
        total=total,
        initial=initial,
        desc=description,
        unit="episode",
        disable=not enabled,
        dynamic_ncols=True,
    )


def report_json(report: GenerationReport) -> str:
    return json.dumps(asdict(report), indent=2)
