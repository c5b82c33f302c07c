"""The fixed references of every published split: each scenario's digest and the expert's result on it.

A split's reference file, ``training/evaluation/references/NAME-vN.json`` (in the
repository, one per split version), pins the split: for each part (``dev``, ``test``)
it lists every scenario's index, seed, source, name and digest
(:func:`~training.evaluation.results.scenario_digest`; ``world_digest`` without the
name, which the protocol's guard compares), and the MILP expert's episode on
it in the physics env, computed once with a generous planning limit
(:data:`REFERENCE_TIME_LIMIT` seconds per planning call): success, cost (metres),
return, phases, pushes, delivered, the planning calls and whether every one was proven
optimal (``proven``; ``status`` is the first call's SCIP status). The episode runs in the
env the benchmark gives every policy on that split: the split's capacity and physics
(:attr:`~training.evaluation.splits.EvalScenario.env_options`; ``perturbed``'s clutter
masses and frictions are drawn from the reset seed, so the reference meets the same ones).
A split whose plans are slow may be computed with another limit (``time_limit_s`` of its
file says which); a scenario with no plan proven within it is recorded all the same
(``proven`` false; ``success`` false when no plan was found).

The benchmark reads the cost ratio, SPL and the score's 100 from here, never from the
expert's run, whose wall-clock limit moves with the machine's load; the expert still
runs, and its disagreements with the reference are reported. ``fetchcarry benchmark
references --split NAME`` makes (or remakes) a file, on the local pool or on Ray, with the
same records either way. A test checks that sampling every split again gives every
digest of its file, so a change in a sampler cannot silently alter a published split.

File::

    {"format": "fetchcarry-references/1", "split": "iid-v1", "time_limit_s": 120.0,
     "parts": {"dev": [{"index": 0, "seed": 1000000000, "digest": "...", "cost": 7.35, ...}, ...],
               "test": [...]}}
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterator, Sequence
from functools import cache
from pathlib import Path
from typing import Any

from fetchcarry_env.jsontext import JsonInputError, read_json
from training.data.generate import progress_bar
from training.envs import make_env
from training.errors import BenchmarkError
from training.evaluation.results import scenario_digest
from training.evaluation.splits import SPLITS, EvalScenario, Split, get_split, split_scenarios
from training.evaluation.tasks import run_all
from training.rollout import run_episode

FORMAT = "fetchcarry-references/1"
FOLDER = Path(__file__).parent / "references"
REFERENCE_TIME_LIMIT = 120.0  # seconds per planning call: generous (the benchmark's expert has 10)
MAX_BYTES = 4_000_000  # a reference file is read within this size
FIELDS = (
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


class ReferenceError(BenchmarkError):
    """A reference file that is missing, broken, or that disagrees with its split's scenarios."""


def reference_path(split: Split | str, folder: Path = FOLDER) -> Path:
    """The reference file of ``split``'s version (``FOLDER/iid-v1.json``)."""
    split = get_split(split) if isinstance(split, str) else split
    return folder / f"{split.version}.json"


class _Recorder:
    """An :class:`~expert.policy.ExpertPolicy` that keeps the SCIP status of every planning call."""

    def __init__(self, env: Any, time_limit: float) -> None:
        from expert.policy import ExpertPolicy

        self.expert = ExpertPolicy(env, time_limit=time_limit)
        self.statuses: list[str] = []

    def reset(self) -> None:
        self.expert.reset()
        self.statuses = []

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
        return action, state

    @property
    def stats(self) -> Any:
        return self.expert.stats

    @property
    def last_decision(self) -> Any:
        return self.expert.last_decision


def reference_episode(item: EvalScenario, time_limit: float = REFERENCE_TIME_LIMIT) -> dict[str, Any]:
    """The expert's episode on ``item`` with ``time_limit`` seconds per plan: one reference record."""
    # The benchmark's env: its floor's lattice (the families' extent), the split's capacity and physics.
    env = make_env("env", **item.floor, **item.env_options)
    try:
        policy = _Recorder(env, time_limit)
        episode = run_episode(env, policy, item.seed, options={"scenario": item.scenario}, stop_on_failure=False)
    finally:
        env.close()
    figures, info = episode.figures, episode.info
    return {
        "index": item.index,
        "seed": item.seed,
        "source": item.source,
        "scenario": item.scenario.name,
        "digest": scenario_digest(item.scenario),
        "world_digest": scenario_digest(item.scenario, named=False),
        "success": bool(info["is_success"]),
        "cost": float(info["travel_cost"]),
        "return": float(figures.episode_return),
        "phases": int(figures.steps),
        "pushes": int(figures.pushes),
        "delivered": int(info["delivered"]),
        "plans": len(policy.statuses),
        "proven": bool(policy.statuses) and all(s == "optimal" for s in policy.statuses),
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
) -> dict[str, Any]:
    """The reference file's content for split version ``version`` (``iid-v1``): every part's references.

    ``episodes`` maps a part to its episode count (default: each part's own). Episodes run
    here, on the process pool or on Ray (:func:`training.evaluation.tasks.run_all`);
    records are put in index order, so every backend gives the same file, planning times aside.
    ``keep`` is an earlier content of the same file (:func:`load_references`): its records
    whose seed and scenario digest are the episode's are kept, and only the other episodes
    run (a part grown by more episodes); it must have been made with ``time_limit``.
    """
    if keep is not None and (keep.get("split") != version or keep.get("time_limit_s") != time_limit):
        raise ReferenceError(
            f"the records kept must be of {version} with a {time_limit:g} s limit, "
            f"not of {keep.get('split')} with {keep.get('time_limit_s')} s"
        )
    parts = [s for s in SPLITS.values() if s.version == version and s.part]
    if not parts:
        known = ", ".join(sorted({s.version for s in SPLITS.values() if s.part}))
        raise ReferenceError(f"split {version!r} has no dev and test parts; known: {known}")
    content: dict[str, Any] = {"format": FORMAT, "split": version, "time_limit_s": time_limit, "parts": {}}
    for part in parts:
        items = split_scenarios(part, (episodes or {}).get(part.part))
        records = _kept(items, (keep or {}).get("parts", {}).get(part.part, []))
        done = {r["index"] for r in records}
        tasks = [(time_limit, item) for item in items if item.index not in done]
        with progress_bar(len(tasks), f"references {part.name}", enabled=progress) as bar:
            for record in run_all(tasks, _reference_task, workers=workers, backend=backend, ray_address=ray_address):
                records.append(record)
                bar.update(1)
        content["parts"][part.part] = sorted(records, key=lambda r: r["index"])
    return content


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


def write_references(content: dict[str, Any], folder: Path = FOLDER) -> Path:
    """Write ``content`` as its split's reference file (one record per line, small diffs); its path."""
    path = folder / f"{content['split']}.json"
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
    """The reference file of split version ``version``, checked; ``None`` when the version has none."""
    path = folder / f"{version}.json"
    if not path.is_file():
        return None
    try:
        content = read_json(path, max_bytes=MAX_BYTES)
    except (JsonInputError, OSError) as error:
        raise ReferenceError(f"{path}: not a reference file ({error})") from None
    if not isinstance(content, dict) or content.get("format") != FORMAT or not isinstance(content.get("parts"), dict):
        raise ReferenceError(f"{path}: not a {FORMAT} file")
    for part, records in content["parts"].items():
        if not isinstance(records, list) or any(not isinstance(r, dict) or set(FIELDS) - set(r) for r in records):
            raise ReferenceError(f"{path}: part {part!r} is not a list of reference records ({', '.join(FIELDS)})")
    return content


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

    :class:`ReferenceError` when the split's file has the episode with another scenario
    digest: the sampler changed what a published split draws.
    """
    if item.split not in SPLITS:
        return None, None
    records = part_references(item.split)
    if item.index >= len(records):
        return None, None
    record = records[item.index]
    if record["digest"] != scenario_digest(item.scenario) or record["seed"] != item.seed:
        raise ReferenceError(
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
