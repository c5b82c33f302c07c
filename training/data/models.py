"""A collection of exported MILPs for a family's seeds (``fetchcarry generate --models``).

For researchers of learned MILP solving: scenario ``k`` of the collection is the family's
scenario of seed ``seed + k`` (``Family.sample(numpy.random.default_rng(seed + k))``, the
scenario the env draws on ``reset(seed=seed + k)``). The planner plans it once with
``export_models`` (:mod:`expert.milp.export`): every MILP it solves (one per phase count
tried, cuts and fixings included) is written as MPS with a JSON of its variables'
meanings, SCIP's status and the optimum it proved. Next to them: the scenario
(``scenario.json``, to check an answer in the simulator) and the planner's plan
(``plan.json``).

Layout of the folder ``out``::

    collection.json                 fetchcarry-milp-collection/1: options and one entry per seed
    seed-<seed>/scenario.json       fetchcarry-scenario/1
    seed-<seed>/plan.json           fetchcarry-plan/1
    seed-<seed>/<scenario>_N<n>.mps and .json

A seed's folder is written aside (``seed-<seed>.partial``) and renamed when whole, and
``collection.json`` is rewritten after each seed, so an interrupted run keeps every seed
it finished and the same call resumes after them. Evaluation seeds (from 10^9) are
refused as for datasets (:func:`training.data.generate.check_training_seeds`).
"""

from __future__ import annotations

import json
import os
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from fetchcarry_env.errors import InputError
from fetchcarry_env.families import FAMILY_NAMES, get_family
from training.data.generate import check_training_seeds

COLLECTION_FORMAT = "fetchcarry-milp-collection/1"
INDEX = "collection.json"
PARTIAL = ".partial"


class CollectionMismatchError(InputError):
    """The folder holds a collection made with other options (family, first seed, time limit)."""


@dataclass(frozen=True)
class CollectionConfig:
    """What a collection is made of: the family, the first seed, how many seeds, the planner's time (seconds)."""

    family: str
    seed: int
    episodes: int
    time_limit: float = 60.0  # seconds per scenario for the planner (an optimum unproven by then is None)

    def manifest(self) -> dict[str, Any]:
        """The options a resumed run must share (the count may grow)."""
        return {"family": self.family, "seed": self.seed, "time_limit": self.time_limit}


@dataclass(frozen=True)
class CollectionReport:
    """What a run did: the seeds found finished, the seeds made now, the models and optima in the folder."""

    out: Path
    resumed: int
    generated: int
    models: int  # MPS files in the collection
    proven: int  # seeds whose final model's optimum SCIP proved
    wall_s: float


def generate_models(
    config: CollectionConfig,
    out: Path,
    *,
    progress: bool = True,
    allow_evaluation_seeds: bool = False,
    on_seed: Callable[[int, dict[str, Any]], None] | None = None,
) -> CollectionReport:
    """Make (or finish) the collection ``config`` in the folder ``out`` (made if missing).

    Raises :class:`~training.data.generate.EvaluationSeedError` for evaluation seeds (unless
    allowed), :class:`CollectionMismatchError` when ``out`` holds a collection made with
    other options, ``InputError`` for an unknown family or a folder that cannot be made.
    ``on_seed(index, entry)`` is called after each seed is written (tests use it to interrupt).
    """
    if config.family not in FAMILY_NAMES:
        raise InputError(f"unknown family {config.family!r}: choose one of {', '.join(FAMILY_NAMES)}")
    check_training_seeds(config.seed, config.episodes, allow_evaluation_seeds)
    started = time.perf_counter()
    index = _open_index(config, out)
    done = {entry["seed"] for entry in index["scenarios"]}
    seeds = [config.seed + k for k in range(config.episodes)]
    missing = [s for s in seeds if s not in done or not (out / f"seed-{s}").is_dir()]
    index["scenarios"] = [e for e in index["scenarios"] if e["seed"] not in missing]
    from expert.planner import plan  # imported here: pyscipopt costs about 0.15 s

    family = get_family(config.family)
    finished = len(seeds) - len(missing)
    desc = f"models {config.family}"
    bar = tqdm(total=len(seeds), initial=finished, desc=desc, unit="scenario", disable=not progress)
    with bar:
        for seed in missing:
            entry = _export_seed(plan, family.sample(np.random.default_rng(seed)), seed, out, config.time_limit)
            index["scenarios"].append(entry)
            index["scenarios"].sort(key=lambda e: e["seed"])
            _write_json(out / INDEX, index)
            bar.update(1)
            bar.set_postfix_str(f"proven {sum(e['status'] == 'optimal' for e in index['scenarios'])}", refresh=False)
            if on_seed is not None:
                on_seed(seed - config.seed, entry)
    mine = [e for e in index["scenarios"] if e["seed"] in set(seeds)]
    return CollectionReport(
        out=out,
        resumed=len(seeds) - len(missing),
        generated=len(missing),
        models=sum(len(e["models"]) for e in mine),
        proven=sum(e["status"] == "optimal" for e in mine),
        wall_s=time.perf_counter() - started,
    )


def _open_index(config: CollectionConfig, out: Path) -> dict[str, Any]:
    """The folder's index (a new one when there is none); a collection of other options is refused."""
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise InputError(f"{out}: cannot make the folder ({error.strerror})") from None
    path = out / INDEX
    if not path.exists():
        if any(p for p in out.iterdir() if not p.name.endswith(PARTIAL)):
            raise CollectionMismatchError(f"{out} is not empty and holds no {INDEX}: give an empty or new folder")
        return {"format": COLLECTION_FORMAT, **config.manifest(), "scenarios": []}
    try:
        index = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:
        raise CollectionMismatchError(f"{path} cannot be read ({error}): give another folder") from None
    if not isinstance(index, dict) or index.get("format") != COLLECTION_FORMAT:
        raise CollectionMismatchError(f"{path} is not a {COLLECTION_FORMAT} index: give another folder")
    differ = sorted(k for k, v in config.manifest().items() if index.get(k) != v)
    if differ:
        raise CollectionMismatchError(
            f"{out} holds a collection made with other options ({', '.join(differ)} differ): "
            "run the same command as before to resume it, or give another folder"
        )
    return index


def _export_seed(plan: Callable[..., Any], scenario: Any, seed: int, out: Path, time_limit: float) -> dict[str, Any]:
    """Plan ``scenario`` with every model exported into ``seed-<seed>``; the index entry of the seed."""
    final = out / f"seed-{seed}"
    partial = out / f"seed-{seed}{PARTIAL}"
    shutil.rmtree(partial, ignore_errors=True)
    shutil.rmtree(final, ignore_errors=True)  # a folder the index does not list is not trusted
    partial.mkdir()
    result = plan(scenario, time_limit=time_limit, export_models=partial)
    if result.status == "userinterrupt":
        raise KeyboardInterrupt
    scenario.save(partial / "scenario.json")
    result.save(partial / "plan.json")
    solves = [s for s in result.stats.get("solves", []) if "exported" in s]
    os.replace(partial, final)
    return {
        "seed": seed,
        "scenario": scenario.name,
        "objects": len(scenario.objects),
        "status": result.status,
        "phases": len(result.phases),
        "objective": result.objective,
        "total_s": result.stats.get("total_s"),
        "models": [
            {"mps": f"{final.name}/{s['exported']}", "phases": s["phases"], "status": s.get("status")} for s in solves
        ],
    }


def _write_json(path: Path, data: Any) -> None:
    """Write ``data`` to ``path`` through a file aside, so that a reader never sees half of it."""
    aside = path.with_name(path.name + ".tmp")
    aside.write_text(json.dumps(data, indent=1), encoding="utf-8")
    os.replace(aside, path)
