"""The oracle's invariant: no episode of any policy earns more than a proven reference on the same scenario.

A split's reference (:mod:`training.evaluation.references`) is the expert's proven optimum
of the task cost, the quantity the env's return is minus; an episode that earns more
(``return > reference return``) shows a plan the expert's model missed, or a reference that
is not optimal. :func:`beaten` lists such episodes among any records; ``fetchcarry
references --invariant RESULTS...`` prints them (exit 1 when there is one).

Records of release 0.2 (results schema 1 against ``fetchcarry-references/1``, the v1
splits) are checked against their own references as they were published: there the
reward (+10 per delivery, minus travel) and the expert's objective (the paper's Eq. 1 with
the fewest phases) differed, which is what this release's single task cost removes.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from training.evaluation.references import load_references
from training.evaluation.splits import SPLITS

RETURN_TOLERANCE = 1e-6  # relative: a return above the reference's by less than this is the same return


@dataclass(frozen=True)
class Beaten:
    """An episode that earned more than the proven reference on its scenario."""

    policy: str
    split: str
    seed: int
    episode_return: float
    reference_return: float
    phases: int
    reference_phases: int


def beaten(records: Iterable[dict[str, Any]]) -> tuple[list[Beaten], int]:
    """The records that earn more than a proven reference, and how many records had one to compare with.

    A record is compared when its split has a reference file with a proven record for its
    seed and scenario digest; other records (no reference, unproven, another scenario) are
    skipped and not counted.
    """
    out: list[Beaten] = []
    compared = 0
    for record in records:
        ref = _proven_reference(record)
        if ref is None:
            continue
        compared += 1
        if record["return"] > ref["return"] + RETURN_TOLERANCE * max(1.0, abs(ref["return"])):
            out.append(
                Beaten(
                    record["policy"],
                    record["split"],
                    record["seed"],
                    float(record["return"]),
                    float(ref["return"]),
                    int(record["phases"]),
                    int(ref["phases"]),
                )
            )
    return out, compared


def _proven_reference(record: dict[str, Any]) -> dict[str, Any] | None:
    """The proven reference of ``record``'s scenario, or None."""
    split = SPLITS.get(record.get("split", ""))
    if split is None or not split.part:
        return None
    content = load_references(split.version)
    records = content["parts"].get(split.part, []) if content else []
    by_seed = {r["seed"]: r for r in records}
    ref = by_seed.get(record.get("seed"))
    if ref is None or not ref["proven"]:
        return None
    if record.get("digest") is not None and record["digest"] != ref["digest"]:
        return None
    return ref
