"""A guard that turns a hang into a test failure: a fuzz example must never block the suite."""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def hang_guard(seconds: int, what: str) -> Iterator[None]:
    """Fail (``TimeoutError``) if the block runs longer than ``seconds``; ``what`` names the work in the message."""

    def alarm(signum: int, frame: object) -> None:
        raise TimeoutError(f"{what} took more than {seconds} s: a hang")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
