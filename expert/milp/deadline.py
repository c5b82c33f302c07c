"""The planner's clock: every step of :func:`expert.planner.plan` checks one deadline.

Preprocessing, the lower-bound searches, model building and the solve all count
against the caller's ``time_limit``. Long loops call :meth:`Deadline.check`, which
raises :class:`TimeUp` once the deadline has passed; the planner catches it and
answers with what it has (a plan found so far, or ``time_limit``).

Units are seconds (``time.perf_counter``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass


class TimeUp(Exception):
    """Raised by :meth:`Deadline.check` when the planner's time is up."""


@dataclass(frozen=True)
class Deadline:
    """A point in time (``time.perf_counter`` seconds); ``inf`` never passes."""

    at: float = math.inf

    @classmethod
    def after(cls, seconds: float) -> Deadline:
        return cls(time.perf_counter() + seconds)

    def left(self) -> float:
        """Seconds left (negative once passed)."""
        return self.at - time.perf_counter()

    def check(self) -> None:
        """Raise :class:`TimeUp` if the deadline has passed (about 0.1 us a call)."""
        if time.perf_counter() > self.at:
            raise TimeUp


NEVER = Deadline()
