"""Run a benchmark: every policy on every scenario of a split (or a folder), then write the results.

:func:`run_benchmark` always runs the two reference policies, ``expert`` (the MILP
planner: on a published split's part, checked against the split's fixed reference,
which every cost ratio is to; elsewhere every cost ratio is to its cost on the same
scenario) and ``random-phases`` (the random policy of the candidate phases), next to the policies
asked for. Every policy acts in an env of the split's capacity and physics
(:func:`acting_spec`: ``objects`` has room for eight objects, ``perturbed`` varies the
clutter's mass and friction), as the split's reference was computed. Episodes run in this process
(``workers=1``), on a process pool or on Ray (:mod:`training.evaluation.tasks`), with the worker set-up of
``fetchcarry generate`` (:mod:`training.data.generate`): workers ignore Ctrl-C and die with
their parent.

``OUT_DIR/results.json`` is rewritten as episodes finish (at most every
:data:`WRITE_EVERY_S` seconds) and once more at the end, so an interrupted run keeps its
finished episodes; ``summary.md``, ``splits.png`` and (with several object counts)
``objects.png`` are written at the end and on an interrupt. With ``resume``, the
episodes already in ``results.json`` are kept and only the others run (an interrupted
benchmark continues where it stopped); the records of other policies or splits in the
file stay after this run's, and in the summary, so one folder can grow a policy at a
time. A record is this run's episode when its policy, split, seed and scenario digest
(:func:`training.evaluation.results.scenario_digest`) are the episode's: a scenario file
whose content changed runs again, and its old record goes. Records are kept in a fixed
order (policy, then episode), so the same command gives the same file, timings aside.

The file's format, its validation and atomic writes are
:mod:`training.evaluation.results`'s: a file that breaks the schema is refused (exit 2,
naming the file and the record), never partly dropped. A benchmark holds the output
folder's lock (:class:`~training.evaluation.results.ResultsLock`) from before it reads
the file until it wrote the last one, so a second benchmark on the same folder stops at
once (exit 2, naming the holder) rather than overwrite the first one's records.
"""

from __future__ import annotations

import time
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any

from fetchcarry_env.observation import Capacity
from fetchcarry_env.observations import mode_names
from training.data.generate import BACKENDS, progress_bar
from training.errors import BenchmarkError
from training.evaluation.episodes import close_all, run_task
from training.evaluation.metrics import RANDOM_PHASES, Row, by_objects, fill_expert_costs, summarise
from training.evaluation.references import reference_for
from training.evaluation.report import source_table, summary_markdown
from training.evaluation.results import RESULTS, ResultsLock, read_results, scenario_digest
from training.evaluation.results import write_results as write_results_file
from training.evaluation.splits import EvalScenario, folder_scenarios, split_scenarios
from training.evaluation.tasks import run_all
from training.pictures.benchmark import plot_splits
from training.resolve import EXPERT, RANDOM, PolicySpec, check_obs_mode, resolve, resolve_all

SUMMARY, PLOT, OBJECTS_PLOT = "summary.md", "splits.png", "objects.png"
WRITE_EVERY_S = 1.0  # seconds between rewrites of results.json while episodes finish

Task = tuple[PolicySpec, EvalScenario]


@dataclass(frozen=True)
class BenchmarkReport:
    """What a finished benchmark wrote."""

    out: Path
    records: list[dict[str, Any]]
    rows: list[Row]
    resumed: int = 0  # episodes found in results.json and not run again (resume)


def run_benchmark(
    policies: list[str],
    *,
    out: str | Path,
    split: str | list[str] | None = None,
    scenarios: str | Path | None = None,
    episodes: int | None = None,
    workers: int = 1,
    backend: str = "process",
    ray_address: str | None = None,
    progress: bool = False,
    resume: bool = False,
    obs_mode: str | None = None,
    capacity: str | None = None,
) -> BenchmarkReport:
    """Evaluate ``policies`` (registry names or run folders) on ``split`` or the scenario files in ``scenarios``.

    ``split`` is a split's name or a list of names (the first ``episodes`` of each).
    ``resume`` keeps the records of ``out/results.json`` that belong to this run's
    episodes (same policy, split, seed and scenario digest) and runs only the others; the
    file's other records (other policies or splits) are written back after this run's.
    ``capacity`` (``"objects=8,..."``) is the observation's slots every policy acts with
    (:func:`with_capacity`); None: each run folder's own where it holds the split's scenarios, else the
    split's (:func:`acting_spec`).

    Raises :class:`BenchmarkError` for bad input before any episode runs (a results file
    that breaks its schema, another benchmark writing to ``out``); a
    ``KeyboardInterrupt`` propagates after the finished episodes are written.
    """
    if (split is None) == (scenarios is None):
        raise BenchmarkError("give exactly one of a split and a folder of scenarios")
    if workers < 1:
        raise BenchmarkError(f"the number of workers must be at least 1, got {workers}")
    if backend not in BACKENDS:
        raise BenchmarkError(f"unknown backend {backend!r}; known: {', '.join(BACKENDS)}")
    if episodes is not None and episodes < 1:
        raise BenchmarkError(f"the number of episodes must be at least 1, got {episodes}")
    specs = with_capacity(with_observations(with_references(policies), obs_mode), capacity)
    if split is not None:
        names = [split] if isinstance(split, str) else list(split)
        if not names:
            raise BenchmarkError("give at least one split")
        items = [item for name in dict.fromkeys(names) for item in split_scenarios(name, episodes)]
    else:
        items = folder_scenarios(scenarios, episodes)
    check_fits(specs, items)
    for item in items:
        reference_for(item)  # a published split whose scenarios differ from its reference file is refused
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with ResultsLock(out):
        return _run([(acting_spec(spec, item), item) for spec in specs for item in items], out, workers, backend,
                    ray_address, progress, resume)  # fmt: skip


def _run(
    tasks: list[Task], out: Path, workers: int, backend: str, ray_address: str | None, progress: bool, resume: bool
) -> BenchmarkReport:
    """Run ``tasks`` (those not in ``out/results.json`` with ``resume``), writing the results as they finish."""
    order = {(spec.name, item.split, item.index): k for k, (spec, item) in enumerate(tasks)}
    records, others = finished_records(out, tasks) if resume else ([], [])
    done = {(r["policy"], r["split"], r["index"]) for r in records}
    tasks = [(spec, item) for spec, item in tasks if (spec.name, item.split, item.index) not in done]
    resumed = len(records)
    last_write = time.monotonic()
    bar = progress_bar(len(tasks) + resumed, "benchmark", initial=resumed, enabled=progress)
    try:
        for record in run_tasks(tasks, workers=workers, backend=backend, ray_address=ray_address):
            records.append(record)
            bar.update(1)
            if time.monotonic() - last_write > WRITE_EVERY_S:
                write_results(out, records, order, others)
                last_write = time.monotonic()
    finally:
        bar.close()
        close_all()
        records = write_results(out, records, order, others)
        rows = summarise(records) if records else []
        if rows:
            splits = dict.fromkeys(row.split for row in rows)
            write_report(out, rows, records, title=f"Benchmark: {', '.join(splits)}")
    return BenchmarkReport(out, records, rows, resumed)


def finished_records(out: Path, tasks: list[Task]) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """``(finished, others)``: the records of ``out/results.json`` that are episodes of ``tasks`` (with their
    ``index``), and its records of other episodes as they are; both [] without the file.

    A record of a task's policy, split and seed but another scenario digest (the scenario
    file changed, or a schema-0 record without a digest) is the task's old result: it is
    left out and the task runs again. A file that breaks the schema is a
    :class:`~training.evaluation.results.ResultsError`.
    """
    try:
        saved = read_results(out / RESULTS)
    except FileNotFoundError:
        return [], []
    items = {(item.split, item.seed): item for _, item in tasks}
    digests = {key: scenario_digest(item.scenario) for key, item in items.items()}
    names = {spec.name for spec, _ in tasks}
    kept, others = {}, []
    for record in saved:
        key = (record["split"], record["seed"])
        if record["policy"] not in names or key not in items:
            others.append(record)
        elif record["digest"] == digests[key]:
            kept[(record["policy"], *key)] = {**record, "index": items[key].index}
    return list(kept.values()), others


def with_references(policies: list[str]) -> list[PolicySpec]:
    """The specs of ``policies`` with ``expert`` and ``random-phases`` first (added if missing)."""
    if not policies:
        raise BenchmarkError("give at least one policy")
    specs = resolve_all(policies)
    fixed = (EXPERT, RANDOM_PHASES, RANDOM)
    clashes = [s.run or s.user for s in specs if (s.run or s.user) is not None and s.name in fixed]
    if clashes:
        raise BenchmarkError(
            f"a run folder may not be named {' or '.join(map(repr, fixed))} (the references): {clashes[0]}"
        )
    names = [s.name for s in specs]
    references = [resolve(name) for name in (EXPERT, RANDOM_PHASES) if name not in names]
    ordered = references + specs
    return sorted(
        ordered, key=lambda s: (s.name != EXPERT, s.name != RANDOM_PHASES)
    )  # stable: the rest keep their order


def with_observations(specs: list[PolicySpec], obs_mode: str | None) -> list[PolicySpec]:
    """``specs`` acting in envs of ``obs_mode``, but for run folders of an image network (they keep their own mode).

    ``obs_mode`` None (not given): the state, and each image network's own mode; a run
    folder of an image network trained on another mode than a given one is refused.
    """
    if obs_mode is None:
        return specs
    if obs_mode not in mode_names():
        raise BenchmarkError(f"unknown observation mode {obs_mode!r}; known: {', '.join(mode_names())}")
    for spec in specs:
        check_obs_mode(spec, obs_mode)
    if obs_mode == "state":
        return specs
    return [s if "obs_mode" in s.env_options else replace(s, env_options={**s.env_options, "obs_mode": obs_mode})
            for s in specs]  # fmt: skip


def acting_spec(spec: PolicySpec, item: EvalScenario) -> PolicySpec:
    """``spec`` with the env options it acts in on ``item``: the split's physics, and a capacity.

    The capacity is the split's (:attr:`EvalScenario.capacity`, which holds every scenario of
    the split), unless ``spec`` is a run folder with its own: then its own when that holds the
    split's, or when its network acts only at its own (a flat network; :func:`check_fits`
    refuses the scenarios that do not fit), else the split's (a set encoder acts at any capacity).
    """
    options = {**spec.env_options, **item.env_options}
    own = spec.env_options.get("capacity")
    if own is not None:
        own = own if isinstance(own, Capacity) else Capacity(**own)
        if own.covers(item.capacity) or not acts_at_any_capacity(spec):
            options["capacity"] = own
    return replace(spec, env_options=options)


def acts_at_any_capacity(spec: PolicySpec) -> bool:
    """True unless ``spec`` is a run folder of a flat network (one input per feature of its trained capacity).

    A run whose network is a set encoder (every member of an ensemble) acts at any capacity,
    as does a policy that is no run folder (it is built for the env it is given).
    """
    return spec.run is None or _set_encoder_run(spec.run)


@cache
def _set_encoder_run(run: str) -> bool:
    """True when the run folder ``run`` holds a set encoder (every member's, for an ensemble)."""
    from training.learners.runs import network_config, read_saved  # torch at its top

    try:
        saved = read_saved(run)
        members = saved["options"]["members"] if saved.get("kind") == "ensemble" else [saved]
        return all(network_config(member).encoder == "set" for member in members)
    except (KeyError, TypeError, ValueError, OSError):
        return False  # not a network run this can read: keep the capacity it was trained with


def with_capacity(specs: list[PolicySpec], capacity: str | None) -> list[PolicySpec]:
    """``specs`` acting at the observation ``capacity`` (None: unchanged); :class:`BenchmarkError` if one cannot.

    A run folder of the set encoder acts at any capacity; one of a flat network only at
    the capacity it was trained with, so another is refused here, before any episode runs.
    """
    if capacity is None:
        return specs
    try:
        wanted = asdict(Capacity.parse(capacity))
    except ValueError as error:
        raise BenchmarkError(str(error)) from None
    out = []
    for spec in specs:
        own = spec.env_options.get("capacity")
        own = asdict(own) if isinstance(own, Capacity) else own
        if spec.run is not None and own is not None and own != wanted and not acts_at_any_capacity(spec):
            raise BenchmarkError(
                f"{spec.name} was trained with the capacity {_capacity_text(own)} and its network (not the set "
                f"encoder) acts at no other: give --capacity {_capacity_text(own)} or leave it out"
            )
        out.append(replace(spec, env_options={**spec.env_options, "capacity": wanted}))
    return out


def _capacity_text(capacity: dict[str, int]) -> str:
    return ",".join(f"{k}={v}" for k, v in capacity.items())


def check_fits(specs: list[PolicySpec], items: list[EvalScenario]) -> None:
    """Every scenario fits the capacity every policy acts at there; :class:`BenchmarkError` names what does not."""
    problems = []
    for spec in specs:
        if spec.env_options.get("capacity") is None:
            continue  # it acts at the split's capacity, which holds every scenario of the split
        for item in items:
            try:
                _capacity(acting_spec(spec, item)).check(item.scenario)
            except ValueError as error:
                problems.append(f"{spec.name} cannot act in {item.source} ({item.scenario.name}): {error}")
    if problems:
        raise BenchmarkError("\n".join(problems[:10]))


def _capacity(spec: PolicySpec) -> Capacity:
    capacity = spec.env_options["capacity"]
    return capacity if isinstance(capacity, Capacity) else Capacity(**capacity)


def write_results(
    out: Path,
    records: list[dict[str, Any]],
    order: dict[tuple[str, str, int], int],
    others: Sequence[dict[str, Any]] = (),
) -> list[dict]:
    """Fill in the expert's costs, sort ``records`` into task order and write them, then ``others``, atomically."""
    fill_expert_costs(records)
    ordered = sorted(records, key=lambda r: order[(r["policy"], r["split"], r["index"])])
    public = [{k: v for k, v in r.items() if k != "index"} for r in ordered] + list(others)
    write_results_file(out / RESULTS, public)
    return public


def write_report(out: Path, rows: list[Row], records: list[dict[str, Any]], title: str) -> None:
    """``summary.md`` (the table of ``rows``, then per scenario source of each split) and ``splits.png`` in ``out``."""
    tables = [summary_markdown(rows, title)]
    for split in dict.fromkeys(row.split for row in rows):
        lines = source_table(
            records, split, f"Per scenario source ({split}): success [95 % CI], cost ratio in brackets."
        )
        tables += ["\n".join(lines)] if lines else []
    (out / SUMMARY).write_text("\n".join(tables))
    plot_splits(rows, out / PLOT)
    if len({r["objects"] for r in records}) > 1:  # success and cost ratio against the number of objects
        plot_splits(by_objects(records), out / OBJECTS_PLOT, groups_label="objects in the scenario")


def run_tasks(
    tasks: Sequence[Task], *, workers: int = 1, backend: str = "process", ray_address: str | None = None
) -> Iterator[dict[str, Any]]:
    """Each task's record (with its ``index`` in the split), as they finish (Ray: on ``ray_address``, if given)."""
    yield from run_all(tasks, _indexed, workers=workers, backend=backend, ray_address=ray_address)


def _indexed(task: Task) -> dict[str, Any]:
    return {**run_task(task), "index": task[1].index}
