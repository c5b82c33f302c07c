"""Run units of work here, on a local process pool or on Ray, yielding their records as they finish.

The benchmark's episodes (:mod:`training.evaluation.runner`) and the references'
(:mod:`training.evaluation.references`) run through :func:`run_all`, with the worker
set-up of ``fetchcarry generate`` (:mod:`training.data.generate`): workers ignore Ctrl-C
and die with their parent. Ray is imported only when asked for (an optional extra).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from typing import Any

from training.cluster import ray_session
from training.pool import first_finished, local_pool


def run_all(
    tasks: Sequence[Any],
    function: Callable[[Any], dict[str, Any]],
    *,
    workers: int = 1,
    backend: str = "process",
    ray_address: str | None = None,
) -> Iterator[dict[str, Any]]:
    """``function(task)`` of every task, as they finish: here (one worker), on a pool, or on Ray.

    ``function`` is a module-level function (picklable); ``ray_address`` a cluster to join
    (default: a local Ray instance of ``workers`` CPUs).
    """
    if backend == "ray":
        yield from _run_ray(function, list(tasks), workers, ray_address)
    elif workers == 1:
        for task in tasks:
            yield function(task)
    else:
        yield from _run_pool(function, list(tasks), workers)


def _run_pool(function: Callable[[Any], dict], tasks: list[Any], workers: int) -> Iterator[dict[str, Any]]:
    with local_pool(workers) as pool:
        pending = {pool.submit(function, task) for task in tasks}
        while pending:
            finished = first_finished(pending)
            pending -= finished
            for future in finished:
                yield future.result()


def _run_ray(
    function: Callable[[Any], dict], tasks: list[Any], workers: int, address: str | None
) -> Iterator[dict[str, Any]]:
    with ray_session(workers, address) as ray:
        remote = ray.remote(num_cpus=1)(function)
        queue, pending = list(tasks), []
        try:
            while queue or pending:
                while queue and len(pending) < 2 * workers:  # few in flight: an interruption loses only those
                    pending.append(remote.remote(queue.pop(0)))
                finished, pending = ray.wait(pending, num_returns=1)
                for ref in finished:
                    yield ray.get(ref)
        finally:
            for ref in pending:
                ray.cancel(ref)
