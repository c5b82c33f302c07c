"""Reading a JSON file that a person or a stranger wrote, with one kind of error for every way it can be bad.

Scenario and plan files go through :func:`read_json` (:func:`read_json_or`): a file that is too large, not
UTF-8 text (binary, UTF-16), not JSON, nested too deeply or holding a number literal
too long to convert raises :class:`JsonInputError` (a ``ValueError``) with a short
message, never ``UnicodeDecodeError``, ``RecursionError`` or ``OverflowError``. The
caller wraps it in its own error (``ScenarioError``, ``PlanFormatError``). A gzip file
(what the repository stores of a large results file) is read as the JSON text it holds,
its decompressed size bounded as the plain file's is.

A large file of many records (a results file) goes through :func:`stream_json`
instead, with the same checks: it is read, inflated and decoded a chunk at a time and
its records decoded one by one, each from a window of at most its limit of
characters, so that the caller can check each record as it comes and stop at the first
bad one; the memory then holds one chunk and the records kept, not the whole text and
every object it would make.

:func:`describe` shows a value in a message without printing megabytes of it or
recursing into deep nesting.
"""

from __future__ import annotations

import codecs
import contextlib
import itertools
import json
import math
import os
import re
import reprlib
import stat
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, BinaryIO

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
    with regular_file(path, max_bytes) as stream:
        raw = stream.read(max_bytes + 1)
    if len(raw) > max_bytes:  # a special file whose size stat did not report
        raise JsonInputError(f"the file is more than the {max_bytes:,} bytes a file of this kind may have")
    if raw.startswith(GZIP_MAGIC):
        raw = gunzip(raw, max_bytes)
    return parse_json(decode_text(raw))


@contextlib.contextmanager
def regular_file(path: str | Path, max_bytes: int) -> Iterator[BinaryIO]:
    """The regular file at ``path`` opened for reading (binary); :class:`JsonInputError` for another kind or size.

    The file is opened without blocking (a FIFO would otherwise wait for a writer
    forever); anything but a regular file, or a file of more than ``max_bytes`` bytes,
    is refused before a byte is read. An ``OSError`` while it is open names the file.
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
            yield stream
    except OSError as error:  # a read error (EIO from a file under /proc) names no file: name it
        raise OSError(error.errno, error.strerror or str(error), str(path)) from None
    finally:
        os.close(descriptor)


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
    _refuse_utf16(raw)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise _not_utf8(error.start) from None
    _refuse_nul(text)
    return text


def _not_utf8(byte: int) -> JsonInputError:
    """The refusal of a text whose byte ``byte`` (from the start) is not UTF-8."""
    return JsonInputError(f"not a text file: byte {byte} is not UTF-8 (expected JSON text)")


def _refuse_nul(text: str) -> None:
    """:class:`JsonInputError` if ``text`` holds a NUL character (a binary file, or UTF-16 without a mark)."""
    if "\x00" in text:
        raise JsonInputError("not a text file: it holds NUL bytes (expected JSON text)")


def _refuse_utf16(start: bytes) -> None:
    """:class:`JsonInputError` if the first bytes of a text, ``start``, look like UTF-16 or UTF-32."""
    if start.startswith((b"\xff\xfe", b"\xfe\xff")) or _ascii_and_nul(start[:2]) or _ascii_and_nul(start[1::-1]):
        raise JsonInputError("not a UTF-8 text file (it looks like UTF-16 or UTF-32): save it as UTF-8")


def _ascii_and_nul(pair: bytes) -> bool:
    """True for a printable ASCII byte (or whitespace) then a NUL: how UTF-16 (no byte order mark) starts."""
    return len(pair) == 2 and (32 <= pair[0] < 127 or pair[0] in b"\t\n\r") and pair[1] == 0


def parse_json(text: str) -> Any:
    """The JSON value of ``text``; :class:`JsonInputError` for broken JSON, deep nesting or absurd numbers.

    ``NaN`` and ``Infinity`` are read as floats (the format's rules then reject them
    with the field's name). An integer literal of more than ``MAX_INT_DIGITS`` digits
    is read as a float, so it is refused as out of range instead of failing to convert.
    """
    with _json_errors():
        return json.loads(text, parse_int=_parse_int)


@contextlib.contextmanager
def _json_errors() -> Iterator[None]:
    """Every way the decoder fails (broken JSON, deep nesting, absurd numbers) as a :class:`JsonInputError`."""
    try:
        yield
    except JsonInputError:  # a refusal already worded
        raise
    except json.JSONDecodeError as error:
        raise JsonInputError(f"not valid JSON: {error}") from None
    except RecursionError:
        raise JsonInputError("not valid JSON for this format: nested too deeply") from None
    except (ValueError, OverflowError) as error:
        raise JsonInputError(f"not valid JSON: {str(error)[:200]}") from None


def _parse_int(literal: str) -> int | float:
    digits = len(literal.lstrip("-"))
    return int(literal) if digits <= MAX_INT_DIGITS else float(literal)


# ------------------------------------------------------------------ a large file read a piece at a time
READ_CHUNK_BYTES = 2**20  # bytes read, inflated and decoded at a time by stream_json
SHARED_KEYS = 1_024  # distinct key names whose one string objects of a streamed file share
_BLANKS = re.compile(r"[ \t\n\r]*")  # JSON's whitespace


def stream_json(
    path: str | Path, max_bytes: int, array_key: str, max_item_chars: int, item: str = "item"
) -> Iterator[tuple[str | None, Any]]:
    """The top level of the JSON file at ``path``, read a chunk at a time, one array decoded item by item.

    Yields ``(key, value)`` for each member of a top-level object, in the file's order,
    or ``(None, value)`` for a top-level value of another kind. The top-level array,
    and the array that is the value of the member ``array_key``, come as
    :class:`JsonItems`: iterating it decodes one item at a time (the rest of the file is
    read only as far as it is iterated), so a caller that checks each item as it
    comes stops a hostile file at its first bad item, holding one chunk of text and the
    items it kept, never the whole text. Each item, and each other value, may take at
    most ``max_item_chars`` characters (``item`` names one in that refusal: "record 7 is
    more than ...").

    The file's checks are :func:`read_json`'s: a regular file of at most ``max_bytes``
    bytes, gzip inflated to at most ``max_bytes`` bytes, UTF-8 text, sane JSON; each
    refusal is a :class:`JsonInputError`.
    """
    with regular_file(path, max_bytes) as stream:
        yield from _Cursor(_text_chunks(_file_bytes(stream, max_bytes))).top_level(array_key, max_item_chars, item)


def _file_bytes(stream: BinaryIO, max_bytes: int) -> Iterator[bytes]:
    """The bytes of ``stream`` a chunk at a time, inflated if it is gzip; :class:`JsonInputError` past ``max_bytes``."""
    first = stream.read(max(READ_CHUNK_BYTES, len(GZIP_MAGIC)))
    chunks = _at_most(itertools.chain([first], iter(lambda: stream.read(READ_CHUNK_BYTES), b"")), max_bytes)
    return _inflated(chunks, max_bytes) if first.startswith(GZIP_MAGIC) else chunks


def _at_most(chunks: Iterator[bytes], max_bytes: int) -> Iterator[bytes]:
    """``chunks``, refused once they add up to more than ``max_bytes`` bytes (a file that grew as it was read)."""
    total = 0
    for chunk in chunks:
        total += len(chunk)
        if total > max_bytes:
            raise JsonInputError(f"the file is more than the {max_bytes:,} bytes a file of this kind may have")
        yield chunk


def _inflated(chunks: Iterator[bytes], max_bytes: int) -> Iterator[bytes]:
    """The one gzip member ``chunks`` hold, inflated a chunk at a time; :func:`gunzip`'s refusals."""
    inflater = zlib.decompressobj(wbits=16 + zlib.MAX_WBITS)  # 16 +: a gzip header and trailer
    total = 0
    for data in chunks:
        if inflater.eof:
            raise JsonInputError("a gzip file cut short or followed by other data: give one whole gzip member")
        while True:  # inflate this chunk, at most READ_CHUNK_BYTES at a time
            try:
                out = inflater.decompress(data, READ_CHUNK_BYTES)
            except zlib.error as error:
                raise JsonInputError(f"a broken gzip file ({error})") from None
            total += len(out)
            if total > max_bytes:
                raise JsonInputError(
                    f"the file decompresses to more than the {max_bytes:,} bytes a file of this kind may have"
                )
            if out:
                yield out
            data = inflater.unconsumed_tail
            if inflater.eof or (not data and len(out) < READ_CHUNK_BYTES):
                break
    if not inflater.eof or inflater.unused_data:
        raise JsonInputError("a gzip file cut short or followed by other data: give one whole gzip member")


def _text_chunks(chunks: Iterator[bytes]) -> Iterator[str]:
    """The UTF-8 text of ``chunks`` (a byte order mark dropped); :func:`decode_text`'s refusals, bytes counted whole."""
    decoder = codecs.getincrementaldecoder("utf-8")()
    offset = 0  # bytes of the text before this chunk
    for chunk in _head_whole(chunks, len(codecs.BOM_UTF8)):
        if offset == 0:
            _refuse_utf16(chunk)
            if chunk.startswith(codecs.BOM_UTF8):
                chunk, offset = chunk[len(codecs.BOM_UTF8) :], len(codecs.BOM_UTF8)
        held = len(decoder.getstate()[0])  # bytes of a character cut by the previous chunk's end
        try:
            text = decoder.decode(chunk)
        except UnicodeDecodeError as error:
            raise _not_utf8(offset - held + error.start) from None
        offset += len(chunk)
        _refuse_nul(text)
        if text:
            yield text
    held = len(decoder.getstate()[0])
    try:
        decoder.decode(b"", final=True)
    except UnicodeDecodeError as error:
        raise _not_utf8(offset - held + error.start) from None


def _head_whole(chunks: Iterator[bytes], size: int) -> Iterator[bytes]:
    """``chunks`` with the first ones joined until they hold ``size`` bytes: a text's marks are read in one piece."""
    head = b""
    for chunk in chunks:
        head += chunk
        if len(head) >= size:
            break
    yield head
    yield from chunks


class JsonItems:
    """The items of a JSON array in a file being read, decoded one at a time as they are iterated (once).

    :attr:`values` counts the JSON values of the items decoded so far, as an upper bound
    read off their text: one for the item, one per opening bracket and one per comma
    (so a comma inside a string counts too). A caller caps it to bound the memory the
    items take, whatever fields they hold.
    """

    def __init__(self, cursor: _Cursor, max_chars: int, name: str) -> None:
        self.values = 0
        self._items = self._decode(cursor, max_chars, name)

    def __iter__(self) -> Iterator[Any]:
        return self._items

    def drain(self) -> None:
        """Decode (and drop) the items not iterated yet: the file goes on after them."""
        for _ in self._items:
            pass

    def _decode(self, cursor: _Cursor, max_chars: int, name: str) -> Iterator[Any]:
        cursor.take("[")
        if cursor.peek() == "]":
            cursor.take("]")
            return
        for index in itertools.count():
            value, values = cursor.decode(max_chars, f"{name} {index}")
            self.values += values
            yield value
            if cursor.peek() == "]":
                cursor.take("]")
                return
            cursor.take(",", "',' delimiter")


class _Cursor:
    """JSON text arriving in chunks, read a value at a time with the standard decoder (its C scanner).

    Only the text from the value being read on is held; a value is decoded from a window
    of at most its limit of characters (and one more), so its memory is bounded by that
    limit, not by the file.
    """

    def __init__(self, chunks: Iterator[str]) -> None:
        self._chunks = chunks
        self._keys: dict[str, str] = {}  # one string per key name across values (the decoder shares them per value)
        self._decoder = json.JSONDecoder(parse_int=_parse_int, object_pairs_hook=self._object)
        self.text = ""  # the text from the value being read on (earlier chunks dropped)
        self.pos = 0  # the next character of text
        self._start = 0  # characters of the file before text
        self._lines = 0  # line breaks of the file before text
        self._line_start = 0  # the character (of the file) where the line that text starts on starts

    def _object(self, pairs: list[tuple[str, Any]]) -> dict[str, Any]:
        """A decoded object, its keys shared with the objects decoded before (records repeat their field names)."""
        if len(self._keys) < SHARED_KEYS:
            return {self._keys.setdefault(key, key): value for key, value in pairs}
        return {self._keys.get(key, key): value for key, value in pairs}

    def top_level(self, array_key: str, max_chars: int, item: str) -> Iterator[tuple[str | None, Any]]:
        """:func:`stream_json`'s members or value, then nothing but whitespace to the end of the text."""
        first = self.peek()
        if first == "[":
            items = JsonItems(self, max_chars, item)
            yield None, items
            items.drain()
        elif first == "{":
            yield from self._members(array_key, max_chars, item)
        else:
            yield None, self.decode(max_chars, "the file's value")[0]
        if self.peek():
            raise self.error("Extra data", self.pos)

    def _members(self, array_key: str, max_chars: int, item: str) -> Iterator[tuple[str, Any]]:
        """The members of the object at the cursor, the array of ``array_key`` as :class:`JsonItems`."""
        self.take("{")
        if self.peek() == "}":
            self.take("}")
            return
        while True:
            if self.peek() != '"':
                raise self.error("Expecting property name enclosed in double quotes", self.pos)
            key = self.decode(max_chars, "a key")[0]
            self.take(":", "':' delimiter")
            if key == array_key and self.peek() == "[":
                items = JsonItems(self, max_chars, item)
                yield key, items
                items.drain()
            else:
                yield key, self.decode(max_chars, f"the value of {describe(key)}")[0]
            if self.peek() == "}":
                self.take("}")
                return
            self.take(",", "',' delimiter")

    def peek(self) -> str:
        """The next character that is not whitespace (the cursor moved to it), or "" at the end of the text."""
        while True:
            self.pos = _BLANKS.match(self.text, self.pos).end()
            if self.pos < len(self.text):
                return self.text[self.pos]
            if not self._more():
                return ""

    def take(self, char: str, what: str = "") -> None:
        """Step over ``char``, the next character that is not whitespace; JSON's refusal (``Expecting what``) if not."""
        if self.peek() != char:
            raise self.error(f"Expecting {what or repr(char)}", self.pos)
        self.pos += 1

    def decode(self, max_chars: int, name: str) -> tuple[Any, int]:
        """The value at the cursor and its count of JSON values (see :class:`JsonItems`); the cursor moves past it.

        :class:`JsonInputError` when it is not JSON, or takes more than ``max_chars``
        characters (``name`` says which value in the refusal).
        """
        self.peek()
        while len(self.text) - self.pos <= max_chars and self._more():
            pass
        window = self.text[self.pos : self.pos + max_chars + 1]
        with _json_errors():
            try:
                value, end = self._decoder.raw_decode(window)
            except json.JSONDecodeError as error:
                if len(window) <= max_chars or (error.pos < max_chars - 6 and "Unterminated" not in error.msg):
                    raise self.error(error.msg, self.pos + error.pos) from None
                value, end = None, max_chars + 1  # cut off by the window: the value goes on beyond the limit
        if end > max_chars:
            raise JsonInputError(f"{name} is more than {max_chars:,} characters (none this long belongs in the file)")
        self.pos += end
        return value, 1 + window.count(",", 0, end) + window.count("[", 0, end) + window.count("{", 0, end)

    def error(self, message: str, pos: int) -> JsonInputError:
        """JSON's refusal ``message`` at character ``pos`` of :attr:`text`, with the line and column in the file."""
        line = self._lines + self.text.count("\n", 0, pos) + 1
        newline = self.text.rfind("\n", 0, pos)
        column = pos - newline if newline >= 0 else self._start + pos - self._line_start + 1
        return JsonInputError(f"not valid JSON: {message}: line {line} column {column} (char {self._start + pos})")

    def _more(self) -> bool:
        """Append the next chunk of text, dropping what was read; False at the end of the text."""
        chunk = next(self._chunks, None)
        if chunk is None:
            return False
        read = self.text[: self.pos]
        newline = read.rfind("\n")
        if newline >= 0:
            self._line_start = self._start + newline + 1
        self._lines += read.count("\n")
        self._start += self.pos
        self.text, self.pos = self.text[self.pos :] + chunk, 0
        return True


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
