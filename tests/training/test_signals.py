"""SIGTERM ends a command the way Ctrl-C does: what finished is kept, the worker pool stops cleanly, exit 143.

The subprocess tests wait for a state (a staged episode, a results file), then signal, then
wait for the exit; no test here bounds a time (:data:`cli_run.SAFETY_TIMEOUT_S` only stops a hang).
A service manager signals the whole process group (systemd, a container's stop), ``kill PID``
only the main process: both are tried.
"""

from __future__ import annotations

import argparse
import os
import signal
import struct
import subprocess
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import pytest
from cli_run import POLL_S, SAFETY_TIMEOUT_S, cli_process, finish, run, signal_while_frozen, wait_for

from training.cli.exits import INTERRUPTED, TERMINATED, run_command
from training.data.generate import run_episodes
from training.data.staging import Staging
from training.evaluation.results import RESULTS, read_results
from training.pool import worker_setup

DATASET_ID = "fetchcarry/signals-v0"
GENERATE = ("generate", "--family", "basic", "--policy", "random", "--dataset-id", DATASET_ID, "--no-progress")
BENCHMARK = ("benchmark", "--policies", "random", "--split", "iid", "--no-progress")
NEVER_ENDING = ("--episodes", "100000")  # more episodes than a test waits for: the signal always lands in the run
WORKERS = 2
TARGETS = ["main-process", "process-group"]  # ``kill PID``, or a service manager's stop of the whole group


def assert_ended_cleanly(err: str) -> None:
    """No traceback, no leaked semaphores of an abandoned pool, no complaint of a finalizer."""
    assert "Traceback" not in err and "leaked semaphore" not in err and "Exception ignored" not in err, err


# ---------------------------------------------------------------------------- generate
@pytest.mark.parametrize("target", TARGETS)
def test_sigterm_stops_generate_keeping_whole_staged_episodes(capsys, minari_root: Path, target: str) -> None:
    process = cli_process(*GENERATE, *NEVER_ENDING, "--workers", WORKERS, minari_root=minari_root,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    staging = Staging(DATASET_ID)
    wait_for(staging.staged, "a staged episode", process)
    at_signal = len(signal_while_frozen(process, signal.SIGTERM, staging.staged, group=target == "process-group"))
    status, _, err = finish(process)
    assert status == TERMINATED, err
    assert_ended_cleanly(err)
    assert "episodes are staged; run the same command again to resume" in err
    staged = staging.staged()
    assert at_signal <= len(staged) <= at_signal + WORKERS  # at most the episodes in flight when it landed
    for index in staged:
        staging.read(index)  # whole: a StagingError otherwise
    episodes = max(staged) + 2
    status, out, err = run(capsys, *GENERATE, "--episodes", episodes)
    assert status == 0, err
    assert f"{len(staged)} resumed, {episodes - len(staged)} generated" in out


def test_a_pool_worker_ignores_sigterm_its_parent_stops_it() -> None:
    """Signalled with its group, a worker lives on until its parent stops it, so no finished result is lost."""
    with ProcessPoolExecutor(1, mp_context=get_context("spawn"), initializer=worker_setup,
                             initargs=(os.getpid(),)) as pool:  # fmt: skip
        handlers = pool.submit(_handlers).result(timeout=SAFETY_TIMEOUT_S)
    assert handlers == (signal.SIG_IGN, signal.SIG_IGN)


def _handlers() -> tuple[object, object]:
    """This process's handlers of SIGINT and SIGTERM (run in a pool worker)."""
    return signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)


def test_a_worker_killed_while_it_sent_its_result_leaves_no_thread_waiting(tmp_path: Path) -> None:
    """The workers are killed on a signal; one cut off in the middle of sending its result left the pool's manager
    thread waiting for the rest forever, and the interpreter's exit, which joins it, with it (``generate
    --workers 2`` hung after Ctrl-C or SIGTERM in some runs of three)."""
    go, sent = tmp_path / "go", tmp_path / "sent"
    episodes = run_episodes((go, sent), [0, 1], workers=2, episode=_at_once_or_cut_off)
    try:
        assert next(episodes) == (0, 0)
        go.touch()
        wait_for(sent.exists, "a result cut off in the middle")
        episodes.close()  # what Ctrl-C or SIGTERM does to the loop that stages episodes
        wait_for(lambda: not _pool_managers(), "the end of the pool's manager thread")
    finally:
        for manager in _pool_managers():  # never leave a stuck thread for pytest's exit to wait for
            manager.result_queue._writer.close()


def _at_once_or_cut_off(markers: tuple[Path, Path], index: int) -> int:
    """Episode 0 returns at once; episode 1, once ``go`` exists, sends the start of a result and never the rest."""
    if index == 0:
        return 0
    go, sent = markers
    while not go.exists():
        time.sleep(POLL_S)
    frame = sys._getframe()
    while "result_queue" not in frame.f_locals:  # the pool's worker loop, which called this function
        frame = frame.f_back
    announced, written = 2**20, 64  # bytes: a result's length, and the part of it written
    os.write(frame.f_locals["result_queue"]._writer.fileno(), struct.pack("!i", announced) + bytes(written))
    sent.touch()
    time.sleep(SAFETY_TIMEOUT_S)  # killed by the parent long before
    return 1


def _pool_managers() -> list[threading.Thread]:
    """The running threads that manage a process pool of this process."""
    return [t for t in threading.enumerate() if type(t).__name__ == "_ExecutorManagerThread" and t.is_alive()]


# ---------------------------------------------------------------------------- benchmark
@pytest.mark.parametrize("target", TARGETS)
def test_sigterm_stops_benchmark_keeping_its_results(capsys, tmp_path: Path, minari_root: Path, target: str) -> None:
    out = tmp_path / "bench"
    process = cli_process(*BENCHMARK, "--out", out, "--workers", WORKERS, minari_root=minari_root,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    wait_for((out / RESULTS).is_file, "a results file", process)
    signal_while_frozen(process, signal.SIGTERM, lambda: None, group=target == "process-group")
    status, _, err = finish(process)
    assert status == TERMINATED, err
    assert_ended_cleanly(err)
    assert f"the finished episodes are in {out / RESULTS}; add --resume to finish them" in err
    kept = {_episode(record) for record in read_results(out / RESULTS)}
    assert kept
    status, _, err = run(capsys, *BENCHMARK, "--out", out, "--episodes", "1", "--resume")
    assert status == 0, err
    after = {_episode(record) for record in read_results(out / RESULTS)}
    assert kept <= after and {policy for policy, _, _ in after} == {"expert", "random-phases", "random"}


def _episode(record: dict) -> tuple[str, str, int]:
    return record["policy"], record["split"], record["seed"]


# ---------------------------------------------------------------------------- in this process
class UnhandledSigterm(Exception):
    """The test's own SIGTERM handler ran: the command did not handle the signal."""


@pytest.fixture
def sigterm_guard():
    """A SIGTERM handler for the test process that raises :class:`UnhandledSigterm` (rather than ending pytest)."""

    def unhandled(signum, frame):
        raise UnhandledSigterm

    previous = signal.signal(signal.SIGTERM, unhandled)
    yield unhandled
    signal.signal(signal.SIGTERM, previous)


def test_sigterm_in_a_command_is_exit_143_and_a_second_one_lets_the_clean_up_finish(capsys, sigterm_guard) -> None:
    cleaned_up = []

    def command(args: argparse.Namespace) -> int:
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(SAFETY_TIMEOUT_S)  # the signal lands here (or the guard's exception does)
        finally:
            os.kill(os.getpid(), signal.SIGTERM)  # a second SIGTERM while the command cleans up
            time.sleep(0)  # a point where the interpreter runs signal handlers
            cleaned_up.append(True)
        return 0

    status = run_command(command, argparse.Namespace())
    assert status == TERMINATED and cleaned_up == [True]
    assert "fetchcarry: terminated" in capsys.readouterr().err
    assert signal.getsignal(signal.SIGTERM) is sigterm_guard  # the handler of before the command is back


def test_ctrl_c_in_a_command_is_still_exit_130(capsys) -> None:
    def command(args: argparse.Namespace) -> int:
        raise KeyboardInterrupt

    assert run_command(command, argparse.Namespace()) == INTERRUPTED
    assert "fetchcarry: interrupted" in capsys.readouterr().err
