"""``results.json``: the benchmark's records, their schema, and reading and writing the file.

The file is one JSON object (docs/results-format.md)::

    {"schema_version": 1, "records": [{"policy": "expert", ...}, ...]}

Readers also accept the plain list of records the benchmark wrote before (schema 0,
records without ``digest``). :func:`read_results` checks every record against
:data:`FIELDS` and refuses a file that breaks the schema with a :class:`ResultsError`
(bad input, exit 2) naming the file and the record; it never drops a record.
:func:`write_results` writes the file atomically (a temporary file, then a rename), so
a reader sees the old file or the new one, never half of one. A file may also be
gzip-compressed (``results.json.gz``, as the repository keeps the published table):
the readers take it as they take the plain file. :class:`ResultsLock`
keeps two benchmarks from writing to one folder at once.
"""

from __future__ import annotations

import gzip
import hashlib
import json
import math
from collections.abc import Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

from fetchcarry_env.jsontext import describe, read_json_or
from fetchcarry_env.scenario import Scenario
from training.data.staging import DatasetBusyError, DatasetLock
from training.errors import BenchmarkError
from training.files import write_atomically

RESULTS = "results.json"
RESULTS_GZIP = "results.json.gz"  # the same records, gzip-compressed: how the repository keeps the published table's
LOCK = ".results.lock"  # in the output folder: held (flock) by the benchmark writing there
SCHEMA_VERSION = 1  # 0: a plain list of records (no digest); 1: {"schema_version": 1, "records": [...]}
FORMAT_DOC = "docs/results-format.md"
MAX_RESULTS_BYTES = 256 * 2**20  # bytes: about half a million records; a larger file is refused unread

_INT, _NUMBER, _TEXT, _BOOL, _NULL = "an integer", "a number", "a string", "true or false", "null"
FIELDS: dict[str, tuple[str, ...]] = {
    "policy": (_TEXT,),
    "scenario": (_TEXT,),
    "split": (_TEXT,),
    "source": (_TEXT,),
    "seed": (_INT,),
    "digest": (_TEXT, _NULL),  # null only in a record carried over from a schema-0 file
    "success": (_BOOL,),
    "delivered": (_INT,),
    "objects": (_INT,),
    "cost": (_NUMBER,),
    "expert_cost": (_NUMBER, _NULL),
    "return": (_NUMBER,),
    "phases": (_INT,),
    "pushes": (_INT,),
    "invalid_actions": (_INT,),
    "contacts": (_INT,),
    "decision_ms": (_NUMBER,),
    "mask_ms": (_NUMBER,),
}
"""Every record's fields and the JSON kinds each may hold (units: docs/results-format.md). Other fields are kept."""

OPTIONAL: dict[str, tuple[str, ...]] = {
    "step_ms": (_NUMBER,),
    "references": (_TEXT, _NULL),
    "baseline": (_TEXT,),
    "training_seed": (_INT, _NULL),
}
"""Fields a record may lack (written by later versions, or by fetchcarry reproduce), checked when present."""

NOT_NEGATIVE = ("seed", "delivered", "objects", "phases", "pushes", "invalid_actions", "contacts")


class ResultsError(BenchmarkError):
    """A ``results.json`` that breaks its schema (the message names the file and the record)."""


class ResultsBusyError(BenchmarkError):
    """Another benchmark holds the lock of an output folder."""


def scenario_digest(scenario: Scenario, named: bool = True) -> str:
    """The sha256 (hex) of ``scenario``'s canonical JSON: what a record's episode was played on.

    ``named=False`` leaves the scenario's name out: the digest of the world alone, which
    a renamed copy of a scenario shares (what the protocol's guard compares).
    """
    data = scenario.to_dict()
    if not named:
        data.pop("name", None)
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def _kind(value: Any) -> str | None:
    """The JSON kind of ``value`` as :data:`FIELDS` names it (a bool is not an integer, a nan no number)."""
    if value is None:
        return _NULL
    if isinstance(value, bool):
        return _BOOL
    if isinstance(value, int):
        return _INT
    if isinstance(value, float):
        return _NUMBER if math.isfinite(value) else None
    if isinstance(value, str):
        return _TEXT
    return None


def record_problem(record: Any) -> str | None:
    """What is wrong with ``record`` against :data:`FIELDS`, or None when it is a well-formed record."""
    if not isinstance(record, dict):
        return f"is {type(record).__name__}, not an object"
    for name, kinds in (*FIELDS.items(), *OPTIONAL.items()):
        if name not in record:
            if name in OPTIONAL:
                continue
            return f"has no {name!r}"
        kind = _kind(record[name])
        if kind not in kinds and not (kind == _INT and _NUMBER in kinds):  # 3 is a number, 3.0 no integer
            return f"has {name!r} = {_shown(record[name])}, which is not {' or '.join(kinds)}"
    for name in NOT_NEGATIVE:
        if record[name] < 0:
            return f"has {name!r} = {record[name]}, which is negative"
    if record["delivered"] > record["objects"]:
        return f"delivers {record['delivered']} of {record['objects']} objects"
    return None


def parse_results(data: Any, path: Path) -> list[dict[str, Any]]:
    """The records of ``data`` (the parsed ``path``: the object of schema 1, or a schema-0 list), validated."""
    if isinstance(data, list):
        records, version = data, 0
    elif isinstance(data, dict):
        version = data.get("schema_version")
        if not isinstance(version, int) or isinstance(version, bool) or not 1 <= version <= SCHEMA_VERSION:
            raise ResultsError(
                f"{path}: schema_version {_shown(version)} is not one this version reads (1 to {SCHEMA_VERSION})"
            )
        records = data.get("records")
        if not isinstance(records, list):
            raise ResultsError(f"{path}: 'records' is not a list of records (the format: {FORMAT_DOC})")
    else:
        raise ResultsError(f"{path}: not an object with 'schema_version' and 'records' (the format: {FORMAT_DOC})")
    out = []
    for k, record in enumerate(records):
        if version == 0 and isinstance(record, dict) and "digest" not in record:
            record = {**record, "digest": None}
        problem = record_problem(record)
        if problem is not None:
            raise ResultsError(f"{path}: record {k} {_label(record)}{problem} (the format: {FORMAT_DOC})")
        out.append(record)
    return out


MAX_SHOWN_CHARS = 80  # characters of a string value quoted in a message


def _shown(value: Any) -> str:
    """``value`` as the file says it (JSON), cut short: a message names a record without printing megabytes."""
    if isinstance(value, str):
        return json.dumps(value if len(value) <= MAX_SHOWN_CHARS else value[:MAX_SHOWN_CHARS] + "...")
    if value is None or isinstance(value, bool | float) or (isinstance(value, int) and value.bit_length() <= 128):
        return json.dumps(value)
    return describe(value)


def _label(record: Any) -> str:
    """``(policy ..., split ..., seed ...) `` as far as ``record`` has them, to find it in the file."""
    if not isinstance(record, dict):
        return ""
    parts = [f"{key} {_shown(record[key])}" for key in ("policy", "split", "seed") if key in record]
    return f"({', '.join(parts)}) " if parts else ""


def read_results(path: str | Path) -> list[dict[str, Any]]:
    """The records of the results file ``path``, validated; :class:`ResultsError` names what breaks the schema.

    ``FileNotFoundError`` propagates (a caller decides whether a missing file is empty).
    """
    path = Path(path)
    data = read_json_or(path, MAX_RESULTS_BYTES, lambda problem: ResultsError(f"{path}: {problem}"))
    return parse_results(data, path)


def results_file(folder: str | Path) -> Path:
    """The results file of a results folder: ``results.json``, else ``results.json.gz`` if only that is there."""
    folder = Path(folder)
    plain, compressed = folder / RESULTS, folder / RESULTS_GZIP
    return compressed if compressed.exists() and not plain.exists() else plain


def encode_results(records: Sequence[dict[str, Any]], compressed: bool = False) -> bytes:
    """The bytes of a results file holding ``records`` in the current schema.

    Indented JSON text, or (``compressed``) compact JSON gzip-compressed with no time
    stamp, so that the same records always give the same bytes.
    """
    table = {"schema_version": SCHEMA_VERSION, "records": list(records)}
    if compressed:
        return gzip.compress(json.dumps(table, separators=(",", ":")).encode(), mtime=0)
    return (json.dumps(table, indent=1) + "\n").encode()


def write_results(path: str | Path, records: Sequence[dict[str, Any]]) -> None:
    """Write ``records`` to ``path`` (gzip-compressed if it ends ``.gz``), atomically."""
    path = Path(path)
    write_atomically(path, encode_results(records, compressed=path.suffix == ".gz"))


class ResultsLock(DatasetLock):
    """An exclusive lock on an output folder (``flock`` on ``OUT/.results.lock``), held while a benchmark writes there.

    The lock of ``fetchcarry generate`` (:class:`training.data.staging.DatasetLock`) on
    another file: the system releases it however its holder exits, and the file names
    the holder (process id, start time, command line), which the refusal quotes.
    """

    def __init__(self, out: str | Path) -> None:  # no super().__init__: the lock file is in the output folder
        self.out = Path(out)
        self.dataset_id = str(self.out)
        self.path = self.out / LOCK
        self._file: Any = None

    def __enter__(self) -> ResultsLock:
        try:
            super().__enter__()
        except DatasetBusyError:
            try:
                holder = self.path.read_text().strip() or "unknown"
            except OSError:
                holder = "unknown"
            raise ResultsBusyError(
                f"another benchmark is writing to {self.out} ({holder}); wait for it to finish or give another "
                f"--out (lock file {self.path})"
            ) from None
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, traceback: TracebackType | None
    ) -> None:
        super().__exit__(kind, error, traceback)
