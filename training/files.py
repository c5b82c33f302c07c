"""Writing a file so that a reader sees the old one or the new one, never half of one."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO


@contextmanager
def atomic_file(path: Path, durable: bool = False) -> Iterator[BinaryIO]:
    """A binary file to write whose bytes become ``path`` when the block ends, through a rename.

    The temporary file lies beside ``path`` and is removed if anything fails; an
    ``OSError`` that names no file (a full disk) is raised naming ``path``. ``durable``:
    the bytes reach the disk (``fsync``) before the rename.
    """
    try:
        handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as error:
        raise naming(error, path) from error
    try:
        with os.fdopen(handle, "wb") as file:
            yield file
            if durable:
                file.flush()
                os.fsync(file.fileno())
        os.replace(temporary, path)
    except OSError as error:
        Path(temporary).unlink(missing_ok=True)
        raise naming(error, path) from error
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def write_atomically(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through :func:`atomic_file`."""
    with atomic_file(path) as file:
        file.write(data)


def naming(error: OSError, path: Path) -> OSError:
    """``error`` with ``path`` as its file name when it names none (a full disk names no file)."""
    if error.filename is not None:
        return error
    return OSError(error.errno, error.strerror or str(error), str(path))
