"""The published table in one call: expert data, every learned baseline per training seed, the benchmark, the report.

:func:`reproduce` runs four stages into one folder ``DIR``:

1. **datasets**: the expert's episodes in the candidate-phase interface, on the
   ``training`` family (basic, push, corridor or multi-2: one and two objects, the
   ``iid`` split's families), as the Minari dataset ``fetchcarry/training-phases-v0``
   under ``DIR/datasets`` (``fetchcarry generate``'s resumable generation, on ``workers``);
2. **training**: per training seed, BC with the flat MLP and with the set encoder,
   DAgger (the expert labels the learner's states), DAgger aimed at the failures
   (``dagger-aimed``, when the budget has ``aimed_iterations``: BC on the whole dataset,
   then iterations whose learner episodes are ``push`` and ``multi-2`` draws), MaskablePPO from scratch and started
   from the BC (flat MLP) weights, and BC on the first 10, 30, ... episodes (the
   demonstrations curve), each a run folder ``DIR/runs/NAME-sSEED``, up to ``workers``
   at a time (:mod:`training.reproduce.jobs`); then, with two seeds or more, the
   ensemble of the seeds' ``dagger-aimed`` runs, ``DIR/runs/dagger-aimed-ensemble``;
3. **benchmark**: the references (expert, random, random-phases, greedy) and every run
   folder on every split, ``DIR/benchmark/SPLIT`` (``fetchcarry benchmark``'s outputs;
   the demonstrations curve's runs on ``iid`` only);
4. **report**: ``DIR/summary.md``, ``DIR/results.json`` and the plots
   (:mod:`training.reproduce.aggregate`).

Every stage runs on a local process pool (``backend="process"``) or on Ray (``"ray"``:
one Ray session for the three stages, a local instance of ``workers`` CPUs or the cluster
``ray_address`` names; each training run is one Ray task), with the same records and
weights either way (``tests/training/test_reproduce.py``). On Ray, a stage's CPU seconds
in ``timings.json`` count this process only (Ray's workers are not its children); each
run's own CPU seconds are measured where it trains, on either backend.

Every stage is skipped when complete, and each run folder, dataset and benchmark
resumes where it stopped, so running the same call again after an interruption loses
nothing finished. ``DIR/reproduce.json`` holds the budget (a folder is never continued
with another) and ``DIR/timings.json`` the seconds of every stage and run.
"""

from __future__ import annotations

import json
import os
import resource
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import MISSING, asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

from fetchcarry_env.errors import InputError
from fetchcarry_env.jsontext import JsonInputError, read_json
from training.cluster import ray_session
from training.data.generate import BACKENDS, generate
from training.data.sources import EpisodeSource, GenerationConfig
from training.evaluation.results import RESULTS, read_results, write_results
from training.evaluation.runner import run_benchmark
from training.evaluation.splits import get_split
from training.learners.options import BCRun, DaggerRun, EnsembleRun, PPORun
from training.reproduce.aggregate import write_published
from training.reproduce.budgets import TRAINING_FAMILY, Budget
from training.reproduce.jobs import TrainJob, is_complete, run_jobs
from training.reproduce.publish import record_commit
from training.reproduce.table import (
    CURVE_SPLIT,
    ENSEMBLE,
    REFERENCES,
    baselines,
    curve_label,
    has_ensemble,
    run_name,
    run_names,
)
from training.reproduce.weights import same_weights, weights_digest
from training.resolve import available

DATASET_ID = "fetchcarry/training-phases-v0"
SETTINGS_FILE, TIMINGS_FILE = "reproduce.json", "timings.json"
MAX_TIMINGS_BYTES = 10_000_000  # timings.json: seconds per stage and run
MAX_DIGESTS_BYTES = 10_000_000  # weights.json: one digest per run
WEIGHTS_DIGESTS = "weights.json"  # per benchmark folder: the digest of each run's weights as benchmarked (by content)
MINARI_ENV = "MINARI_DATASETS_PATH"


class ReproduceError(InputError):
    """A reproduction cannot start or continue with what it was given (its folder, seeds, workers)."""


@dataclass(frozen=True)
class Backend:
    """Where a reproduction's episodes and training runs go: ``workers`` at a time, on a pool or on Ray."""

    workers: int
    backend: str = "process"  # "process" or "ray"
    ray_address: str | None = None  # the Ray cluster to join; None: a local instance


def training_jobs(out: Path, seeds: int, budget: Budget) -> list[TrainJob]:
    """Every run of the table, longest-first within what can start (a PPO run from BC waits for its BC run)."""
    runs = out.resolve() / "runs"
    jobs: list[TrainJob] = []
    for seed in range(seeds):
        jobs.append(_bc(runs, "bc-mlp", seed, budget, "mlp"))
    for seed in range(seeds):
        init = str(runs / run_name("bc-mlp", seed))
        for label, options in (("ppo-scratch", budget.ppo_options(seed)), ("ppo-bc", budget.ppo_options(seed, init))):
            needs = (run_name("bc-mlp", seed),) if options.init else ()
            name = run_name(label, seed)
            jobs.append(TrainJob(name, "ppo", str(runs / name), PPORun(TRAINING_FAMILY, options), needs=needs))
    for seed in range(seeds):
        name = run_name("dagger", seed)
        jobs.append(TrainJob(name, "dagger", str(runs / name), DaggerRun(TRAINING_FAMILY, budget.dagger_options(),
                                                                         budget.bc_config("mlp", seed))))  # fmt: skip
        if budget.aimed_iterations:
            name = run_name("dagger-aimed", seed)
            jobs.append(TrainJob(name, "dagger", str(runs / name), DaggerRun(
                TRAINING_FAMILY, budget.aimed_options(DATASET_ID), budget.bc_config("mlp", seed))))  # fmt: skip
        jobs.append(_bc(runs, "bc-set", seed, budget, "set"))
    if has_ensemble(seeds, budget):
        members = run_names("dagger-aimed", seeds)
        jobs.append(TrainJob(ENSEMBLE, "ensemble", str(runs / ENSEMBLE),
                             EnsembleRun(tuple(str(runs / name) for name in members)), needs=members))  # fmt: skip
    for seed in range(seeds):
        jobs += [_bc(runs, curve_label(n), seed, budget, "mlp", n) for n in budget.curve]
    return jobs


def _bc(runs: Path, label: str, seed: int, budget: Budget, encoder: str, episodes: int | None = None) -> TrainJob:
    name = run_name(label, seed)
    return TrainJob(name, "bc", str(runs / name), BCRun(DATASET_ID, episodes, budget.bc_config(encoder, seed)))


@contextmanager
def minari_root(path: Path) -> Iterator[None]:
    """Minari's datasets under ``path`` while the block runs (spawned workers inherit it)."""
    before = os.environ.get(MINARI_ENV)
    os.environ[MINARI_ENV] = str(path)
    try:
        yield
    finally:
        if before is None:
            os.environ.pop(MINARI_ENV, None)
        else:
            os.environ[MINARI_ENV] = before


def check_settings(out: Path, seeds: int, budget: Budget) -> None:
    """Refuse a folder made with another budget (:class:`ReproduceError`); record this one's settings."""
    if seeds < 1:
        raise ReproduceError(f"the number of training seeds must be at least 1, got {seeds}")
    file = out / SETTINGS_FILE
    settings: dict[str, Any] = {"budget": asdict(budget)}
    if file.is_file():
        try:
            saved = read_json(file, MAX_TIMINGS_BYTES)
        except JsonInputError as error:
            raise ReproduceError(f"{file}: {error}") from None
        saved_budget = saved.get("budget") if isinstance(saved, dict) else None
        if isinstance(saved_budget, dict):  # a field added since the folder was made: as it was, its default
            defaults = {f.name: f.default for f in fields(Budget) if f.default is not MISSING}
            saved_budget = {**json.loads(json.dumps(defaults)), **saved_budget}
        if json.loads(json.dumps(settings["budget"])) != saved_budget:
            name = saved_budget.get("name") if isinstance(saved_budget, dict) else "?"
            raise ReproduceError(f"{out} holds a reproduction with another budget ({name}): use another folder")
        saved_seeds = saved.get("seeds", seeds)  # a folder without the field: not known, so not refused
        if saved_seeds != seeds:  # the ensemble, the benchmark and the table were made for those seeds
            sane = isinstance(saved_seeds, int) and 1 <= saved_seeds <= 10**6
            again = f"run it with --seeds {saved_seeds}, or" if sane else f"delete its {SETTINGS_FILE}, or"
            raise ReproduceError(
                f"{out} holds a reproduction of {saved_seeds if sane else 'other'} training seeds, not {seeds}: "
                f"{again} use another folder"
            )
        commits = saved.get("commits") if isinstance(saved, dict) else None
        settings["commits"] = commits if isinstance(commits, list) else []  # publish.record_commit adds this call's
    elif out.exists() and any(out.iterdir()):
        raise ReproduceError(f"{out} exists and is not an empty folder or a reproduction folder")
    out.mkdir(parents=True, exist_ok=True)
    (out / SETTINGS_FILE).write_text(json.dumps({**settings, "seeds": seeds}, indent=2) + "\n")


class Timings:
    """Wall-clock and CPU seconds per stage and per run, kept in ``DIR/timings.json`` across interrupted calls.

    CPU seconds count this process and its finished workers (``getrusage``): on a shared
    machine they say what a stage costs better than its wall-clock time does.
    """

    def __init__(self, out: Path) -> None:
        self.file = out / TIMINGS_FILE
        try:
            data = read_json(self.file, MAX_TIMINGS_BYTES)
        except FileNotFoundError:
            data = {}
        except JsonInputError as error:
            raise ReproduceError(f"{self.file}: {error} (delete it to start the timings again)") from None
        if not _is_timings(data):
            raise ReproduceError(
                f"{self.file} is not a timings file (stages and runs, each with wall and cpu seconds): "
                "delete it to start the timings again"
            )
        self.data: dict[str, Any] = data
        self.data.setdefault("stages", {})
        self.data.setdefault("runs", {})

    def add(self, group: str, name: str, wall: float, cpu: float) -> None:
        entry = self.data[group].get(name)
        entry = entry if isinstance(entry, dict) else {"wall": 0.0, "cpu": 0.0}
        self.data[group][name] = {"wall": round(entry["wall"] + wall, 1), "cpu": round(entry["cpu"] + cpu, 1)}
        self.file.write_text(json.dumps(self.data, indent=2) + "\n")

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        """Add the block's wall-clock and CPU seconds (this process and its workers) to stage ``name``."""
        started, cpu = time.perf_counter(), cpu_seconds()
        yield
        self.add("stages", name, time.perf_counter() - started, cpu_seconds() - cpu)


def _is_timings(data: Any) -> bool:
    """Whether ``data`` is what :class:`Timings` writes: ``{"stages"|"runs": {name: {"wall": s, "cpu": s}}}``."""
    if not isinstance(data, dict):
        return False
    groups = [data.get(group, {}) for group in ("stages", "runs")]
    entries = [entry for group in groups if isinstance(group, dict) for entry in group.values()]
    return all(isinstance(group, dict) for group in groups) and all(
        isinstance(entry, dict) and all(_is_seconds(entry.get(k)) for k in ("wall", "cpu")) for entry in entries
    )


def _is_seconds(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def cpu_seconds() -> float:
    """CPU seconds (user and system) of this process and of its children that have finished."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def reproduce(
    out: str | Path,
    *,
    seeds: int = 3,
    budget: Budget,
    workers: int = 2,
    backend: str = "process",
    ray_address: str | None = None,
    progress: bool = True,
    datasets: str | Path | None = None,
    say: Callable[[str], None] = print,
) -> Path:
    """Run (or finish) the published table into ``out``; return the path of its ``summary.md``.

    ``backend`` is ``process`` (a local pool of ``workers``) or ``ray`` (Ray, ``workers``
    tasks at a time; on the cluster ``ray_address`` if given, else a local instance).
    ``datasets`` is the Minari root for the expert dataset (default ``out/datasets``).
    ``say`` gets one line per stage and per finished run. Bad input raises
    :class:`ReproduceError` (a ``ValueError``); any other exception is a bug;
    ``KeyboardInterrupt`` propagates with everything finished kept.
    """
    if workers < 1:
        raise ReproduceError(f"the number of workers must be at least 1, got {workers}")
    if backend not in BACKENDS:
        raise ReproduceError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")
    out = Path(out)
    check_settings(out, seeds, budget)
    commits = record_commit(out)
    timings = Timings(out)
    root = Path(datasets) if datasets is not None else out / "datasets"
    where = Backend(workers, backend, ray_address)
    with minari_root(root.resolve()), ray_session(workers, ray_address) if backend == "ray" else nullcontext():
        _stage_datasets(budget, where, progress, timings, say)
        _stage_training(out, seeds, budget, where, timings, say)
        _stage_benchmark(out, seeds, budget, where, progress, timings, say)
    with timings.stage("report"):
        summary = write_published(out, baselines(seeds, budget), budget, seeds, timings.data, commits)
    say(f"[4/4] report: {summary}, {out / 'results.json'} and the plots in {out}")
    return summary


def _stage_datasets(budget: Budget, where: Backend, progress: bool, timings: Timings, say: Callable) -> None:
    source = EpisodeSource(
        family=TRAINING_FAMILY, interface="phases", time_limit=budget.time_limit, capacity=budget.capacity
    )
    config = GenerationConfig(DATASET_ID, budget.demonstrations, source)
    say(f"[1/4] datasets: {DATASET_ID}, {budget.demonstrations} expert episodes of family {TRAINING_FAMILY}")
    started, cpu = time.perf_counter(), cpu_seconds()
    report = generate(config, workers=where.workers, backend=where.backend, ray_address=where.ray_address,
                      progress=progress)  # fmt: skip
    if report.already_complete:
        say("[1/4] datasets: already complete")
        return
    timings.add("stages", "datasets", time.perf_counter() - started, cpu_seconds() - cpu)
    say(f"[1/4] datasets: done in {report.wall_s:.0f} s ({report.resumed} episodes resumed)")


def _stage_training(out: Path, seeds: int, budget: Budget, where: Backend, timings: Timings, say: Callable) -> None:
    jobs = training_jobs(out, seeds, budget)
    todo = [job for job in jobs if not is_complete(job)]
    say(f"[2/4] training: {len(jobs)} runs in {out / 'runs'}, {len(jobs) - len(todo)} already complete")
    if not todo:
        return
    complete = {job.name for job in jobs} - {job.name for job in todo}
    todo = [replace(job, needs=tuple(n for n in job.needs if n not in complete)) for job in todo]
    with timings.stage("training"):
        finished = run_jobs(todo, where.workers, where.backend, where.ray_address)
        for count, (job, (wall, cpu)) in enumerate(finished, start=1):
            timings.add("runs", job.name, wall, cpu)
            say(f"[2/4] training {count}/{len(todo)}: {job.name} done in {wall:.0f} s ({cpu:.0f} CPU s)")


def _stage_benchmark(
    out: Path, seeds: int, budget: Budget, where: Backend, progress: bool, timings: Timings, say: Callable
) -> None:
    references = [name for name in REFERENCES if name in available()]
    runs = out / "runs"
    for split in budget.splits:
        learned = [b for b in baselines(seeds, budget) if split == CURVE_SPLIT or not b.label.startswith("bc-mlp-n")]
        policies = references + [str(runs / name) for b in learned for name in b.runs]
        folder = out / "benchmark" / split
        episodes = split_episodes(split, budget)
        total = len(policies) * episodes
        started, cpu = time.perf_counter(), cpu_seconds()
        forget_retrained(folder, [runs / name for b in learned for name in b.runs])
        report = run_benchmark(policies, out=folder, split=split, episodes=episodes, workers=where.workers,
                               backend=where.backend, ray_address=where.ray_address, progress=progress,
                               resume=True)  # fmt: skip
        if report.resumed == total:
            say(f"[3/4] benchmark {get_split(split).name}: already complete ({total} episodes)")
            continue
        timings.add("stages", f"benchmark {split}", time.perf_counter() - started, cpu_seconds() - cpu)
        say(f"[3/4] benchmark {get_split(split).name}: {total} episodes ({report.resumed} resumed) "
            f"in {time.perf_counter() - started:.0f} s")  # fmt: skip


def split_episodes(split: str, budget: Budget) -> int:
    """The benchmark episodes of ``split``: the budget's, or fewer where the split's test part has fewer references."""
    return min(budget.episodes, get_split(split).episodes)


def forget_retrained(folder: Path, runs: list[Path]) -> None:
    """Drop from ``folder/results.json`` the episodes of runs whose weights changed since they were benchmarked.

    ``folder/weights.json`` keeps a digest of each run's weights as benchmarked
    (:func:`~training.reproduce.weights.weights_digest`, by content: a run retrained to the
    same tensors keeps its episodes; an older folder's file hash is still read), so a run
    folder trained again with other weights is benchmarked again rather than kept with
    the episodes of its former weights.
    """
    file = folder / WEIGHTS_DIGESTS
    try:
        before = read_json(file, MAX_DIGESTS_BYTES)
    except (FileNotFoundError, JsonInputError):  # none or unreadable: every run is benchmarked again
        before = {}
    if not isinstance(before, dict):
        before = {}
    changed = {run.name for run in runs if not same_weights(run / "model.pt", before.get(run.name))}
    now = {run.name: weights_digest(run / "model.pt") for run in runs}
    results = folder / RESULTS
    if changed and results.is_file():
        records = read_results(results)
        kept = [r for r in records if not (isinstance(r, dict) and r.get("policy") in changed)]
        if len(kept) < len(records):
            write_results(results, kept)
    folder.mkdir(parents=True, exist_ok=True)
    file.write_text(json.dumps(now, indent=1) + "\n")
