"""Plan the unproven references of some split versions again with this checkout (a measurement; no file changes).

    python -m benchmarks.studies.unproven_references [--splits apartment-v2 objects-v2] [--limit S] > rows.jsonl

Every record of the splits' reference files (dev and test) that is not proven optimal is
planned again as ``fetchcarry references`` plans it (:func:`training.evaluation.references.reference_episode`,
``--limit`` seconds a call as the safety stop, default the files' 120 s), on two worker
processes, fewest objects first. One JSON line per record: the split, part, index and
source, whether it is proven now, its status and whether the clock stopped it, its cost
now and in the file, and the CPU and wall seconds.
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor

from training.evaluation.references import load_references, reference_episode
from training.evaluation.splits import get_split, split_scenarios


def _again(job: tuple[str, str, int, float]) -> dict:
    split, part, index, limit = job
    item = split_scenarios(get_split(f"{split}:{part}"))[index]
    cpu, wall = time.process_time(), time.perf_counter()
    record = reference_episode(item, limit)
    return {
        "split": split, "part": part, "index": index, "source": record["source"], "proven": record["proven"],
        "status": record["status"], "clock_stopped": record["clock_stopped"], "cost": record["cost"],
        "cpu_s": round(time.process_time() - cpu, 1), "wall_s": round(time.perf_counter() - wall, 1),
    }  # fmt: skip


def _objects(source: str) -> int:
    """How many objects a source draws (``objects-K``), 0 for any other."""
    return int(source.split("-")[1]) if source.startswith("objects-") else 0


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.studies.unproven_references",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--splits", nargs="+", default=["apartment-v2", "objects-v2"], help="split versions")
    parser.add_argument("--limit", type=float, default=120.0, help="seconds per planning call (safety stop)")
    args = parser.parse_args(argv)
    unproven = []
    for split in args.splits:
        content = load_references(split)
        if content is None:
            raise SystemExit(f"no reference file for {split}")
        for part, records in content["parts"].items():
            rows = [r for r in records if not r["proven"]]
            unproven += [(_objects(r["source"]), split, part, r["index"], r["cost"]) for r in rows]
    unproven.sort()
    before = {(split, part, index): cost for _, split, part, index, cost in unproven}
    with ProcessPoolExecutor(2) as pool:
        jobs = [(split, part, index, args.limit) for _, split, part, index, _ in unproven]
        for row in pool.map(_again, jobs):
            row["cost_in_file"] = before[row["split"], row["part"], row["index"]]
            print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
