"""The training side's kinds of bad input, each an :class:`~fetchcarry_env.errors.InputError` (exit 2).

Kept on the lowest floor of ``training`` so that any module may raise them without
importing the part of the project that would catch them.
"""

from __future__ import annotations

from fetchcarry_env.errors import InputError


class BenchmarkError(InputError):
    """What the benchmark was asked cannot be done as asked (an unknown policy or split, a bad scenario)."""
