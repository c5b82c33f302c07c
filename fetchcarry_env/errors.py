"""Errors that the command line turns into a short message and exit status 2."""


class UsageError(Exception):
    """Bad input from a user (a missing file, a wrong option value): no traceback, exit 2."""
