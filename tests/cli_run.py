"""The ``fetchcarry`` command line (and ``python -m benchmarks``) run in-process, as every CLI test runs it, or in a
subprocess for signal tests.

A subprocess test waits for a state (a file written, a line printed), never for a number of
seconds: :data:`SAFETY_TIMEOUT_S` only stops a test that would otherwise hang, so that a
loaded machine cannot fail it.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import psutil
import pytest

from benchmarks.cli import main as benchmarks_main
from training.cli import main

ROOT = Path(__file__).resolve().parents[1]
SAFETY_TIMEOUT_S = 300  # seconds: a guard against a hang, not a speed bound (no command here takes a tenth of it)
POLL_S = 0.05  # seconds between two looks at the state a test waits for

T = TypeVar("T")


def run(capsys: pytest.CaptureFixture, *argv: object) -> tuple[int, str, str]:
    """``fetchcarry argv...`` in this process: (exit status, stdout, stderr); argparse's own exits included.

    Fails the test on any traceback in stderr: a command never prints one.
    """
    return _in_process(main, capsys, argv)


def bench(capsys: pytest.CaptureFixture, *argv: object) -> tuple[int, str, str]:
    """``python -m benchmarks argv...`` in this process, as :func:`run` runs ``fetchcarry``."""
    return _in_process(benchmarks_main, capsys, argv)


def _in_process(
    command: Callable[[list[str]], int], capsys: pytest.CaptureFixture, argv: tuple[object, ...]
) -> tuple[int, str, str]:
    try:
        status = command([str(a) for a in argv])
    except SystemExit as exit_:
        status = exit_.code
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return status, out, err


def cli_process(*argv: object, minari_root: Path, **options) -> subprocess.Popen:
    """``python -m training.cli argv...`` in a subprocess of this checkout, its datasets under ``minari_root``.

    The process leads its own process group (``start_new_session``), so that a test can signal
    it and its workers together (:func:`signal_group`) as a service manager does, and a
    terminal's Ctrl-C does not reach it. It starts with SIGINT's default action, as from a
    terminal, even when the tests run as a background job (which ignores SIGINT, and its
    children with it: Python then never raises KeyboardInterrupt, and a Ctrl-C test hangs).
    ``options`` go to :class:`subprocess.Popen`.
    """
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MINARI_DATASETS_PATH": str(minari_root)}
    return subprocess.Popen(
        [sys.executable, "-m", "training.cli", *map(str, argv)],
        env=env,
        cwd=options.pop("cwd", ROOT),
        text=True,
        start_new_session=True,
        preexec_fn=_default_sigint,
        **options,
    )


def _default_sigint() -> None:
    """In the child, before it runs Python: SIGINT's default action (a background job's children ignore it)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def signal_group(process: subprocess.Popen, signum: int) -> None:
    """Send ``signum`` to every process of ``process``'s group (it, its workers and their helpers)."""
    os.killpg(process.pid, signum)


def signal_while_frozen(process: subprocess.Popen, signum: int, look: Callable[[], T], *, group: bool = False) -> T:
    """Send ``signum`` to a frozen ``process`` and return what ``look()`` saw just before.

    The process group is stopped (SIGSTOP) and, once the main process is stopped,
    ``look()`` reads the state (nothing moves), ``signum`` goes to the main process (or,
    with ``group``, to the whole group) and the group resumes (SIGCONT): the signal lands
    as it resumes, so a test can compare what the command left with what ``look()`` saw,
    whatever the machine's load (only what was in flight may have finished).
    """
    signal_group(process, signal.SIGSTOP)
    main_process = psutil.Process(process.pid)
    wait_for(lambda: main_process.status() == psutil.STATUS_STOPPED, "the command to stop", process)
    seen = look()
    if group:
        signal_group(process, signum)
    else:
        process.send_signal(signum)
    signal_group(process, signal.SIGCONT)
    return seen


def wait_for(condition: Callable[[], T], what: str, process: subprocess.Popen | None = None) -> T:
    """The first truthy value of ``condition()``, polled every :data:`POLL_S` seconds.

    Fails the test when ``process`` ends first (with its stderr, when it was piped), or after
    :data:`SAFETY_TIMEOUT_S` (a hang).
    """
    deadline = time.monotonic() + SAFETY_TIMEOUT_S
    while not (value := condition()):
        if process is not None and process.poll() is not None:
            err = process.stderr.read() if process.stderr is not None else ""
            pytest.fail(f"the command ended (status {process.returncode}) before {what}: {err}")
        if time.monotonic() > deadline:
            pytest.fail(f"still waiting for {what} after the safety timeout of {SAFETY_TIMEOUT_S} s: a hang")
        time.sleep(POLL_S)
    return value


def finish(process: subprocess.Popen) -> tuple[int, str, str]:
    """Wait for ``process`` to end (at most :data:`SAFETY_TIMEOUT_S`): (exit status, stdout, stderr).

    A process still running after the safety timeout is killed and fails the test (a hang).
    """
    try:
        out, err = process.communicate(timeout=SAFETY_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        signal_group(process, signal.SIGKILL)
        process.communicate()
        pytest.fail(f"the command still ran after the safety timeout of {SAFETY_TIMEOUT_S} s: a hang")
    return process.returncode, out or "", err or ""
