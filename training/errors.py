"""The benchmark's one error: bad input to it (an unknown policy or split, a missing run folder, a bad scenario)."""

from __future__ import annotations

from fetchcarry_env.errors import InputError


class BenchmarkError(InputError):
    """What the benchmark was asked cannot be done as asked; the message says why."""
