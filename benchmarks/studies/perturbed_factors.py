"""Which of ``perturbed``'s three factors a policy loses on: paired differences in success between its splits.

    python -m benchmarks.studies.perturbed_factors RESULTS.json

``RESULTS.json`` is a ``fetchcarry benchmark`` run on ``perturbed-v2`` and its one-factor
splits (``perturbed-layout-v2``, ``perturbed-distractors-v2``, ``perturbed-physics-v2``,
the same part and episodes). Episode ``k`` of each is the same ``training`` scenario
with other factors, so each pair of splits is compared over the episodes whose base
scenario is the same (their names' numbers agree), with a paired bootstrap over them.
Prints, per policy, its success on each split and the differences.
"""

from __future__ import annotations

import sys
from collections import defaultdict
from itertools import combinations

from training.evaluation.results import read_results
from training.stats import paired_bootstrap

SPLITS = ("perturbed", "perturbed-layout", "perturbed-distractors", "perturbed-physics")


def _base(split: str) -> str:
    return split.split(":")[0].rsplit("-v", 1)[0]


def main(path: str) -> None:
    outcomes: dict[str, dict[str, dict[int, tuple[str, bool]]]] = defaultdict(lambda: defaultdict(dict))
    for record in read_results(path):
        base = _base(record["split"])
        if base in SPLITS:
            number = record["scenario"].rsplit("-", 1)[1]
            outcomes[record["policy"]][base][record["seed"]] = (number, bool(record["success"]))
    for policy, by_split in outcomes.items():
        rates = ", ".join(
            f"{split} {sum(s for _, s in by_split[split].values()) / len(by_split[split]):.0%}"
            for split in SPLITS
            if by_split.get(split)
        )
        print(f"{policy}: {rates}")
        for a, b in combinations([s for s in SPLITS if by_split.get(s)], 2):
            pairs = [
                (by_split[a][seed][1], by_split[b][seed][1])
                for seed in by_split[a]
                if seed in by_split[b] and by_split[a][seed][0] == by_split[b][seed][0]
            ]
            mean, low, high = paired_bootstrap([float(x) - float(y) for x, y in pairs])
            print(f"  {a} - {b}: {100 * mean:+.1f} pts [{100 * low:+.1f}, {100 * high:+.1f}] over {len(pairs)} pairs")


if __name__ == "__main__":
    main(sys.argv[1])
