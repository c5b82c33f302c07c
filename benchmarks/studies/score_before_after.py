"""The score before and after 0.2.0 on one results file: random-phases as the zero, then doing nothing.

    python -m benchmarks.studies.score_before_after [RESULTS.json[.gz]]

Per split and policy (and a do-nothing row made from each scenario's do-nothing return:
no delivery, no travel, every object waiting all the env's phases), prints the success
rate, the score whose zero was ``random-phases``' mean return (``100 (R - R_zero) /
(R_reference - R_zero)``, before) and the score now
(:func:`training.evaluation.metrics.score`). Default file: the invariant v2 records,
whose returns are the task cost's.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from fetchcarry_env.registration import do_nothing_return
from training.evaluation.metrics import reference_of, reference_table, score
from training.evaluation.results import read_results

INVARIANT = Path(__file__).resolve().parents[2] / "docs" / "benchmarks" / "raw" / "invariant-v2" / "results.json.gz"
DO_NOTHING = "(do nothing)"


def old_score(group: list[dict], zero: list[dict], refs: list[dict]) -> float:
    """The score as it was: 100 (R - R_zero) / (R_reference - R_zero), means over the split's episodes."""
    r, r_zero, r_ref = (float(np.mean([x["return"] for x in xs])) for xs in (group, zero, refs))
    return 100.0 * (r - r_zero) / (r_ref - r_zero)


def table(records: list[dict]) -> list[str]:
    """One Markdown row per split and policy (the do-nothing row included)."""
    references = reference_table(records)
    lines = ["| split | policy | success | score before (zero: random-phases) | score now (zero: doing nothing) |",
             "| --- | --- | ---: | ---: | ---: |"]  # fmt: skip
    for split in dict.fromkeys(r["split"] for r in records):
        chosen = [r for r in records if r["split"] == split]
        zero = [r for r in chosen if r["policy"] == "random-phases"]
        idle = [{**r, "policy": DO_NOTHING, "success": False, "return": do_nothing_return(r["objects"])} for r in zero]
        for policy in [*dict.fromkeys(r["policy"] for r in chosen), DO_NOTHING]:
            group = idle if policy == DO_NOTHING else [r for r in chosen if r["policy"] == policy]
            refs = [reference_of(r, references) for r in group]
            before = old_score(group, zero, [x for x in refs if x is not None])
            now = score(zip(group, refs, strict=True))
            success = np.mean([r["success"] for r in group])
            lines.append(f"| {split} | {policy} | {success:.1%} | {before:.1f} | {now:.1f} |")
    return lines


if __name__ == "__main__":
    print("\n".join(table(read_results(sys.argv[1] if len(sys.argv) > 1 else INVARIANT))))
