"""Writing a file so that a reader sees the old one or the new one, never half of one."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def write_atomically(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file beside it and a rename.

    The temporary file is removed if anything fails; an ``OSError`` that names no file
    (a full disk) is raised naming ``path``.
    """
    try:
        handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as error:
        raise naming(error, path) from None
    try:
        with os.fdopen(handle, "wb") as file:
            file.write(data)
        os.replace(temporary, path)
    except OSError as error:
        Path(temporary).unlink(missing_ok=True)
        raise naming(error, path) from None
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def naming(error: OSError, path: Path) -> OSError:
    """``error`` with ``path`` as its file name when it names none (a full disk names no file)."""
    if error.filename is not None:
        return error
    return OSError(error.errno, error.strerror or str(error), str(path))
