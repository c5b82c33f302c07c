"""Run the episodes of recorded results again and say which come out the same, timings aside.

``fetchcarry benchmark --check RESULTS.json --policies P...`` (:func:`recheck`): for every
record of ``RESULTS.json`` whose policy is one of ``P`` (a run folder is its folder's
name, as the benchmark labels it), the same episode (split, seed, scenario) runs again,
acting as the benchmark made it act (the split's capacity and physics, or the run's
own capacity), and the new record is compared with the recorded one field by field:
every field the benchmark writes except the wall-clock ones (:func:`is_timing`:
``decision_ms``, ``mask_ms``, ``step_ms`` and any other ``*_ms`` or ``*_s``). Fields a
record holds beyond the benchmark's (``baseline``, ``training_seed`` of a reproduction)
are not results and are not compared. Numbers are compared exactly, as JSON holds them.

The expert's own run is wall-clock bound (its planning stops at 10 s a call, and what
it finds by then moves with the machine's load), so a mismatch of the expert on a
scenario its fixed reference needed long to prove (:func:`wall_clock_bound`) is marked
as such; it is still a mismatch.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from training.data.generate import progress_bar
from training.errors import BenchmarkError
from training.evaluation.episodes import close_all
from training.evaluation.metrics import fill_expert_costs
from training.evaluation.references import part_references, reference_for
from training.evaluation.results import read_results
from training.evaluation.runner import acting_spec, check_fits, run_tasks, with_capacity, with_observations
from training.evaluation.splits import SPLITS, EvalScenario, get_split, split_scenarios
from training.resolve import EXPERT, EXPERT_TIME_LIMIT, resolve_all
from training.rollout import is_timing

RECORD_TIMINGS = ("decision_ms", "mask_ms", "step_ms")  # a record's wall times (is_timing): never reproducible
MISSING = "(missing)"  # how a field the recorded record lacks is shown
BOUND_SHARE = 0.25  # an expert run is wall-clock bound where its reference took this share of its limit, or more


def differences(recorded: dict[str, Any], rerun: dict[str, Any]) -> dict[str, tuple[Any, Any]]:
    """``field -> (recorded, re-run)`` for every field of ``rerun`` (timings aside) whose value differs."""
    plain = json.loads(json.dumps(rerun))  # as results.json would hold it
    return {
        name: (recorded.get(name, MISSING), value)
        for name, value in plain.items()
        if name != "index" and not is_timing(name) and recorded.get(name, MISSING) != value
    }


def wall_clock_bound(record: dict[str, Any]) -> bool:
    """Whether ``record`` is the expert's on a scenario where its planning limit may bind.

    That is where the split's fixed reference was not proven optimal, or took at least
    :data:`BOUND_SHARE` of the expert's :data:`~training.resolve.EXPERT_TIME_LIMIT` to plan,
    or where the episode's own decisions took that limit in all (a machine loaded enough to
    slow any planning call to its safety stop).
    """
    if record["policy"] != EXPERT:
        return False
    if record["decision_ms"] * record["phases"] >= 1000.0 * EXPERT_TIME_LIMIT:
        return True
    split = SPLITS.get(record["split"])
    if split is None or not split.part:
        return True  # no fixed reference: not known, so not promised
    reference = {r["seed"]: r for r in part_references(split)}.get(record["seed"])
    return reference is None or not reference["proven"] or reference["planning_s"] >= BOUND_SHARE * EXPERT_TIME_LIMIT


@dataclass(frozen=True)
class Mismatch:
    """One recorded episode that came out differently."""

    policy: str
    split: str
    seed: int
    fields: dict[str, tuple[Any, Any]]  # field -> (recorded, re-run)
    bound: bool = False  # the expert on a scenario where its wall-clock limit may bind

    def line(self) -> str:
        """``bc-mlp-s0 iid-v1:test seed 1000500001: cost 7.52 recorded, 7.61 re-run; ...``."""
        shown = "; ".join(f"{name} {_shown(a)} recorded, {_shown(b)} re-run" for name, (a, b) in self.fields.items())
        note = " (the expert at its wall-clock planning limit)" if self.bound else ""
        return f"{self.policy} {self.split} seed {self.seed}: {shown}{note}"


@dataclass(frozen=True)
class Recheck:
    """What :func:`recheck` found: how many of the checked records came out identical, timings aside."""

    checked: int
    identical: int
    mismatches: list[Mismatch] = field(default_factory=list)
    not_checked: int = 0  # records of other policies (or splits) in the file

    @property
    def all_identical(self) -> bool:
        return self.identical == self.checked

    def line(self) -> str:
        others = f"; {self.not_checked} records of other policies or splits not re-run" if self.not_checked else ""
        return (f"{self.identical} of {self.checked} records identical (timings aside: "
                f"{', '.join(RECORD_TIMINGS)}){others}")  # fmt: skip


def _shown(value: Any) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def recheck(
    file: str | Path,
    policies: list[str],
    *,
    splits: Sequence[str] | None = None,
    workers: int = 1,
    backend: str = "process",
    ray_address: str | None = None,
    obs_mode: str | None = None,
    capacity: str | None = None,
    progress: bool = False,
) -> Recheck:
    """Run again the episodes of ``file``'s records of ``policies`` (on ``splits`` only, if given); compare.

    Raises :class:`BenchmarkError` (bad input) for a policy without records in the file and
    for records of a folder of scenarios (only a split's episodes can be drawn again).
    """
    records = read_results(file)
    specs = with_capacity(with_observations(resolve_all(policies), obs_mode), capacity)
    wanted = None if splits is None else {get_split(name).name for name in splits}
    chosen = [r for r in records if r["policy"] in {s.name for s in specs} and (wanted is None or r["split"] in wanted)]
    missing = [s.name for s in specs if not any(r["policy"] == s.name for r in chosen)]
    if missing:
        raise BenchmarkError(f"{file} holds no record of {', '.join(missing)} to check")
    items = _items(chosen)
    check_fits(specs, list(items.values()))
    for item in items.values():
        reference_for(item)  # a published split whose scenarios differ from its reference file is refused
    by_name = {spec.name: spec for spec in specs}
    tasks = [(acting_spec(by_name[r["policy"]], items[(r["split"], r["seed"])]), items[(r["split"], r["seed"])])
             for r in chosen]  # fmt: skip
    rerun = _run(tasks, workers, backend, ray_address, progress)
    experts = [dict(r) for r in records if r["policy"] == EXPERT and r["policy"] not in by_name]
    fill_expert_costs(rerun + experts)  # where no fixed reference: the recorded expert's costs, as the file had them
    new = {(r["policy"], r["split"], r["seed"]): r for r in rerun}
    mismatches = []
    for record in chosen:
        again = new[(record["policy"], record["split"], record["seed"])]
        found = differences(record, again)
        if found:
            mismatches.append(Mismatch(record["policy"], record["split"], record["seed"], found,
                                       wall_clock_bound(record) or wall_clock_bound(again)))  # fmt: skip
    return Recheck(len(chosen), len(chosen) - len(mismatches), mismatches, len(records) - len(chosen))


def _items(records: Iterable[dict[str, Any]]) -> dict[tuple[str, int], EvalScenario]:
    """``(split, seed) -> scenario`` for every episode of ``records``, drawn again from its split."""
    seeds: dict[str, set[int]] = {}
    for record in records:
        seeds.setdefault(record["split"], set()).add(record["seed"])
    items = {}
    for name, wanted in seeds.items():
        if name not in SPLITS:
            raise BenchmarkError(f"records of {name!r} cannot be drawn again: only a split's episodes can be checked")
        split = SPLITS[name]
        indices = sorted(seed - split.seed(0) for seed in wanted)
        if indices[0] < 0:
            raise BenchmarkError(f"seed {min(wanted)} is not an episode of {name}")
        drawn = split_scenarios(split, indices[-1] + 1)
        items.update({(name, item.seed): item for item in drawn if item.seed in wanted})
    return items


def _run(tasks: list, workers: int, backend: str, ray_address: str | None, progress: bool) -> list[dict[str, Any]]:
    """The records of ``tasks`` (each with its ``index``), as the benchmark makes them."""
    out = []
    bar = progress_bar(len(tasks), "check", enabled=progress)
    try:
        for record in run_tasks(tasks, workers=workers, backend=backend, ray_address=ray_address):
            out.append(record)
            bar.update(1)
    finally:
        bar.close()
        close_all()
    return out
