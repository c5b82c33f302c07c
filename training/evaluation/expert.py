"""How well the MILP expert does in the physics env: success rate, failures, speed, per family.

For each family, episodes ``0 .. n-1`` run with seeds ``seed + k`` (the env draws the
scenario from the seed), the :class:`~expert.policy.ExpertPolicy` acting, on the same
process pool as dataset generation. Every failed episode is written out as the
scenario file it drew (``<family>-seed<seed>.json``, a valid ``fetchcarry-scenario/1``
file) and a sidecar (``<family>-seed<seed>.outcome.json``) with the seed, the figures
and the commands that replay it:

    fetchcarry rollout --family push --seed 1234        # the same episode
    fetchcarry rollout --scenario <family>-seed<seed>.json   # the same scenario, fixed

The figures per family (episodes per second per worker, planning against simulation
seconds) are what ``docs/benchmarks/datasets.md`` reports.
"""

from __future__ import annotations

import json
import statistics
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from fetchcarry_env.families import TRAINING_FAMILIES
from training.data.generate import DEFAULT_TIME_LIMIT, EpisodeSource, progress_bar, run_episodes
from training.rollout import EpisodeRecord

DEFAULT_FAMILIES = TRAINING_FAMILIES
SUCCESS_GOAL = 0.99  # fraction of episodes the expert must finish (issue 4, section 2)


@dataclass(frozen=True)
class FamilyResult:
    """The expert on one family (seconds, episodes)."""

    family: str
    episodes: int
    successes: int
    success_rate: float
    failures: list[dict[str, Any]]  # seed, outcome, delivered/objects, scenario file of each failed episode
    mean_steps: float
    replans: int  # planning calls after the first of an episode, all episodes together
    repairs: int  # actions the expert adapted to the env's rules (see expert.policy), all episodes together
    planner_failures: int  # planning calls without a plan
    planning_s: float  # seconds in the planner, all episodes together
    policy_s: float  # seconds in ExpertPolicy.predict (planning and decoding)
    simulation_s: float  # seconds in env.reset and env.step
    mean_planning_s: float  # per episode
    max_planning_s: float  # the slowest episode's planning
    wall_s: float  # seconds for the family, as the user waits
    workers: int
    episodes_per_s_per_worker: float = field(default=0.0)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def evaluate_expert(
    families: tuple[str, ...] = DEFAULT_FAMILIES,
    *,
    episodes: int = 500,
    seed: int = 0,
    workers: int = 1,
    time_limit: float = DEFAULT_TIME_LIMIT,
    failures_dir: Path | None = None,
    progress: bool = True,
    start: int = 0,
) -> list[FamilyResult]:
    """Run the expert on ``episodes`` seeded scenarios of each family and collect the figures.

    Episodes ``start .. start + episodes - 1`` are run (seeds ``seed + k``), so a long
    evaluation can be split. Failures are written to ``failures_dir`` when given.
    """
    results: list[FamilyResult] = []
    for family in families:
        source = EpisodeSource(family=family, seed=seed, policy="expert", time_limit=time_limit)
        records: list[EpisodeRecord] = []
        failures: list[dict[str, Any]] = []  # written as each failed episode ends, so an interruption keeps them
        started = time.perf_counter()
        try:
            with progress_bar(episodes, f"expert on {family}", enabled=progress) as bar:
                for _, record in run_episodes(source, list(range(start, start + episodes)), workers=workers):
                    records.append(record)
                    if not record.figures.success:
                        failures.append(_failure_entry(family, record, failures_dir))
                    bar.update(1)
                    bar.set_postfix_str(f"success {sum(r.figures.success for r in records)}/{len(records)}")
        except KeyboardInterrupt:
            if records:
                results.append(_summarise(family, records, failures, time.perf_counter() - started, workers))
            raise EvaluationInterrupted(results) from None
        failures.sort(key=lambda entry: entry["seed"])
        results.append(_summarise(family, records, failures, time.perf_counter() - started, workers))
    return results


class EvaluationInterrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`evaluate_expert`; ``results`` holds the figures of the episodes that finished."""

    def __init__(self, results: list[FamilyResult]) -> None:
        super().__init__("interrupted")
        self.results = results


def _summarise(
    family: str, records: list[EpisodeRecord], failures: list[dict[str, Any]], wall: float, workers: int
) -> FamilyResult:
    figures = [r.figures for r in records]
    successes = sum(f.success for f in figures)
    planning = [f.planning_s for f in figures]
    return FamilyResult(
        family=family,
        episodes=len(figures),
        successes=successes,
        success_rate=successes / len(figures),
        failures=failures,
        mean_steps=statistics.fmean(f.steps for f in figures),
        replans=sum(f.replans for f in figures),
        repairs=sum(f.repairs for f in figures),
        planner_failures=sum(f.planner_failures for f in figures),
        planning_s=sum(planning),
        policy_s=sum(f.policy_s for f in figures),
        simulation_s=sum(f.simulation_s for f in figures),
        mean_planning_s=statistics.fmean(planning),
        max_planning_s=max(planning),
        wall_s=wall,
        workers=workers,
        episodes_per_s_per_worker=len(figures) / wall / workers,
    )


def _failure_entry(family: str, record: EpisodeRecord, failures_dir: Path | None) -> dict[str, Any]:
    figures = record.figures
    entry: dict[str, Any] = {
        "family": family,
        "seed": record.seed,
        "scenario": figures.scenario,
        "outcome": figures.outcome,
        "failure": figures.failure,
        "delivered": f"{figures.delivered}/{figures.objects}",
        "steps": figures.steps,
        "replans": figures.replans,
        "collisions": figures.collisions,
        "invalid_actions": figures.invalid_actions,
        "replay": f"fetchcarry rollout --family {family} --seed {record.seed}",
    }
    if failures_dir is not None:
        failures_dir.mkdir(parents=True, exist_ok=True)
        stem = f"{family}-seed{record.seed}"
        scenario_file = failures_dir / f"{stem}.json"
        scenario_file.write_text(json.dumps(record.scenario, indent=2) + "\n")
        entry["scenario_file"] = str(scenario_file)
        entry["replay_scenario"] = f"fetchcarry rollout --scenario {scenario_file}"
        sidecar = {**entry, "figures": figures.to_dict(), "actions": record.actions.tolist()}
        (failures_dir / f"{stem}.outcome.json").write_text(json.dumps(sidecar, indent=2) + "\n")
    return entry


def results_table(results: list[FamilyResult]) -> str:
    """A plain-text table of the results, one family a row.

    ``plan %`` is the planner's share of the time in the policy and the simulation.
    """
    header = (
        f"{'family':<10} {'episodes':>8} {'success':>9} {'fails':>5} {'replans':>7} {'repairs':>7} {'steps':>6} "
        f"{'plan s/ep':>9} {'max plan s':>10} {'sim s/ep':>8} {'plan %':>6} {'ep/s/worker':>11}"
    )
    lines = [header, "-" * len(header)]
    for r in results:
        busy = r.policy_s + r.simulation_s
        lines.append(
            f"{r.family:<10} {r.episodes:>8} {r.success_rate:>8.1%} {len(r.failures):>5} {r.replans:>7} {r.repairs:>7} "
            f"{r.mean_steps:>6.1f} {r.mean_planning_s:>9.3f} {r.max_planning_s:>10.2f} "
            f"{r.simulation_s / r.episodes:>8.3f} {100 * r.planning_s / busy if busy else 0:>6.1f} "
            f"{r.episodes_per_s_per_worker:>11.2f}"
        )
    return "\n".join(lines)
