"""Local process pools that Ctrl-C and SIGTERM stop cleanly, keeping every finished result.

The workers are spawned clean (no simulator or solver state inherited), ignore Ctrl-C and
SIGTERM (their parent stops them: a service manager signals the whole group) and die with
their parent. The parent never lets a signal's exception land inside the executor's own
code: :func:`first_finished` waits in short slices with the signals deferred and acts on
them between slices. An exception raised halfway through ``concurrent.futures.wait``
(which holds every future's lock while it registers) left a lock held, so the executor's
manager thread, and the interpreter's exit that joins it, waited forever.
"""

from __future__ import annotations

import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Collection, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass, field
from types import FrameType

PARENT_CHECK_S = 0.5  # seconds between a pool worker's checks that its parent is alive
SIGNAL_CHECK_S = 0.2  # seconds: the longest a signal waits before the parent acts on it (a poll, not a decision)
STOPPING_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_PR_SET_PDEATHSIG = 1  # Linux prctl option: the signal a process gets when its parent dies


@contextmanager
def local_pool(workers: int) -> Iterator[ProcessPoolExecutor]:
    """A pool of ``workers`` spawned processes (:func:`worker_setup`), stopped at once if the block is left early.

    Leaving the block normally waits for the pool to shut down; leaving it by an exception
    (Ctrl-C, SIGTERM, an error, or a generator closed by its caller) kills the workers
    first, so that no running call is waited for.
    """
    pool = ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=worker_setup,
        initargs=(os.getpid(),),
    )
    finished_cleanly = False
    try:
        yield pool
        finished_cleanly = True
    finally:
        with deferred_signals():  # a second Ctrl-C does not cut the clean-up short; it is acted on after
            if not finished_cleanly:
                terminate_workers(pool)
            pool.shutdown(wait=finished_cleanly, cancel_futures=True)


def first_finished(futures: Collection[Future]) -> set[Future]:
    """The finished ones of ``futures``, once at least one is (``wait(..., FIRST_COMPLETED)``).

    Ctrl-C and SIGTERM are acted on between waits of :data:`SIGNAL_CHECK_S` seconds, never
    inside the executor's code, so the pool can always be stopped afterwards.
    """
    while True:
        with deferred_signals():
            finished, _ = wait(futures, timeout=SIGNAL_CHECK_S, return_when=FIRST_COMPLETED)
        if finished:
            return finished


@dataclass
class DeferredSignals:
    """The stopping signals that arrived within a :func:`deferred_signals` block, in order."""

    received: list[int] = field(default_factory=list)

    def record(self, signum: int, frame: FrameType | None) -> None:
        self.received.append(signum)


@contextmanager
def deferred_signals() -> Iterator[DeferredSignals]:
    """Within the block, Ctrl-C and SIGTERM are only recorded; at its end they are raised again.

    The handlers of before come back first, so each signal then does what it would have
    done (``KeyboardInterrupt``, the command's termination, or the default action) at a
    point where nothing is half done. A block left by an exception drops them: the
    program is already stopping. Outside the main thread, where Python runs no signal
    handler, the block changes nothing.
    """
    deferred = DeferredSignals()
    if threading.current_thread() is not threading.main_thread():
        yield deferred
        return
    previous = {signum: signal.signal(signum, deferred.record) for signum in STOPPING_SIGNALS}
    try:
        yield deferred
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    for signum in deferred.received:
        signal.raise_signal(signum)


def worker_setup(parent: int) -> None:
    """Initialise a pool worker: it ignores Ctrl-C and SIGTERM (its parent stops it) and dies with its parent.

    Ctrl-C and a service manager's stop signal every process of the group: the parent
    keeps what finished and kills its workers (:func:`terminate_workers`), so a worker
    that died first would only break the pool under it. On Linux the kernel kills the
    worker when the parent dies, however it dies (``PR_SET_PDEATHSIG``); elsewhere, and as
    a second guard, a daemon thread checks every :data:`PARENT_CHECK_S` seconds that the
    parent is still there.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:  # the parent died before the line above took effect
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent,), name="watch-parent", daemon=True).start()


def _watch_parent(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(PARENT_CHECK_S)
    os._exit(1)


def terminate_workers(pool: ProcessPoolExecutor) -> None:
    """Kill the pool's worker processes now (the executor has no public way to stop running calls).

    A worker killed in the middle of sending its result leaves the pool's manager thread
    waiting for the rest of the message, and the interpreter's exit, which joins that
    thread, with it. This process's own copy of the result pipe's writing end is closed
    once the workers are gone, so that the wait ends (end of file: the pool is broken).
    """
    processes = dict(getattr(pool, "_processes", None) or {})
    for process in processes.values():
        if process.is_alive():
            process.kill()
    for process in processes.values():
        process.join(timeout=1.0)
    results = getattr(pool, "_result_queue", None)
    if results is not None:  # a worker still alive keeps its own copy: its result, if any, still arrives
        results._writer.close()
