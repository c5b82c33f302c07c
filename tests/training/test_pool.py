"""The local pool stops cleanly however often Ctrl-C lands, and a deferred signal is acted on after its block."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
from collections.abc import Iterator

import pytest
from cli_run import SAFETY_TIMEOUT_S

from training.pool import deferred_signals

# Ctrl-C pressed once while the parent waits on many short calls, as ``generate --episodes 100000`` does.
# An interrupt that landed halfway through ``concurrent.futures.wait`` (which locks every future in
# turn) left a future's lock held: the pool's manager thread, and the interpreter's exit that joins
# it, then waited forever (2 of 12 runs of this program before the fix; each attempt takes about 2 s).
CTRL_C_WHILE_WAITING = textwrap.dedent(
    """
    import os, signal, threading, time
    from training.pool import first_finished, local_pool

    signal.signal(signal.SIGINT, signal.default_int_handler)  # a background job starts with Ctrl-C ignored
    finished = 0

    def press():
        while finished < 200:
            time.sleep(0.01)
        os.kill(os.getpid(), signal.SIGINT)

    try:
        with local_pool(2) as pool:
            pending = {pool.submit(time.sleep, 0.002) for _ in range(20000)}
            threading.Thread(target=press, daemon=True).start()
            while pending:
                done = first_finished(pending)
                pending -= done
                finished += len(done)
    except KeyboardInterrupt:
        print("stopped", flush=True)
    """
)


@pytest.mark.parametrize("attempt", range(4))
def test_ctrl_c_while_a_pool_waits_lets_the_program_end(attempt: int) -> None:
    process = subprocess.run(
        [sys.executable, "-c", CTRL_C_WHILE_WAITING],
        capture_output=True,
        text=True,
        timeout=SAFETY_TIMEOUT_S,  # a hang, not a speed bound: the program ends in about a second
    )
    assert (process.returncode, process.stdout) == (0, "stopped\n"), process.stderr


@pytest.fixture(autouse=True)
def ctrl_c_raises() -> Iterator[None]:
    """Ctrl-C as an interactive Python has it (a background job, as CI may run, starts with it ignored)."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def test_a_signal_within_the_block_is_acted_on_at_its_end() -> None:
    reached_the_end = False
    with pytest.raises(KeyboardInterrupt), deferred_signals() as deferred:
        signal.raise_signal(signal.SIGINT)
        reached_the_end = True
    assert reached_the_end and deferred.received == [signal.SIGINT]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_block_left_by_an_exception_drops_its_signals() -> None:
    with pytest.raises(ValueError), deferred_signals():
        signal.raise_signal(signal.SIGINT)
        raise ValueError("already stopping")
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
