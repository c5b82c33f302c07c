"""Text for a terminal: names and ids from files are shown, never obeyed.

A scenario's name or an object's id may hold ANSI escape codes or other control
characters (an edited file can move the cursor, recolour or clear the terminal) or a
lone surrogate (which stdout cannot encode). :func:`printable` shows each such
character as its Python escape (``\\x1b``, ``\\u202e``, ``\\ud800``), and :func:`echo`
prints text through it, keeping only its line breaks.
"""

from __future__ import annotations

import sys
from typing import TextIO


def printable(text: str) -> str:
    """``text`` with every non-printable character (control, format, surrogate, line break) escaped."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)


def echo(text: str, file: TextIO | None = None) -> None:
    """Print ``text`` line by line through :func:`printable` (its own line breaks are kept)."""
    print("\n".join(printable(line) for line in text.split("\n")), file=file if file is not None else sys.stdout)
