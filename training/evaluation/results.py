"""``results.json``: the benchmark's records, their schema, and reading and writing the file.

The file is one JSON object (docs/results-format.md)::

    {"schema_version": 1, "records": [{"policy": "expert", ...}, ...]}

Readers also accept the plain list of records the benchmark wrote before (schema 0,
records without ``digest``). :func:`read_results` reads the file a chunk at a time and
checks each record as it is decoded: against :data:`FIELDS` and :data:`BOUNDS`, its
figures against each other (:func:`record_problem`), the file's caps (``MAX_*``: records,
characters of a record, JSON values, splits, policies, pairs, scenarios of a split) and
the records before it (no episode twice). The first record that breaks one stops the
read with a :class:`ResultsError` (bad input, exit 2) naming the file and the record;
no record is ever dropped.
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
import re
from collections.abc import Iterable, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

from fetchcarry_env.jsontext import JsonInputError, JsonItems, describe, stream_json
from fetchcarry_env.kinematics import (
    COLLISION_PENALTY,
    DELIVERY_BONUS,
    INVALID_ACTION_PENALTY,
    WAIT_COST,
    travel_cost,
)
from fetchcarry_env.scenario import COORD_LIMIT, Scenario
from training.data.staging import DatasetBusyError, DatasetLock
from training.errors import BenchmarkError
from training.files import write_atomically

RESULTS = "results.json"
RESULTS_GZIP = "results.json.gz"  # the same records, gzip-compressed: how the repository keeps the published table's
LOCK = ".results.lock"  # in the output folder: held (flock) by the benchmark writing there
SCHEMA_VERSION = 2  # 0: a plain list of records (no digest); 1: {"schema_version": 1, "records": [...]};
# 2: the same, each record's cost the task cost (its travel in "travel"): a record with "travel" is of schema 2
FORMAT_DOC = "docs/results-format.md"
MAX_RESULTS_BYTES = 256 * 2**20  # bytes: about half a million records; a larger file is refused unread

# What one results file may hold: read a record at a time, a file is refused at the first record past a cap.
# Each cap is several times the published table's figure (docs/benchmarks/published: 42,470 records).
MAX_RECORDS = 200_000  # records: 4.7 times the published table's 42,470
MAX_RECORD_CHARS = 8_192  # characters of one record's JSON text: 13 times the published records' longest, 626
MAX_VALUES = 32 * MAX_RECORDS  # JSON values of every record together (fields, items): 23 a published record
MAX_SPLITS = 64  # splits one file names: the published table names 7
MAX_POLICIES = 1_024  # policy labels one file names: the published table names 35
MAX_PAIRS = 4_096  # pairs of a policy label and a split (a leaderboard's rows at most): the published table has 173
MAX_SPLIT_SCENARIOS = 5_000  # scenarios (seeds) on one split: the published splits have at most 300
MAX_COUNT = 2**31 - 1  # the largest count a record may hold (objects, phases, pushes, invalid actions, contacts)
MAX_MS = 86_400_000.0  # milliseconds: a mean time per decision above a day is no measurement
MAX_PHASE_COST_M = 2 * max(
    travel_cost((-COORD_LIMIT, -COORD_LIMIT), (COORD_LIMIT, COORD_LIMIT)),
    travel_cost((-COORD_LIMIT, 0.0), (COORD_LIMIT, 0.0)),
)  # metres: twice the longest move within the square every coordinate of a scenario lies in
MAX_COST_M = MAX_COUNT * MAX_PHASE_COST_M  # metres: the most an episode of the most phases can travel

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
    "travel": (_NUMBER,),  # schema 2 (cost: the task cost); schema 1's cost is the travel
    "step_ms": (_NUMBER,),
    "references": (_TEXT, _NULL),
    "baseline": (_TEXT,),
    "training_seed": (_INT, _NULL),
}
"""Fields a record may lack (written by later versions, or by fetchcarry reproduce), checked when present."""

BOUNDS: dict[str, tuple[float, float | None]] = {
    "seed": (0, None),
    "training_seed": (0, None),
    **dict.fromkeys(("delivered", "objects", "phases", "pushes", "invalid_actions", "contacts"), (0, MAX_COUNT)),
    "cost": (0, None),  # at most what its phases can travel and wait (record_problem)
    "travel": (0, None),
    "expert_cost": (0, MAX_COST_M),
    **dict.fromkeys(("decision_ms", "mask_ms", "step_ms"), (0, MAX_MS)),
}
"""The least and the largest value (None: no largest) of the numeric fields, checked when the field is a number."""

DIGESTS = ("digest", "references")  # fields that, when a string, are a sha256 in hex
_SHA256_HEX = re.compile(r"[0-9a-f]{64}")


class ResultsError(BenchmarkError):
    """A ``results.json`` that breaks its schema (the message names the file and the record)."""


class ResultsBusyError(BenchmarkError):
    """Another benchmark holds the lock of an output folder."""


SEED_SUFFIX = re.compile(r"^(?P<method>.+)-s(?P<seed>\d{1,18})$")  # a longer number is no training seed


def method_of(record: dict[str, Any]) -> tuple[str, int | None]:
    """``(method, training seed)`` of ``record`` (seed ``None``: one run, a reference or an ensemble).

    Its ``baseline`` and ``training_seed`` when it has them (``fetchcarry reproduce``'s
    records), else its policy label read as ``NAME-sSEED`` (``bc-mlp-s2``: ``bc-mlp``, 2).
    """
    if isinstance(record.get("baseline"), str):
        seed = record.get("training_seed")
        return record["baseline"], seed if isinstance(seed, int) else None
    match = SEED_SUFFIX.match(record["policy"])
    return (match["method"], int(match["seed"])) if match else (record["policy"], None)


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
    """What is wrong with ``record`` (its fields against :data:`FIELDS`, :data:`BOUNDS` and each other), or None."""
    if not isinstance(record, dict):
        return f"is {type(record).__name__}, not an object"
    return _kind_problem(record) or _bound_problem(record) or _digest_problem(record) or _agreement_problem(record)


def _kind_problem(record: dict[str, Any]) -> str | None:
    """A field missing or of a kind :data:`FIELDS` (:data:`OPTIONAL`) does not allow, or None."""
    for name, kinds in (*FIELDS.items(), *OPTIONAL.items()):
        if name not in record:
            if name in OPTIONAL:
                continue
            return f"has no {name!r}"
        kind = _kind(record[name])
        if kind not in kinds and not (kind == _INT and _NUMBER in kinds):  # 3 is a number, 3.0 no integer
            return f"has {name!r} = {_shown(record[name])}, which is not {' or '.join(kinds)}"
    return None


def _bound_problem(record: dict[str, Any]) -> str | None:
    """A number below or above its :data:`BOUNDS`, or None (fields of a well-kinded record)."""
    for name, (least, largest) in BOUNDS.items():
        value = record.get(name)
        if value is None:
            continue
        if value < least:
            return f"has {name!r} = {_shown(value)}, which is negative"
        if largest is not None and value > largest:
            return f"has {name!r} = {_shown(value)}, more than {_figure(largest)}, the most the format allows"
    return None


def _digest_problem(record: dict[str, Any]) -> str | None:
    """A ``digest`` or ``references`` string that is not a sha256 in hex, or None."""
    for name in DIGESTS:
        value = record.get(name)
        if isinstance(value, str) and not _SHA256_HEX.fullmatch(value):
            return f"has {name!r} = {_shown(value)}, which is not 64 hexadecimal digits (a sha256)"
    return None


def _agreement_problem(record: dict[str, Any]) -> str | None:
    """Figures of one record that contradict each other (docs/results-format.md), or None."""
    delivered, objects, phases, cost = record["delivered"], record["objects"], record["phases"], record["cost"]
    if delivered > objects:
        return f"delivers {delivered} of {objects} objects"
    if record["success"] and delivered != objects:
        return f"has 'success' = true but delivers {delivered} of {objects} objects"
    if "travel" in record:
        return _task_cost_problem(record)
    if cost > phases * MAX_PHASE_COST_M:
        return (
            f"has 'cost' = {_shown(cost)}, more than its {phases} phases can travel "
            f"(at most {_figure(MAX_PHASE_COST_M)} m each)"
        )
    most = DELIVERY_BONUS * objects + phases * (MAX_PHASE_COST_M + COLLISION_PENALTY + INVALID_ACTION_PENALTY)
    if abs(record["return"]) > most:
        return (
            f"has 'return' = {_shown(record['return'])}, more in size than {_figure(most)}, what {objects} objects "
            f"and {phases} phases can earn or lose"
        )
    return None


def _task_cost_problem(record: dict[str, Any]) -> str | None:
    """Schema 2: the cost is the task cost, minus the return; at most what the phases can travel, wait and lose."""
    objects, phases, cost, travel = record["objects"], record["phases"], record["cost"], record["travel"]
    most = phases * (MAX_PHASE_COST_M + WAIT_COST * objects + COLLISION_PENALTY + INVALID_ACTION_PENALTY)
    if cost > most:
        return (
            f"has 'cost' = {_shown(cost)}, more than its {phases} phases can travel, wait and lose "
            f"(at most {_figure(most)})"
        )
    if travel > cost + 1e-6 * max(1.0, cost):
        return f"has 'travel' = {_shown(travel)} above its task cost {_shown(cost)}"
    if abs(record["return"] + cost) > 1e-6 * max(1.0, cost):
        return f"has 'return' = {_shown(record['return'])}, not minus its task cost {_shown(cost)}"
    return None


def _figure(value: float) -> str:
    """A bound in a message: an integer with thousands separators, a float in six significant digits."""
    if isinstance(value, int):
        return f"{value:,}"
    return f"{value:,.0f}" if value.is_integer() and abs(value) < 1e15 else f"{value:.6g}"


def parse_results(data: Any, path: Path) -> list[dict[str, Any]]:
    """The records of ``data`` (the parsed ``path``: the object of schema 1, or a schema-0 list), validated."""
    if isinstance(data, list):
        return _checked(data, path, version=0)
    if not isinstance(data, dict):
        raise _not_results(path)
    _check_version(data.get("schema_version"), path)
    records = data.get("records")
    if not isinstance(records, list):
        raise _not_a_list(path)
    return _checked(records, path, version=SCHEMA_VERSION)


def _check_version(version: Any, path: Path) -> None:
    """:class:`ResultsError` unless ``version`` is a ``schema_version`` this module reads."""
    if not isinstance(version, int) or isinstance(version, bool) or not 1 <= version <= SCHEMA_VERSION:
        raise ResultsError(
            f"{path}: schema_version {_shown(version)} is not one this version reads (1 to {SCHEMA_VERSION})"
        )


def _not_results(path: Path) -> ResultsError:
    return ResultsError(f"{path}: not an object with 'schema_version' and 'records' (the format: {FORMAT_DOC})")


def _not_a_list(path: Path) -> ResultsError:
    return ResultsError(f"{path}: 'records' is not a list of records (the format: {FORMAT_DOC})")


def _checked(records: Iterable[Any], path: Path, version: int) -> list[dict[str, Any]]:
    """``records`` (of a file of schema ``version``) checked as they come: :class:`ResultsError` at the first bad one.

    A record must be well formed (:func:`record_problem`), within the file's caps
    (:data:`MAX_RECORDS`, :data:`MAX_VALUES` when ``records`` are :class:`JsonItems`
    being read, and :class:`_Census`'s) and no episode of a record before it.
    """
    census = _Census(path)
    out = []
    for index, record in enumerate(records):
        if index >= MAX_RECORDS:
            raise ResultsError(f"{path}: more than {MAX_RECORDS:,} records (record {index}) {_CAPS}")
        if isinstance(records, JsonItems) and records.values > MAX_VALUES:
            raise ResultsError(f"{path}: more than {MAX_VALUES:,} JSON values by record {index} {_CAPS}")
        if version == 0 and isinstance(record, dict) and "digest" not in record:
            record = {**record, "digest": None}
        problem = record_problem(record)
        if problem is not None:
            raise ResultsError(f"{path}: record {index} {_label(record)}{problem} (the format: {FORMAT_DOC})")
        census.add(index, record)
        out.append(record)
    return out


_CAPS = f"(a results file may hold no more: the format, {FORMAT_DOC}, says its caps)"


class _Census:
    """What the records of a file read so far name and which episodes they hold: the caps, and no episode twice."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.episodes: dict[tuple[Any, ...], int] = {}  # (split, seed, method, training seed) -> its record
        self.splits: set[str] = set()
        self.policies: set[str] = set()
        self.pairs: set[tuple[str, str]] = set()
        self.scenarios: dict[str, set[int]] = {}  # split -> seeds

    def add(self, index: int, record: dict[str, Any]) -> None:
        """Count ``record`` (the file's record ``index``); :class:`ResultsError` past a cap, or for an episode twice."""
        split, policy = record["split"], record["policy"]
        self._grow(self.splits, split, MAX_SPLITS, "splits", index)
        self._grow(self.policies, policy, MAX_POLICIES, "policies", index)
        self._grow(self.pairs, (policy, split), MAX_PAIRS, "pairs of a policy and a split", index)
        seeds = self.scenarios.setdefault(split, set())
        self._grow(seeds, record["seed"], MAX_SPLIT_SCENARIOS, f"scenarios on {_shown(split)}", index)
        method, training_seed = method_of(record)
        first = self.episodes.setdefault((split, record["seed"], method, training_seed), index)
        if first != index:
            raise ResultsError(
                f"{self.path}: records {first} and {index} are the same episode (method {_shown(method)}, training "
                f"seed {_shown(training_seed)}, split {_shown(split)}, seed {record['seed']}): a file holds each "
                f"episode once (the format: {FORMAT_DOC})"
            )

    def _grow(self, seen: set, name: Any, cap: int, what: str, index: int) -> None:
        """Add ``name`` to ``seen``; :class:`ResultsError` when it would make more than ``cap`` ``what``."""
        if name not in seen and len(seen) >= cap:
            raise ResultsError(f"{self.path}: more than {cap:,} {what} (record {index} makes one more) {_CAPS}")
        seen.add(name)


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

    The file is read a chunk at a time and its records checked one by one as they are
    decoded (:func:`fetchcarry_env.jsontext.stream_json`): the first record that breaks
    the schema or a cap stops the read, so a hostile file costs no more memory than
    the records before it. ``FileNotFoundError`` propagates (a caller decides whether a
    missing file is empty).
    """
    path = Path(path)
    try:
        return _read(path)
    except JsonInputError as problem:
        raise ResultsError(f"{path}: {problem}") from None


def _read(path: Path) -> list[dict[str, Any]]:
    """:func:`read_results` on the members of the file's top level as they come."""
    records: list[dict[str, Any]] | None = None
    versioned = False
    for key, value in stream_json(path, MAX_RESULTS_BYTES, "records", MAX_RECORD_CHARS, item="record"):
        if key is None and isinstance(value, JsonItems):  # schema 0: a list of records
            records, versioned = _checked(value, path, version=0), True
        elif key is None:
            raise _not_results(path)
        elif key == "schema_version":
            _check_version(value, path)
            versioned = True
        elif key == "records":
            if not isinstance(value, JsonItems) or records is not None:
                raise _not_a_list(path)
            records = _checked(value, path, version=SCHEMA_VERSION)
    if not versioned:
        _check_version(None, path)
    if records is None:
        raise _not_a_list(path)
    return records


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
