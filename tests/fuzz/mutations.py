"""Hypothesis strategies that break valid scenario and plan files the ways people and hostile files do.

A mutation walks to a random place in a valid JSON document and does one thing there:
replaces the value (wrong types, NaN and infinities, huge and tiny numbers, integers
beyond float range, long strings, control characters, lone surrogates, deep nesting),
deletes a key, adds an unknown key, or repeats a list's items many times. The text of
the document may then be mangled too (cut short, a byte flipped, another encoding, a
byte order mark). Everything is drawn by hypothesis, so a failure shrinks to a small
example and the suite stays deterministic under ``derandomize=True``.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Any

from hypothesis import strategies as st

# Values that have broken loaders somewhere: each is a replacement for whatever stands at a path.
HOSTILE_SCALARS: tuple[Any, ...] = (
    None,
    True,
    False,
    0,
    -1,
    0.0,
    -0.0,
    1e-9,
    5e-4,
    -5.0,
    1e7,  # 10,000 km
    1e300,
    -1e300,
    math.nan,
    math.inf,
    -math.inf,
    10**400,  # beyond float range
    -(10**400),
    2**63,
    "",
    "x",
    "5",
    "+x",
    "reach_far",
    "\x1b[31mred\x1b[0m",  # ANSI escape
    "bad\ud800id",  # a lone surrogate
    "\u202eevil",  # a bidi override
    "x" * 10_000,
    [],
    {},
    [1.0],
    [1.0, 2.0, 3.0],
    [math.nan, 0.0],
    ["1", "2"],
    {"min": [0, 0]},
)


def _nested(depth: int) -> Any:
    value: Any = 0
    for _ in range(depth):
        value = [value]
    return value


hostile_values = st.one_of(
    st.sampled_from(HOSTILE_SCALARS).map(copy.deepcopy),  # a copy: later mutations must not change the table
    st.integers(min_value=-(10**30), max_value=10**30),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=20),
    st.integers(min_value=2, max_value=500).map(_nested),  # deep, but within the recursion limit
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=3),
)


def _paths(document: Any, prefix: tuple = ()) -> list[tuple]:
    """Every path (a tuple of keys and indices) into ``document``, the root included."""
    out = [prefix]
    if isinstance(document, dict):
        for key, value in document.items():
            out += _paths(value, (*prefix, key))
    elif isinstance(document, list):
        for index, value in enumerate(document):
            out += _paths(value, (*prefix, index))
    return out


def _parent(document: Any, path: tuple) -> Any:
    for key in path[:-1]:
        document = document[key]
    return document


@st.composite
def mutated(draw: st.DrawFn, valid: dict, max_mutations: int = 3) -> Any:
    """A copy of ``valid`` with 1 to ``max_mutations`` mutations put in."""
    document: Any = copy.deepcopy(valid)
    for _ in range(draw(st.integers(1, max_mutations))):
        paths = _paths(document)
        path = draw(st.sampled_from(paths))
        kind = draw(st.sampled_from(["replace", "replace", "replace", "delete", "extra", "repeat", "wrap"]))
        target = _parent(document, path)[path[-1]] if path else document
        if kind == "replace" or (not path and kind in ("delete", "wrap")):
            value = draw(hostile_values)
            if path:
                _parent(document, path)[path[-1]] = value
            else:
                document = value
        elif kind == "delete":
            parent = _parent(document, path)
            del parent[path[-1]]
        elif kind == "extra" and isinstance(target, dict):
            target[draw(st.sampled_from(["colour", "id", "", "\x00", "min", "\ud800"]))] = draw(hostile_values)
        elif kind == "repeat" and isinstance(target, list) and target:
            target *= draw(st.sampled_from([2, 3, 70, 300, 1100]))
        elif kind == "wrap" and path:
            _parent(document, path)[path[-1]] = draw(st.sampled_from([[target], {"value": target}, [target, target]]))
        if not isinstance(document, dict | list):
            break
    return document


def to_json_text(document: Any) -> str:
    """The JSON text of ``document`` (NaN and infinities written as JSON's extensions, as Python does)."""
    return json.dumps(document, allow_nan=True)


@st.composite
def file_bytes(draw: st.DrawFn, text: str) -> bytes:
    """The bytes of a file holding ``text``, sometimes mangled: cut short, a byte flipped, UTF-16, a BOM."""
    raw = text.encode("utf-8", errors="surrogatepass")
    how = draw(st.sampled_from(["plain"] * 6 + ["cut", "flip", "utf-16", "utf-16-le", "utf-32", "bom", "nul", "deep"]))
    if how == "cut" and raw:
        return raw[: draw(st.integers(0, len(raw) - 1))]
    if how == "flip" and raw:
        at = draw(st.integers(0, len(raw) - 1))
        return raw[:at] + bytes([draw(st.integers(0, 255))]) + raw[at + 1 :]
    if how in ("utf-16", "utf-16-le", "utf-32"):
        return text.encode(how, errors="surrogatepass")
    if how == "bom":
        return b"\xef\xbb\xbf" + raw
    if how == "nul":
        return raw + b"\x00"
    if how == "deep":
        depth = draw(st.sampled_from([1_000, 100_000]))
        return b"[" * depth + raw + b"]" * depth
    return raw


def write_mutated(data: st.DataObject, path: Path, valid: dict, max_mutations: int = 3) -> Path:
    """Write a mutated copy of ``valid`` (:func:`mutated`) to ``path`` as file bytes drawn by :func:`file_bytes`."""
    document = data.draw(mutated(valid, max_mutations=max_mutations))
    path.write_bytes(data.draw(file_bytes(to_json_text(document))))
    return path


@st.composite
def nudged(draw: st.DrawFn, valid: dict) -> Any:
    """A copy of ``valid`` with one number moved by up to 0.3 (often still valid, so the planner runs)."""
    document = copy.deepcopy(valid)
    numeric = [p for p in _paths(document) if p and isinstance(_parent(document, p)[p[-1]], float | int)]
    numeric = [p for p in numeric if not isinstance(_parent(document, p)[p[-1]], bool)]
    path = draw(st.sampled_from(numeric))
    _parent(document, path)[path[-1]] += draw(st.floats(-0.3, 0.3))
    return document
