"""Reading and writing the files a command names: a missing, unreadable or misplaced file is a ``InputError``."""

from __future__ import annotations

from pathlib import Path

from expert.plans import Plan, PlanFormatError
from fetchcarry_env.errors import InputError
from fetchcarry_env.jsontext import read_json
from fetchcarry_env.scenario import Scenario, ScenarioError
from training.pictures.files import check_picture_path

MAX_PEEK_BYTES = 50_000_000  # files larger than this are not opened just to guess what they are


def load_scenario(path: Path) -> Scenario:
    """Read a scenario file; a missing or unreadable file is a ``InputError``, a bad one a ``ScenarioError``."""
    check_readable(path, "scenario file")
    try:
        return Scenario.load(path)
    except UnicodeDecodeError:
        raise ScenarioError(["not a text file (expected JSON)"], str(path)) from None


def load_plan(path: Path) -> Plan:
    """Read a plan file; a missing file is a ``InputError``, a malformed one a ``PlanFormatError``."""
    check_readable(path, "plan file")
    try:
        return Plan.load(path)
    except UnicodeDecodeError:
        raise PlanFormatError(f"{path}: not a text file (expected JSON)") from None


def file_format(path: Path) -> str | None:
    """The ``format`` field of a JSON file, or ``None`` when the file is not a readable JSON object with one."""
    try:
        data = read_json(path, MAX_PEEK_BYTES)  # a regular file only: a FIFO is not waited on
    except (OSError, ValueError):  # JsonInputError is a ValueError
        return None
    value = data.get("format") if isinstance(data, dict) else None
    return value if isinstance(value, str) else None


def check_readable(path: Path, what: str) -> None:
    """Raise ``InputError`` unless ``path`` is an existing file."""
    if not path.exists():
        raise InputError(f"{what} not found: {path}")
    if path.is_dir():
        raise InputError(f"{what} is a directory, not a file: {path}")


def check_writable(path: Path, what: str) -> None:
    """Raise ``InputError`` unless ``path`` names a file in an existing folder."""
    if path.is_dir():
        raise InputError(f"{what} {path} is a directory; give a file name")
    if not path.parent.is_dir():
        raise InputError(f"{what} {path}: the directory {path.parent} does not exist")


def check_plot_format(path: Path) -> None:
    """Raise ``InputError`` unless matplotlib can write ``path``'s format."""
    from matplotlib.backend_bases import FigureCanvasBase  # matplotlib: only when a plot is asked for

    formats = FigureCanvasBase.get_supported_filetypes()
    if path.suffix.lower().lstrip(".") not in formats:
        raise InputError(f"cannot draw into {path}: give a file ending in one of .{', .'.join(sorted(formats))}")


def check_picture(path: str | None) -> Path | None:
    """The episode picture's path (a .png or .gif in an existing folder), or ``None`` when none is asked for.

    A suffix that is not a picture format, or a folder that does not exist, is an ``InputError``.
    """
    if path is None:
        return None
    picture = check_picture_path(path)
    if not picture.parent.is_dir():
        raise InputError(f"cannot write {picture}: folder {picture.parent} does not exist")
    return picture
