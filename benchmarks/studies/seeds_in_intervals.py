"""How many per-seed success rates fall outside their method's pooled 95 % interval, per results file.

    python -m benchmarks.studies.seeds_in_intervals [RESULTS.json[.gz]]

Reads a results file (default: the published table's), pools each method's training
seeds per split as the summary does, and counts the (method, split, seed) success rates
that lie outside the method's interval (:func:`training.evaluation.metrics.summarise`).
An interval that holds the networks fixed leaves out what varies between training runs:
rates of seeds that disagree fall outside it.
"""

from __future__ import annotations

import sys
from pathlib import Path

from training.evaluation.compare import pooled
from training.evaluation.metrics import summarise
from training.evaluation.results import read_results

PUBLISHED = Path(__file__).resolve().parents[2] / "docs" / "benchmarks" / "published" / "results.json.gz"


def outside(records: list[dict]) -> tuple[int, int, list[str]]:
    """(rates outside their method's interval, per-seed rates counted, a line for each one outside)."""
    records = pooled(records)
    rows = {(row.policy, row.split): row for row in summarise(records)}
    by_seed: dict[tuple[str, str, int], list[bool]] = {}
    for r in records:
        if r["training_seed"] is not None:
            by_seed.setdefault((r["policy"], r["split"], r["training_seed"]), []).append(bool(r["success"]))
    lines = []
    for (policy, split, seed), outcomes in sorted(by_seed.items()):
        row, rate = rows[policy, split], sum(outcomes) / len(outcomes)
        if not row.success_low <= rate <= row.success_high:
            lines.append(f"{policy} seed {seed} on {split}: {rate:.1%} outside [{row.success_low:.1%}, "
                         f"{row.success_high:.1%}]")  # fmt: skip
    return len(lines), len(by_seed), lines


if __name__ == "__main__":
    count, total, lines = outside(read_results(sys.argv[1] if len(sys.argv) > 1 else PUBLISHED))
    print("\n".join(lines))
    print(f"{count} of {total} per-seed success rates outside their method's 95 % interval")
