"""The one base class of the user's bad input, which the command line turns into a short message and exit 2.

Every error that means "what you gave cannot be used" (a scenario that breaks a rule,
a plan file, a run folder, a dataset, an unknown name or option value) derives from
:class:`InputError`, itself a ``ValueError``, so library callers may catch either. The
``fetchcarry`` command line maps :class:`InputError` to exit status 2 in one place;
any other exception is a bug, exit 3 with a crash report.
"""

import warnings


class InputError(ValueError):
    """Bad input from a user (a missing file, a wrong option value, a broken file): no traceback, exit 2."""


def __getattr__(name: str) -> type[InputError]:
    """``UsageError``, the name :class:`InputError` had before 0.2, still imports, with a DeprecationWarning."""
    if name == "UsageError":
        warnings.warn("UsageError is now InputError", DeprecationWarning, stacklevel=2)
        return InputError
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
