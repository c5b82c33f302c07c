"""Reading a JSON file that a person or a stranger wrote, with one kind of error for every way it can be bad.

Scenario and plan files go through :func:`read_json` (:func:`read_json_or`): a file that is too large, not
UTF-8 text (binary, UTF-16), not JSON, nested too deeply or holding a number literal
too long to convert raises :class:`JsonInputError` (a ``ValueError``) with a short
message, never ``UnicodeDecodeError``, ``RecursionError`` or ``OverflowError``. The
caller wraps it in its own error (``ScenarioError``, ``PlanFormatError``). A gzip file
(what the repository stores of a large results file) is read as the JSON text it holds,
its decompressed size bounded as the plain file's is.

:func:`describe` shows a value in a message without printing megabytes of it or
recursing into deep nesting.
"""

from __future__ import annotations

import json
import math
import os
import reprlib
import stat
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fetchcarry_env.errors import InputError

GZIP_MAGIC = b"\x1f\x8b"  # the first two bytes of every gzip file
MAX_INT_DIGITS = 300  # digits: a longer integer literal is read as a float (inf beyond about 1e308)


class JsonInputError(InputError):
    """A file is not readable as the JSON text it should be; the message says why."""


def read_json(path: str | Path, max_bytes: int) -> Any:
    """The JSON value in the file at ``path``; :class:`JsonInputError` if the file is not sane JSON text.

    Only a regular file is read: it is opened without blocking (a FIFO would otherwise
    wait for a writer forever) and anything else (a FIFO, a device, a socket, a folder)
    is a :class:`JsonInputError`. The size (bytes) is checked before anything is read.
    ``OSError`` (a missing or unreadable file) passes through, always naming the file.
    """
    path = Path(path)
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    try:
        mode = os.fstat(descriptor)
        if not stat.S_ISREG(mode.st_mode):
            raise JsonInputError(f"not a regular file ({_kind(mode.st_mode)}): give the path of a JSON file")
        if mode.st_size > max_bytes:
            raise JsonInputError(
                f"the file is {mode.st_size:,} bytes, more than the {max_bytes:,} a file of this kind may have"
            )
        with os.fdopen(descriptor, "rb", closefd=False) as stream:
            raw = stream.read(max_bytes + 1)
    except OSError as error:  # a read error (EIO from a file under /proc) names no file: name it
        raise OSError(error.errno, error.strerror or str(error), str(path)) from None
    finally:
        os.close(descriptor)
    if len(raw) > max_bytes:  # a special file whose size stat did not report
        raise JsonInputError(f"the file is more than the {max_bytes:,} bytes a file of this kind may have")
    if raw.startswith(GZIP_MAGIC):
        raw = gunzip(raw, max_bytes)
    return parse_json(decode_text(raw))


def gunzip(raw: bytes, max_bytes: int) -> bytes:
    """The one gzip member ``raw`` decompressed; :class:`JsonInputError` if broken or above ``max_bytes`` bytes.

    Decompression stops at ``max_bytes + 1`` bytes, so a small file that would inflate
    to gigabytes costs no more memory than a plain file of the limit's size.
    """
    inflater = zlib.decompressobj(wbits=16 + zlib.MAX_WBITS)  # 16 +: a gzip header and trailer
    try:
        text = inflater.decompress(raw, max_bytes + 1)
    except zlib.error as error:
        raise JsonInputError(f"a broken gzip file ({error})") from None
    if len(text) > max_bytes:
        raise JsonInputError(f"the file decompresses to more than the {max_bytes:,} bytes a file of this kind may have")
    if not inflater.eof or inflater.unused_data:
        raise JsonInputError("a gzip file cut short or followed by other data: give one whole gzip member")
    return text


def _kind(mode: int) -> str:
    """What a file that is not a regular file is, in words."""
    kinds = {stat.S_ISDIR: "a folder", stat.S_ISFIFO: "a FIFO", stat.S_ISSOCK: "a socket", stat.S_ISCHR: "a device"}
    return next((name for test, name in kinds.items() if test(mode)), "a special file")


def read_json_or(path: Path, max_bytes: int, error: Callable[[JsonInputError], Exception]) -> Any:
    """:func:`read_json`, raising ``error(problem)`` (a caller's own error) instead of :class:`JsonInputError`."""
    try:
        return read_json(path, max_bytes)
    except JsonInputError as problem:
        raise error(problem) from None


def decode_text(raw: bytes) -> str:
    """``raw`` as UTF-8 text (a UTF-8 byte order mark is allowed); :class:`JsonInputError` otherwise."""
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")) or _ascii_and_nul(raw[:2]) or _ascii_and_nul(raw[1::-1]):
        raise JsonInputError("not a UTF-8 text file (it looks like UTF-16 or UTF-32): save it as UTF-8")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise JsonInputError(f"not a text file: byte {error.start} is not UTF-8 (expected JSON text)") from None
    if "\x00" in text:
        raise JsonInputError("not a text file: it holds NUL bytes (expected JSON text)")
    return text


def _ascii_and_nul(pair: bytes) -> bool:
    """True for a printable ASCII byte (or whitespace) then a NUL: how UTF-16 (no byte order mark) starts."""
    return len(pair) == 2 and (32 <= pair[0] < 127 or pair[0] in b"\t\n\r") and pair[1] == 0


def parse_json(text: str) -> Any:
    """The JSON value of ``text``; :class:`JsonInputError` for broken JSON, deep nesting or absurd numbers.

    ``NaN`` and ``Infinity`` are read as floats (the format's rules then reject them
    with the field's name). An integer literal of more than ``MAX_INT_DIGITS`` digits
    is read as a float, so it is refused as out of range instead of failing to convert.
    """
    try:
        return json.loads(text, parse_int=_parse_int)
    except json.JSONDecodeError as error:
        raise JsonInputError(f"not valid JSON: {error}") from None
    except RecursionError:
        raise JsonInputError("not valid JSON for this format: nested too deeply") from None
    except (ValueError, OverflowError) as error:
        raise JsonInputError(f"not valid JSON: {str(error)[:200]}") from None


def _parse_int(literal: str) -> int | float:
    digits = len(literal.lstrip("-"))
    return int(literal) if digits <= MAX_INT_DIGITS else float(literal)


_REPR = reprlib.Repr()
_REPR.maxlevel = 2
_REPR.maxstring = 40
_REPR.maxother = 40
_REPR.maxlist = _REPR.maxdict = _REPR.maxtuple = 4


def describe(value: Any) -> str:
    """A short, printable ``repr`` of ``value`` for an error message (long or deep values are cut)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 128:
        return f"<an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits>"
    try:
        return _REPR.repr(value)
    except (ValueError, RecursionError):  # an integer too long for str() inside a container
        return f"<a {type(value).__name__}>"
