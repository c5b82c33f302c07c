"""Do two Minari datasets hold the same episodes? Episode by episode: actions, observations, rewards.

    python -m benchmarks.studies.same_episodes DATASETS_A DATASETS_B DATASET_ID

``DATASETS_A`` and ``DATASETS_B`` are Minari folders (``MINARI_DATASETS_PATH``), each
holding ``DATASET_ID``: for example one written by ``fetchcarry generate`` in a checkout
before a change and one after. Prints each episode that differs (its id, its steps in
each, whether each ended delivered) and the counts; exits 1 when any episode differs.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np


def _episodes(folder: str, dataset_id: str) -> list:
    import minari

    os.environ["MINARI_DATASETS_PATH"] = folder
    return list(minari.load_dataset(dataset_id).iterate_episodes())


def _flat(observations) -> np.ndarray:
    return np.asarray(observations["observation"] if isinstance(observations, dict) else observations)


def _same(a, b) -> bool:
    return (
        np.array_equal(a.actions, b.actions)
        and np.array_equal(a.rewards, b.rewards)
        and np.array_equal(_flat(a.observations), _flat(b.observations))
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.studies.same_episodes",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("first", help="a Minari datasets folder")
    parser.add_argument("second", help="another")
    parser.add_argument("dataset_id", help="the dataset both hold")
    args = parser.parse_args(argv)
    first, second = _episodes(args.first, args.dataset_id), _episodes(args.second, args.dataset_id)
    differ = 0
    for a, b in zip(first, second, strict=False):
        if not _same(a, b):
            differ += 1
            print(
                f"episode {a.id}: {len(a.actions)} and {len(b.actions)} steps, "
                f"delivered {bool(a.terminations[-1])} and {bool(b.terminations[-1])}"
            )
    delivered = [sum(bool(e.terminations[-1]) for e in episodes) for episodes in (first, second)]
    print(
        f"{len(first)} and {len(second)} episodes, {differ} of the common ones differ; "
        f"ended delivered: {delivered[0]} and {delivered[1]}"
    )
    return 1 if differ or len(first) != len(second) else 0


if __name__ == "__main__":
    sys.exit(main())
