"""The fixed references of every published split: each scenario's digest and the proven optimum on it.

A split's reference file, ``training/evaluation/references/NAME-vN.json`` (in the
repository, one per split version), pins the split: for each part (``dev``, ``test``)
it lists every scenario's index, seed, source, name and digest
(:func:`~training.evaluation.results.scenario_digest`; ``world_digest`` without the
name, which the protocol's guard compares), and the MILP expert's episode on it in the
physics env, planned to proven optimality (no node budget; :data:`REFERENCE_TIME_LIMIT`
seconds per planning call is only the safety stop): ``cost``, the task cost of the proven
optimal plan (``docs/formulation.md``, "The task cost"), ``return`` (minus it), ``travel``
and ``episode_cost`` (what the episode measured in the env), success, phases, pushes,
delivered, the planning calls, whether every one was proven optimal with no clock stopping
one (``proven``, ``clock_stopped``) and the first call's status. The episode runs in the
env the benchmark gives every policy on that split: the split's capacity and physics
(:attr:`~training.evaluation.splits.EvalScenario.env_options`; ``perturbed``'s clutter
masses and frictions are drawn from the reset seed, so the reference meets the same ones).
A scenario with no proven plan is recorded all the same (``proven`` false, ``cost`` the
episode's); ``fetchcarry references --check`` counts them.

No episode on the scenario can cost less than a proven ``cost`` (the env's rules are the
planner's model, and the env's return is minus the task cost): the invariant
:func:`training.evaluation.invariant.beaten` checks over any results.

The benchmark reads the cost ratio, SPL and the score's 100 from here, never from the
expert's run; the expert still runs, and its disagreements with the reference are reported.
Files of release 0.2 (``fetchcarry-references/1``, the ``v1`` splits) measured another task
(a reward of +10 per delivery, travel cost as the cost): they stay as published and load,
marked legacy, and the benchmark refuses to score a split against them.
``fetchcarry references --split NAME`` makes (or remakes) a file, on the local pool or on
Ray, with the same records either way. A test checks that sampling every split again gives
every digest of its file, so a change in a sampler cannot silently alter a published split.

File::

    {"format": "fetchcarry-references/2", "split": "iid-v2", "time_limit_s": 600.0,
     "parts": {"dev": [{"index": 0, "seed": 1008000000, "digest": "...", "cost": 27.35, ...}, ...],
               "test": [...]}}
"""

from __future__ import annotations

import hashlib
import json
import math
import zlib
from collections.abc import Callable, Iterator, Sequence
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from fetchcarry_env.jsontext import JsonInputError, read_json
from training.data.generate import progress_bar
from training.envs import make_env
from training.errors import BenchmarkError
from training.evaluation.results import scenario_digest
from training.evaluation.splits import SPLITS, EvalScenario, Split, get_split, split_scenarios
from training.evaluation.tasks import run_all
from training.rollout import run_episode

FORMAT = "fetchcarry-references/2"
LEGACY_FORMAT = "fetchcarry-references/1"  # release 0.2's task (v1 splits): kept as published, not scored against
FOLDER = Path(__file__).parent / "references"
REFERENCE_TIME_LIMIT = 600.0  # seconds per planning call: the safety stop only (the expert plans to proven optimality)
MAX_BYTES = 8_000_000  # a reference file is read within this size
REPLANNED = ("success", "proven", "status", "phases", "pushes", "delivered")  # fields a re-plan must give again
COST_TOLERANCE = 1e-6  # relative: a re-planned cost or return that differs by more is a disagreement
LEGACY_FIELDS = (
    "index",
    "seed",
    "source",
    "scenario",
    "digest",
    "world_digest",
    "success",
    "cost",
    "return",
    "phases",
    "pushes",
    "delivered",
    "plans",
    "proven",
    "status",
    "planning_s",
)
FIELDS = (*LEGACY_FIELDS, "travel", "episode_cost", "clock_stopped")
NUMBERS = ("cost", "return", "travel", "episode_cost", "planning_s")
COUNTS = ("index", "seed", "phases", "pushes", "delivered", "plans")
FLAGS = ("success", "proven", "clock_stopped")


class ReferenceFileError(BenchmarkError):
    """A reference file that is missing, broken, or that disagrees with its split's scenarios."""


def reference_path(split: Split | str, folder: Path = FOLDER) -> Path:
    """The reference file of ``split``'s version (``FOLDER/iid-v1.json``)."""
    split = get_split(split) if isinstance(split, str) else split
    return folder / f"{split.version}.json"


class _Recorder:
    """An :class:`~expert.policy.ExpertPolicy` planning to proven optimality (no node budget; ``time_limit`` is
    the safety stop) that keeps every planning call's status, first plan and whether a clock stopped it."""

    def __init__(self, env: Any, time_limit: float) -> None:
        from expert.policy import ExpertPolicy

        self.expert = ExpertPolicy(env, time_limit=time_limit, node_limit=None)
        self.statuses: list[str] = []
        self.first_plan: Any = None
        self.clock_stopped = False

    def reset(self) -> None:
        self.expert.reset()
        self.statuses, self.first_plan, self.clock_stopped = [], None, False

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
        action_masks: Any = None,
    ) -> tuple[Any, Any]:
        action, state = self.expert.predict(observation, state, episode_start, deterministic)
        decision = self.expert.last_decision
        if decision is not None and decision.planned:
            self.statuses.append(str(decision.status))
            plan = self.expert.last_plan
            if plan is not None:
                self.first_plan = self.first_plan or plan
                self.clock_stopped = self.clock_stopped or bool(plan.stats.get("clock_stopped"))
        return action, state

    @property
    def stats(self) -> Any:
        return self.expert.stats

    @property
    def last_decision(self) -> Any:
        return self.expert.last_decision


def reference_episode(item: EvalScenario, time_limit: float = REFERENCE_TIME_LIMIT) -> dict[str, Any]:
    """The expert's episode on ``item``, planned to proven optimality (``time_limit`` seconds per plan is the
    safety stop): one reference record.

    ``cost`` is the task cost of the first plan when every plan of the episode was proven
    optimal and no clock stopped one (``proven``), the optimum every episode on the scenario
    is measured against (``return`` is minus it); otherwise the episode's own task cost.
    ``episode_cost`` is what the episode cost in the env (the same, unless physics made the
    expert replan), ``travel`` its travel.
    """
    # The benchmark's env: its floor's lattice (the families' extent), the split's capacity and physics.
    env = make_env("env", **item.floor, **item.env_options)
    try:
        policy = _Recorder(env, time_limit)
        episode = run_episode(env, policy, item.seed, options={"scenario": item.scenario}, stop_on_failure=False)
    finally:
        env.close()
    figures, info = episode.figures, episode.info
    success = bool(info["is_success"])
    proven = success and bool(policy.statuses) and all(s == "optimal" for s in policy.statuses)
    proven = proven and not policy.clock_stopped
    optimum = policy.first_plan.objective if proven and policy.first_plan is not None else None
    cost = float(optimum) if optimum is not None else float(info["task_cost"])
    return {
        "index": item.index,
        "seed": item.seed,
        "source": item.source,
        "scenario": item.scenario.name,
        "digest": scenario_digest(item.scenario),
        "world_digest": scenario_digest(item.scenario, named=False),
        "success": success,
        "cost": cost,
        "return": -cost if optimum is not None else float(figures.episode_return),
        "travel": float(info["travel_cost"]),
        "episode_cost": float(info["task_cost"]),
        "phases": int(figures.steps),
        "pushes": int(figures.pushes),
        "delivered": int(info["delivered"]),
        "plans": len(policy.statuses),
        "proven": proven,
        "clock_stopped": policy.clock_stopped,
        "status": policy.statuses[0] if policy.statuses else None,
        "planning_s": float(figures.planning_s),
    }


def compute_references(
    version: str,
    *,
    episodes: dict[str, int] | None = None,
    workers: int = 1,
    backend: str = "process",
    ray_address: str | None = None,
    time_limit: float = REFERENCE_TIME_LIMIT,
    progress: bool = False,
    keep: dict[str, Any] | None = None,
    checkpoint: Callable[[dict[str, Any]], None] | None = None,
) -> dict[str, Any]:
    """The reference file's content for split version ``version`` (``iid-v1``): every part's references.

    ``episodes`` maps a part to its episode count (default: each part's own). Episodes run
    here, on the process pool or on Ray (:func:`training.evaluation.tasks.run_all`);
    records are put in index order, so every backend gives the same file, planning times aside.
    ``keep`` is an earlier content of the same file (:func:`load_references`): its records
    whose seed and scenario digest are the episode's are kept, and only the other episodes
    run (a part grown by more episodes); it must have been made with ``time_limit``.
    ``checkpoint(content)`` receives the content so far after every finished episode (an
    interrupted run keeps them: :func:`partial_version`).
    """
    if keep is not None and (keep.get("split") != version or keep.get("time_limit_s") != time_limit):
        raise ReferenceFileError(
            f"the records kept must be of {version} with a {time_limit:g} s limit, "
            f"not of {keep.get('split')} with {keep.get('time_limit_s')} s"
        )
    parts = [s for s in SPLITS.values() if s.version == version and s.part]
    if not parts:
        known = ", ".join(sorted({s.version for s in SPLITS.values() if s.part}))
        raise ReferenceFileError(f"split {version!r} has no dev and test parts; known: {known}")
    content: dict[str, Any] = {"format": FORMAT, "split": version, "time_limit_s": time_limit, "parts": {}}
    for part in parts:
        items = split_scenarios(part, (episodes or {}).get(part.part))
        records = _kept(items, (keep or {}).get("parts", {}).get(part.part, []))
        done = {r["index"] for r in records}
        tasks = [(time_limit, item) for item in items if item.index not in done]
        with progress_bar(len(tasks), f"references {part.name}", enabled=progress) as bar:
            for record in run_all(tasks, _reference_task, workers=workers, backend=backend, ray_address=ray_address):
                records.append(record)
                content["parts"][part.part] = sorted(records, key=lambda r: r["index"])
                if checkpoint is not None:
                    checkpoint(content)
                bar.update(1)
        content["parts"][part.part] = sorted(records, key=lambda r: r["index"])
    return content


def partial_version(version: str) -> str:
    """The name under which an unfinished run of ``version``'s references keeps its records."""
    return f"{version}.partial"


def merged_records(*contents: dict[str, Any] | None) -> dict[str, Any] | None:
    """One content holding every part's records of ``contents`` (a later one's record wins its index)."""
    present = [c for c in contents if c is not None]
    if not present:
        return None
    parts: dict[str, dict[int, dict[str, Any]]] = {}
    for content in present:
        for part, records in content["parts"].items():
            parts.setdefault(part, {}).update({r["index"]: r for r in records})
    head = {k: v for k, v in present[-1].items() if k != "parts"}
    return {**head, "parts": {part: [by[i] for i in sorted(by)] for part, by in parts.items()}}


def _kept(items: Sequence[EvalScenario], records: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """The ``records`` that are references of ``items``: same index, seed and scenario digest."""
    by_index = {r.get("index"): r for r in records}
    out = []
    for item in items:
        record = by_index.get(item.index)
        if record is not None and record["seed"] == item.seed and record["digest"] == scenario_digest(item.scenario):
            out.append(record)
    return out


def _reference_task(task: tuple[float, EvalScenario]) -> dict[str, Any]:
    """``reference_episode(item, time_limit)`` as the pool's picklable unit of work, with its ``index``."""
    time_limit, item = task
    return reference_episode(item, time_limit)


def write_references(content: dict[str, Any], folder: Path = FOLDER, name: str | None = None) -> Path:
    """Write ``content`` as its split's reference file (one record per line, small diffs); its path.

    ``name`` is the file's name without ``.json`` (default the split version's).
    """
    path = folder / f"{name or content['split']}.json"
    folder.mkdir(parents=True, exist_ok=True)
    head = {k: v for k, v in content.items() if k != "parts"}
    lines = ["{" + json.dumps(head)[1:-1] + ', "parts": {']
    for k, (part, records) in enumerate(content["parts"].items()):
        body = ",\n".join("  " + json.dumps(r, sort_keys=True) for r in records)
        lines.append(f"{json.dumps(part)}: [\n{body}\n]" + ("," if k < len(content["parts"]) - 1 else ""))
    path.write_text("\n".join(lines) + "}}\n")
    load_references.cache_clear()
    return path


@cache
def load_references(version: str, folder: Path = FOLDER) -> dict[str, Any] | None:
    """The reference file of split version ``version``, checked; ``None`` when the version has none.

    Every record's fields must be there with values of the right type: finite numbers,
    whole counts, true or false, a status string or null (:class:`ReferenceFileError` names the
    first that is not). A file of release 0.2's format (the v1 splits) loads, marked legacy.
    """
    path = folder / f"{version}.json"
    if not path.is_file():
        return None
    try:
        content = read_json(path, max_bytes=MAX_BYTES)
    except (JsonInputError, OSError) as error:
        raise ReferenceFileError(f"{path}: not a reference file ({error})") from None
    if not isinstance(content, dict) or not isinstance(content.get("parts"), dict):
        raise ReferenceFileError(f"{path}: not a {FORMAT} file")
    fields = {FORMAT: FIELDS, LEGACY_FORMAT: LEGACY_FIELDS}.get(content.get("format"))
    if fields is None:
        raise ReferenceFileError(f"{path}: not a {FORMAT} file (its format is {content.get('format')!r})")
    for part, records in content["parts"].items():
        if not isinstance(records, list) or any(not isinstance(r, dict) or set(fields) - set(r) for r in records):
            raise ReferenceFileError(f"{path}: part {part!r} is not a list of reference records ({', '.join(fields)})")
        for k, record in enumerate(records):
            problem = _value_problem(record, fields)
            if problem is not None:
                raise ReferenceFileError(f"{path}: part {part!r} record {k}: {problem}")
    return content


def _value_problem(record: dict[str, Any], fields: Sequence[str]) -> str | None:
    """The first field of ``record`` whose value is not of its kind (see :func:`load_references`), or None."""
    for name in (n for n in NUMBERS if n in fields):
        value = record[name]
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            return f"{name} = {value!r} is not a finite number"
    for name in (n for n in COUNTS if n in fields):
        value = record[name]
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            return f"{name} = {value!r} is not a whole number >= 0"
    for name in (n for n in FLAGS if n in fields):
        if not isinstance(record[name], bool):
            return f"{name} = {record[name]!r} is not true or false"
    for name in ("source", "scenario", "digest", "world_digest"):
        if not isinstance(record[name], str):
            return f"{name} = {record[name]!r} is not a string"
    if record["status"] is not None and not isinstance(record["status"], str):
        return f"status = {record['status']!r} is not a string or null"
    return None


def refuse_legacy(split: Split | str, folder: Path = FOLDER) -> None:
    """:class:`ReferenceFileError` when ``split``'s reference file is of release 0.2's format (another task)."""
    split = get_split(split) if isinstance(split, str) else split
    content = load_references(split.version, folder) if split.part else None
    if content is not None and content.get("format") == LEGACY_FORMAT:
        newest = get_split(f"{split.base_name}:{split.part}").name
        raise ReferenceFileError(
            f"{split.version}'s references were made by release 0.2 under its task (a reward of +10 per delivery, "
            f"travel as the cost), not this release's task cost: benchmark {newest} instead (the published table of "
            "release 0.2 is reproduced by that release)"
        )


def part_references(split: Split | str, folder: Path = FOLDER) -> list[dict[str, Any]]:
    """The reference records of one part (``iid-v1:test``), in index order; [] when it has none."""
    split = get_split(split) if isinstance(split, str) else split
    content = load_references(split.version, folder) if split.part else None
    return list(content["parts"].get(split.part, [])) if content else []


def references_digest(records: Sequence[dict[str, Any]]) -> str:
    """sha256 of a part's reference records (their canonical JSON, planning times left out): what results carry."""
    stable = [{k: v for k, v in r.items() if k != "planning_s"} for r in records]
    return hashlib.sha256(json.dumps(stable, sort_keys=True).encode()).hexdigest()


def reference_for(item: EvalScenario) -> tuple[dict[str, Any] | None, str | None]:
    """The reference record of ``item`` and its part's references digest; ``(None, None)`` without one.

    :class:`ReferenceFileError` when the split's file has the episode with another scenario
    digest: the sampler changed what a published split draws.
    """
    if item.split not in SPLITS:
        return None, None
    refuse_legacy(item.split)
    records = part_references(item.split)
    if item.index >= len(records):
        return None, None
    record = records[item.index]
    if record["digest"] != scenario_digest(item.scenario) or record["seed"] != item.seed:
        raise ReferenceFileError(
            f"{item.split} episode {item.index} (seed {item.seed}) is not the scenario its reference file pins: "
            "a sampler changed a published split (make a new split version instead)"
        )
    return record, references_digest(records)


def digest_mismatches(split: Split | str) -> Iterator[str]:
    """A line for every scenario of ``split``'s reference file that sampling the split again does not give."""
    split = get_split(split) if isinstance(split, str) else split
    records = part_references(split)
    if not records:
        return
    for item, record in zip(split_scenarios(split, len(records)), records, strict=True):
        if scenario_digest(item.scenario) != record["digest"] or item.seed != record["seed"]:
            yield f"{split.name} episode {item.index} (seed {item.seed}, {item.source}): digest differs"


def replan_sample(split: Split | str, count: int) -> list[EvalScenario]:
    """``count`` scenarios of ``split``'s proven references, drawn by a generator seeded with the split's name.

    Only proven references are drawn: a proven plan is the same whatever the machine's load,
    so planning it again must give its cost, return and status exactly.
    """
    split = get_split(split) if isinstance(split, str) else split
    records = part_references(split)
    proven = [r["index"] for r in records if r["proven"]]
    if not proven or count < 1:
        return []
    rng = np.random.default_rng(zlib.crc32(split.name.encode()))
    chosen = sorted(rng.choice(proven, size=min(count, len(proven)), replace=False).tolist())
    items = split_scenarios(split, max(chosen) + 1)
    return [items[k] for k in chosen]


def replan_mismatches(item: EvalScenario, time_limit: float) -> list[str]:
    """Plan ``item`` again as its reference was planned; a line for every field that differs from the file's.

    Compares the cost and return (to :data:`COST_TOLERANCE`, relative), the status, the
    proven flag, the phases, pushes and deliveries.
    """
    record = part_references(item.split)[item.index]
    fresh = reference_episode(item, time_limit)
    where = f"{item.split} episode {item.index} (seed {item.seed}, {item.source})"
    lines = [
        f"{where}: {name} {record[name]!r} in the file, {fresh[name]!r} planned again"
        for name in REPLANNED
        if record[name] != fresh[name]
    ]
    for name in ("cost", "return"):
        if not math.isclose(record[name], fresh[name], rel_tol=COST_TOLERANCE, abs_tol=COST_TOLERANCE):
            lines.append(f"{where}: {name} {record[name]:.6f} in the file, {fresh[name]:.6f} planned again")
    return lines
