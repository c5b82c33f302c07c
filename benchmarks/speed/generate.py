"""How fast dataset generation runs: episodes per second per worker, planning against simulation.

:func:`generation` runs the same seeded episodes of one episode source with each worker
count (the process pool of dataset generation, its start-up included, as a user of
``generate`` sees it) and returns one row of figures per count: episodes per second, per
second per worker, the seconds per episode in the planner, in the rest of the policy and
in the simulation, and the speed-up over the first worker count.
"""

from __future__ import annotations

import time
from typing import Any

from training.data.generate import run_episodes
from training.data.sources import EpisodeSource


def generation(source: EpisodeSource, episodes: int, worker_counts: list[int]) -> list[dict[str, Any]]:
    """Run episodes ``0 .. episodes-1`` of ``source`` with each worker count; one row of figures per count.

    ``policy_s`` includes the planner's seconds (``planning_s``); ``planning_share`` is the
    planner's part of the policy and simulation seconds; ``speed_up`` is relative to the
    first count. Times are wall-clock seconds.
    """
    rows: list[dict[str, Any]] = []
    for workers in worker_counts:
        started = time.perf_counter()
        figures = [record.figures for _, record in run_episodes(source, list(range(episodes)), workers=workers)]
        rows.append(_row(source, workers, figures, time.perf_counter() - started))
    for row in rows:
        row["speed_up"] = row["episodes_per_s"] / rows[0]["episodes_per_s"]
    return rows


def _row(source: EpisodeSource, workers: int, figures: list[Any], wall: float) -> dict[str, Any]:
    planning = sum(f.planning_s for f in figures)
    policy = sum(f.policy_s for f in figures)
    simulation = sum(f.simulation_s for f in figures)
    return {
        "family": source.family if source.family is not None else source.label,
        "workers": workers,
        "episodes": len(figures),
        "successes": sum(f.success for f in figures),
        "wall_s": wall,
        "episodes_per_s": len(figures) / wall,
        "episodes_per_s_per_worker": len(figures) / wall / workers,
        "planning_s_per_episode": planning / len(figures),
        "policy_s_per_episode": policy / len(figures),
        "simulation_s_per_episode": simulation / len(figures),
        "planning_share": planning / (policy + simulation) if policy + simulation else 0.0,
        "speed_up": 0.0,
    }
