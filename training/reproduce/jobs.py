"""Training jobs of a reproduction, up to ``workers`` at a time, each a resumable run folder.

A :class:`TrainJob` is one ``fetchcarry train KIND`` run: a registered learner's kind and
its options dataclass (:mod:`training.learners.registry`), plain and picklable;
:func:`run_job` trains it through the registry, as the command does, with ``resume=True``
(a complete run folder is left as it is; an interrupted one continues from its
checkpoint) and torch on one thread. :func:`run_jobs` runs jobs in this process (one
worker), on a spawned process pool (the worker set-up of ``fetchcarry generate``:
workers ignore Ctrl-C and die with their parent) or as Ray tasks (one task per run
folder, on a local Ray instance or the cluster ``ray_address`` names: the run folders
and the Minari datasets must then be on a file system every node sees), starting a job
once the jobs it needs (a PPO run's BC init) are done. On Ctrl-C the running jobs are
stopped at once; what finished stays, and their checkpoints let the same call continue.
"""

from __future__ import annotations

import os
import time
from collections.abc import Iterator
from concurrent.futures import Future
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from training.cluster import ray_session
from training.data.generate import BACKENDS
from training.learners import registry
from training.pool import first_finished, local_pool

MINARI_ENV = "MINARI_DATASETS_PATH"  # where a job's datasets are: handed to every Ray task


@dataclass(frozen=True)
class TrainJob:
    """One run folder to train: the learner ``kind`` with its ``options``, after the jobs named in ``needs``."""

    name: str  # the run folder's name (unique: the benchmark labels policies by it)
    kind: str  # a registered learner: "bc", "dagger", "ppo", "ensemble", ...
    out: str  # the run folder
    options: Any  # the learner's options dataclass (BCRun, DaggerRun, PPORun, EnsembleRun, ...)
    needs: tuple[str, ...] = field(default=())  # names of jobs that must finish first

    def __getattr__(self, name: str) -> Any:
        """An option of the job reads as the job's own (``job.members``, ``job.family``: as before options existed)."""
        if name == "options" or name.startswith("__"):  # not set yet (unpickling): no recursion
            raise AttributeError(name)
        try:
            return getattr(self.options, name)
        except AttributeError:
            raise AttributeError(f"{type(self).__name__} of kind {self.kind!r} has no {name!r}") from None


def is_complete(job: TrainJob) -> bool:
    """Whether ``job``'s run folder holds a finished run."""
    from training.learners.runs import CONFIG_FILE, read_saved

    folder = Path(job.out)
    return (folder / CONFIG_FILE).is_file() and bool(read_saved(folder).get("complete"))


def run_job(job: TrainJob) -> tuple[float, float]:
    """Train ``job`` (resuming its run folder); return the wall-clock and CPU seconds it took (this process)."""
    import torch

    torch.set_num_threads(1)
    started, cpu = time.perf_counter(), time.process_time()
    registry.train(job.kind, job.options, job.out, resume=True, progress=False)
    return time.perf_counter() - started, time.process_time() - cpu


def run_job_with(job: TrainJob, environment: dict[str, str]) -> tuple[float, float]:
    """:func:`run_job` with ``environment`` set first (a Ray worker does not inherit this process's)."""
    os.environ.update(environment)
    return run_job(job)


def run_jobs(
    jobs: list[TrainJob], workers: int = 1, backend: str = "process", ray_address: str | None = None
) -> Iterator[tuple[TrainJob, tuple[float, float]]]:
    """Train ``jobs`` (in list order, each after its ``needs``); yield each with its wall and CPU seconds.

    ``backend`` is ``process`` (this process with one worker, else a process pool) or
    ``ray`` (Ray tasks, ``workers`` at a time, on ``ray_address`` if given).
    """
    names = {job.name for job in jobs}
    unknown = sorted({need for job in jobs for need in job.needs} - names)
    if unknown:
        raise ValueError(f"training jobs need jobs that are not given: {', '.join(unknown)}")
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")
    if backend == "ray":
        yield from _run_ray(jobs, workers, ray_address)
        return
    if workers == 1:
        done: set[str] = set()
        while len(done) < len(jobs):
            job = next(j for j in jobs if j.name not in done and set(j.needs) <= done)
            yield job, run_job(job)
            done.add(job.name)
        return
    yield from _run_pool(jobs, workers)


def _run_pool(jobs: list[TrainJob], workers: int) -> Iterator[tuple[TrainJob, tuple[float, float]]]:
    """``workers`` jobs at a time on a local pool, each started once its ``needs`` are done.

    Ctrl-C or an error stops the running jobs at once; their checkpoints stay.
    """
    waiting, done = list(jobs), set()
    running: dict[Future, TrainJob] = {}
    with local_pool(workers) as pool:
        while waiting or running:
            for job in [j for j in waiting if set(j.needs) <= done][: workers - len(running)]:
                waiting.remove(job)
                running[pool.submit(run_job, job)] = job
            for future in first_finished(running):
                job = running.pop(future)
                seconds = future.result()
                done.add(job.name)
                yield job, seconds


def _run_ray(jobs: list[TrainJob], workers: int, address: str | None) -> Iterator[tuple[TrainJob, tuple[float, float]]]:
    """One Ray task per job, ``workers`` at a time, each started once its ``needs`` are done."""
    environment = {MINARI_ENV: os.environ[MINARI_ENV]} if MINARI_ENV in os.environ else {}
    with ray_session(workers, address) as ray:
        remote = ray.remote(num_cpus=1, max_retries=0)(run_job_with)
        waiting, done = list(jobs), set()
        running: dict[Any, TrainJob] = {}
        try:
            while waiting or running:
                for job in [j for j in waiting if set(j.needs) <= done][: workers - len(running)]:
                    waiting.remove(job)
                    running[remote.remote(job, environment)] = job
                if not running:
                    raise ValueError(f"training jobs wait for each other: {', '.join(j.name for j in waiting)}")
                finished, _ = ray.wait(list(running), num_returns=1)
                for ref in finished:
                    job = running.pop(ref)
                    seconds = ray.get(ref)
                    done.add(job.name)
                    yield job, seconds
        finally:
            for ref in running:  # Ctrl-C or an error: stop the running jobs now (their checkpoints stay)
                ray.cancel(ref, force=True)
